#pragma once
// Best effort when the process dies of a signal that dumps core (SIGABRT,
// SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGTRAP, SIGSYS: a real fault, abort(),
// or `kill -SEGV` from outside). Those cannot be blocked and taken by
// sigtimedwait() like the stop signals (bridge/stop_signals.hpp): when the
// fault is real the thread cannot go on. A handler runs instead and, with
// async-signal-safe calls only:
//
//   1. silences the process's other senders: dup2() of /dev/null over the
//      UDP send sockets (LCM's) and over other descriptors of the device
//      nodes it writes, so nothing the still-running threads send afterwards
//      (a MASTER_FORCE with torque, a MASTER_COMMAND that enables) can
//      overtake the messages below; then waits 1 ms (select()) for a send
//      that was already inside the kernel;
//   2. sends each prepared output as it is: a complete datagram with
//      sendto() on its own socket, or a report with write() on its own
//      descriptor;
//   3. returns with the default action restored (SA_RESETHAND) and the
//      signal raised again (raise()), so the process ends exactly as the
//      kernel would have ended it: same signal, same exit status, a core
//      dump where the limits allow one.
//
// Nothing is encoded, signed, allocated or locked in the handler: the
// outputs are prepared beforehand, and kept fresh, by the program's main
// thread with set(). Each output has two buffers; set() fills the one the
// handler is not reading and then publishes it with one atomic store, and
// refuses to write once the handler has started. What it cannot do: run at
// all after SIGKILL, a power loss or a kernel panic (then the device's and
// the slave's own watchdogs act); send messages that went stale because the
// main thread stopped refreshing them (a keyed receiver drops a trailer
// older than its freshness window); win against a second thread that faults
// while the first handler runs (the default action, already restored, ends
// the process at once).
//
// The one piece of process-wide state: a signal handler receives no context
// argument, so the installed CrashStop is reachable through a single static
// atomic pointer (crash_stop.cpp). One CrashStop may be installed at a time.

#include <signal.h>

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <string>

#include "bridge/udpm_frame.hpp"

namespace tsmh::bridge {

class CrashStop {
 public:
  /// The signals handled: those whose default action dumps core.
  static constexpr std::array<int, 7> kSignals = {SIGABRT, SIGSEGV, SIGBUS, SIGFPE,
                                                  SIGILL,  SIGTRAP, SIGSYS};
  static constexpr std::size_t kMaxBytes = 1472;  ///< one datagram within an Ethernet MTU
  static constexpr std::size_t kMaxOutputs = 4;
  static constexpr std::size_t kMaxMuted = 16;

  /// Opens /dev/null (what other senders are muted onto). Throws std::runtime_error.
  CrashStop();
  /// Uninstalls the handler and closes its descriptors.
  ~CrashStop();
  CrashStop(const CrashStop&) = delete;
  CrashStop& operator=(const CrashStop&) = delete;

  /// An output sent with sendto() on a socket of its own to `endpoint`
  /// (multicast TTL and loopback as LCM sets them). Setup only; returns its
  /// index; throws std::runtime_error when the socket cannot be made or all
  /// kMaxOutputs are taken.
  std::size_t add_datagram(const UdpmEndpoint& endpoint);
  /// An output written with write() to a descriptor of its own, open on
  /// `node` (a hidraw node) when given, else on /dev/null until
  /// reopen_node(). Setup only; throws std::runtime_error.
  std::size_t add_node(const std::string& node = {});
  /// Points node output `output` at `node` (a device that came back under
  /// another name): the new file takes the output's descriptor number with
  /// one dup2(), so the handler never writes a closed or reused number.
  /// Main thread. False (and unchanged) when `node` cannot be opened.
  bool reopen_node(std::size_t output, const std::string& node) noexcept;
  /// Points node output `output` at the file open on `fd` (one dup2(); -1:
  /// back to /dev/null), for a device whose node cannot be opened twice (an
  /// exclusive serial port). Main thread. False (and unchanged) on error.
  bool adopt_descriptor(std::size_t output, int fd) noexcept;

  /// Replaces what output `output` sends. Main thread only (one writer); no
  /// allocation. False when too long, or once the handler has started.
  bool set(std::size_t output, const std::uint8_t* bytes, std::size_t size) noexcept;
  /// Nothing is sent on `output` until the next set().
  void clear(std::size_t output) noexcept;

  /// Finds the descriptors the handler silences first: every IPv4 datagram
  /// socket of this process that is not one of its own outputs and not bound
  /// to one of `keep_ports` (LCM's receive sockets; its send sockets are
  /// unbound or on an ephemeral port), and every other descriptor open on
  /// one of `nodes`. Replaces the previous list; main thread. Returns how
  /// many were found (at most kMaxMuted are kept).
  std::size_t find_senders(std::initializer_list<int> keep_ports,
                           std::initializer_list<std::string> nodes = {});

  /// Installs the handler for kSignals. Throws std::logic_error when another
  /// CrashStop is installed.
  void install();
  /// Restores the default action of kSignals (when this one is installed).
  void uninstall() noexcept;

  /// How many outputs hold bytes to send now (for logs and tests).
  std::size_t armed_outputs() const noexcept;

 private:
  struct Output {
    int fd = -1;
    bool datagram = false;
    sockaddr_in to{};
    std::array<std::array<std::uint8_t, kMaxBytes>, 2> bytes{};
    std::array<std::size_t, 2> size{};
    std::atomic<int> current{-1};  ///< buffer the handler sends; -1: nothing
  };

  static void on_signal(int sig) noexcept;
  void fire() noexcept;

  int null_fd_ = -1;
  std::array<Output, kMaxOutputs> outputs_{};
  std::size_t used_ = 0;
  std::array<std::atomic<int>, kMaxMuted> muted_{};
  std::atomic<bool> crashing_{false};
  bool installed_ = false;
};

}  // namespace tsmh::bridge
