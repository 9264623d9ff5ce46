#pragma once
// The signals that end a program by default and can be caught, as one set,
// so every long-running program (haptic-server, virtual-slave, the adapter)
// takes the same orderly path -- zero torque, slave told to hold -- whatever
// the signal: SIGINT, SIGTERM, SIGHUP (terminal closed), SIGQUIT, SIGUSR1/2,
// SIGALRM, SIGVTALRM, SIGPROF, SIGXCPU, SIGXFSZ, SIGIO, SIGPWR, SIGSTKFLT and
// the real-time signals. Left out: the synchronous fault signals (SIGSEGV,
// SIGBUS, SIGFPE, SIGILL, SIGTRAP, SIGSYS, SIGABRT), whose blocking is
// undefined when the fault is real, and SIGKILL/SIGSTOP, which cannot be
// caught. SIGPIPE is ignored instead: a closed pipe is a write error that
// the writer reports, not a reason to die with torque on.

#include <signal.h>

namespace tsmh::bridge {

/// The set described above.
sigset_t terminating_signals() noexcept;

/// Ignores SIGPIPE, blocks terminating_signals() in the calling thread (and so
/// in every thread it starts afterwards) and returns the set, for sigwait(),
/// sigtimedwait() or sigpending() in the thread that handles stopping. Call it
/// before any other thread exists.
sigset_t block_terminating_signals() noexcept;

/// "SIGHUP", "SIGRTMIN+3", ...; never null.
const char* signal_name(int sig) noexcept;

/// Whether a signal of `set` is pending for this thread or the process.
bool terminating_signal_pending(const sigset_t& set) noexcept;

}  // namespace tsmh::bridge
