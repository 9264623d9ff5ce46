#pragma once
// The Haply board's emulator (haply_board.hpp) behind a real pty: the driver
// opens the pty's terminal side as it would /dev/ttyACM0 (termios, raw mode,
// poll) and this helper's thread answers on the other side. unplug() closes
// that side: the terminal side then reads a hang-up, as a ttyACM does when
// the board is pulled.

#include <fcntl.h>
#include <poll.h>
#include <stdlib.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <functional>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "master_devices/haply_board.hpp"

namespace tsmh::master_devices::testing {

class PtyBoard {
 public:
  PtyBoard() {
    master_ = ::posix_openpt(O_RDWR | O_NOCTTY | O_CLOEXEC);
    if (master_ < 0 || ::grantpt(master_) != 0 || ::unlockpt(master_) != 0)
      throw std::runtime_error("posix_openpt failed");
    path_ = ::ptsname(master_);
    // Held open so the master side never reads a hang-up before the driver
    // opens the port.
    keep_ = ::open(path_.c_str(), O_RDWR | O_NOCTTY | O_CLOEXEC);
    thread_ = std::thread([this] { run(); });
  }
  ~PtyBoard() {
    unplug();
    if (keep_ >= 0) ::close(keep_);
  }
  PtyBoard(const PtyBoard&) = delete;
  PtyBoard& operator=(const PtyBoard&) = delete;

  const std::string& path() const { return path_; }

  /// Runs `f` on the emulator with the pump stopped for its duration.
  template <class F>
  auto with(F&& f) {
    std::lock_guard<std::mutex> lock(mutex_);
    return f(board_);
  }

  /// The cable pulled: the board side goes away.
  void unplug() {
    if (!running_.exchange(false)) return;
    thread_.join();
    ::close(master_);
    master_ = -1;
  }

 private:
  void run() {
    std::vector<std::uint8_t> in(4096), out;
    while (running_.load()) {
      pollfd p{master_, POLLIN, 0};
      if (::poll(&p, 1, 5) <= 0 || !(p.revents & POLLIN)) continue;
      const ssize_t n = ::read(master_, in.data(), in.size());
      if (n <= 0) continue;
      out.clear();
      {
        std::lock_guard<std::mutex> lock(mutex_);
        board_.receive(in.data(), static_cast<std::size_t>(n), out);
      }
      if (!out.empty() && ::write(master_, out.data(), out.size()) < 0) continue;
    }
  }

  int master_ = -1, keep_ = -1;
  std::string path_;
  std::mutex mutex_;
  haply::BoardEmulator board_;
  std::atomic<bool> running_{true};
  std::thread thread_;
};

/// Waits (real time: the driver's I/O thread and the pty must run) until
/// `done` holds or `limit` passes; returns whether it held.
inline bool wait_until(const std::function<bool()>& done,
                       std::chrono::milliseconds limit = std::chrono::milliseconds(3000)) {
  const auto end = std::chrono::steady_clock::now() + limit;
  while (std::chrono::steady_clock::now() < end) {
    if (done()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return done();
}

}  // namespace tsmh::master_devices::testing
