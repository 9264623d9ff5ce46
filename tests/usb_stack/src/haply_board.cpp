// Gadget side of the `haply_acm` case: the Haply board's emulator
// (haply_board.hpp) behind the kernel's CDC-ACM gadget function (usb_f_acm,
// /dev/ttyGS0), so the host side's `haply` driver talks to a real
// /dev/ttyACM0 through cdc_acm, dummy_hcd and the gadget stack. A hand holds
// the handle still in the middle of the workspace.
//
// Control and state through files next to CONTROL (the guest's tmpfs):
//   CONTROL.silent  exists: keep reading commands, stop answering
//   CONTROL.state   rewritten every 2 ms: "states N port_torques T1 T2 T3 T4 largest L"
// Exits when the tty hangs up (the gadget unbound) or on SIGTERM.
//
// usb_stack_haply_board --tty /dev/ttyGS0 --control /tmp/haply

#include "master_devices/haply_board.hpp"

#include <signal.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <numbers>
#include <string>
#include <vector>

#include "master_devices/serial_port.hpp"

namespace md = tsmh::master_devices;

int main(int argc, char** argv) {
  std::string tty = "/dev/ttyGS0", control = "/tmp/haply";
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--tty")) tty = argv[i + 1];
    if (!std::strcmp(argv[i], "--control")) control = argv[i + 1];
  }
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGTERM);
  sigaddset(&set, SIGINT);
  sigprocmask(SIG_BLOCK, &set, nullptr);
  md::SerialPort port;
  try {
    port = md::SerialPort(tty);
  } catch (const std::exception& e) {
    std::printf("USB_STACK_NOTE haply_board: %s\n", e.what());
    return 1;
  }
  md::haply::BoardEmulator board;
  // 813 encoder counts from the gen3 offsets: the middle of the workspace.
  const double mid = 813.0 * 360.0 / 4880.0 * std::numbers::pi / 180.0;
  board.set_port_angles({mid, std::numbers::pi - mid, 0.0, 0.0});
  std::vector<std::uint8_t> in(512), out;
  const std::string silent_file = control + ".silent", state_file = control + ".state";
  auto last_state = std::chrono::steady_clock::now();
  for (;;) {
    timespec zero{0, 0};
    if (sigtimedwait(&set, nullptr, &zero) > 0) break;
    std::size_t got = 0;
    const auto io = port.read_some(in.data(), in.size(), got, 1);
    if (io == md::SerialPort::Io::kGone) {
      std::printf("USB_STACK_NOTE haply_board: %s hung up\n", tty.c_str());
      break;
    }
    board.set_silent(::access(silent_file.c_str(), F_OK) == 0);
    out.clear();
    if (got > 0) board.receive(in.data(), got, out);
    if (!out.empty() && port.write_all(out.data(), out.size(), 20) == md::SerialPort::Io::kGone)
      break;
    const auto now = std::chrono::steady_clock::now();
    if (now - last_state >= std::chrono::milliseconds(2)) {
      last_state = now;
      const std::string tmp = state_file + ".tmp";
      if (std::FILE* f = std::fopen(tmp.c_str(), "w")) {
        const auto& t = board.port_torques();
        std::fprintf(f, "states %llu port_torques %.6f %.6f %.6f %.6f largest %.6f\n",
                     static_cast<unsigned long long>(board.states()), t[0], t[1], t[2], t[3],
                     board.largest_requested_nm());
        std::fclose(f);
        std::rename(tmp.c_str(), state_file.c_str());
      }
    }
  }
  return 0;
}
