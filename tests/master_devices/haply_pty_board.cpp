// The Haply board's emulator on a pty, as a program: prints the pty's path on
// its first line (the `port:` to give the haply driver), then answers until
// SIGTERM/SIGINT or --seconds. A hand holds the handle near the motors until
// 1.5 s after the first state command (haptic-server indexes the slave to
// where the master is when it starts), then pushes it slowly along +y and
// back (the 2DIY's third-generation geometry, symmetric poses): motor 2
// sweeps 40-80 deg at 0.25 Hz, motor 1 mirrors it. At the end it prints
//   HAPLY_BOARD states N largest_torque_nm T final_torque_nm A B
//     free_nm F pressing_nm P
// F: the mean of the larger motor torque while the slave joint is clear of
// the tissue (motor 2 below 45 deg: 0.1 rad short of it), P: while pressing
// into it (above 70 deg).
// Used by haply_server.sh (haptic-server against virtual-slave through it).

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <stdlib.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numbers>
#include <string>
#include <vector>

#include "master_devices/haply_board.hpp"

int main(int argc, char** argv) {
  double seconds = 30.0;
  for (int i = 1; i + 1 < argc; ++i)
    if (std::string(argv[i]) == "--seconds") seconds = std::atof(argv[i + 1]);
  const int master = ::posix_openpt(O_RDWR | O_NOCTTY | O_CLOEXEC);
  if (master < 0 || ::grantpt(master) != 0 || ::unlockpt(master) != 0) {
    std::perror("posix_openpt");
    return 1;
  }
  const std::string path = ::ptsname(master);
  const int keep = ::open(path.c_str(), O_RDWR | O_NOCTTY | O_CLOEXEC);  // no hang-up before use
  std::printf("%s\n", path.c_str());
  std::fflush(stdout);
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGTERM);
  sigaddset(&set, SIGINT);
  sigprocmask(SIG_BLOCK, &set, nullptr);

  tsmh::master_devices::haply::BoardEmulator board;
  std::vector<std::uint8_t> in(4096), out;
  const auto start = std::chrono::steady_clock::now();
  auto since = [](std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  };
  std::chrono::steady_clock::time_point first_state{};
  double free_sum = 0.0, pressing_sum = 0.0;
  long free_n = 0, pressing_n = 0;
  for (;;) {
    timespec zero{0, 0};
    if (sigtimedwait(&set, nullptr, &zero) > 0) break;
    if (since(start) > seconds) break;
    if (board.states() > 0 && first_state == std::chrono::steady_clock::time_point{})
      first_state = std::chrono::steady_clock::now();
    const double t = board.states() > 0 ? std::max(0.0, since(first_state) - 1.5) : 0.0;
    // 40-80 deg: the slave joint goes from 0.03 to 0.45 rad, the tissue's
    // surface 0.2 rad above the start.
    const double a =
        (60.0 - 20.0 * std::cos(2.0 * std::numbers::pi * 0.25 * t)) * std::numbers::pi / 180.0;
    board.set_port_angles({a, std::numbers::pi - a, 0.0, 0.0});
    pollfd p{master, POLLIN, 0};
    if (::poll(&p, 1, 5) <= 0 || !(p.revents & POLLIN)) continue;
    const ssize_t n = ::read(master, in.data(), in.size());
    if (n <= 0) continue;
    out.clear();
    board.receive(in.data(), static_cast<std::size_t>(n), out);
    if (!out.empty() && ::write(master, out.data(), out.size()) < 0) break;
    const double tau =
        std::max(std::abs(board.port_torques()[0]), std::abs(board.port_torques()[1]));
    if (t > 0.0 && a < 45.0 * std::numbers::pi / 180.0) {
      free_sum += tau;
      ++free_n;
    }
    if (t > 0.0 && a > 70.0 * std::numbers::pi / 180.0) {
      pressing_sum += tau;
      ++pressing_n;
    }
  }
  std::printf(
      "HAPLY_BOARD states %llu largest_torque_nm %.6f final_torque_nm %.6f %.6f free_nm %.6f "
      "pressing_nm %.6f\n",
      static_cast<unsigned long long>(board.states()), board.largest_requested_nm(),
      board.port_torques()[0], board.port_torques()[1], free_n ? free_sum / free_n : 0.0,
      pressing_n ? pressing_sum / pressing_n : 0.0);
  ::close(keep);
  ::close(master);
  return 0;
}
