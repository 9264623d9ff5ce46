// Device side on usb_f_hid: the console firmware (master_devices' Firmware)
// behind /dev/hidg0, with our report descriptor. usb_f_hid moves input and
// output reports through userspace but answers GET_REPORT itself (kernel
// 6.1), so the feature-report handshake cannot be served from here; the
// FunctionFS console (usb_stack_ffs_console) can. This program proves the
// kernel's side of our descriptor and reports on the plain HID gadget.
//
// Usage: usb_stack_hidg_console --device /dev/hidg0 --prefix P
//        usb_stack_hidg_console --write-descriptor FILE
// SIGTERM: report the stream statistics and exit.

#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>
#include <thread>

#include "firmware_host.hpp"
#include "guest_report.hpp"
#include "master_devices/firmware.hpp"
#include "master_devices/protocol.hpp"

namespace md = tsmh::master_devices;
namespace protocol = tsmh::master_devices::protocol;
using tsmh::usb_stack::FirmwareHost;
using tsmh::usb_stack::result;

int main(int argc, char** argv) {
  std::string device = "/dev/hidg0";
  std::string prefix = "hidg";
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    const std::string value = argv[i + 1];
    if (flag == "--device") {
      device = value;
    } else if (flag == "--prefix") {
      prefix = value;
    } else if (flag == "--write-descriptor") {
      const auto d = protocol::hid_report_descriptor();
      std::ofstream(value, std::ios::binary)
          .write(reinterpret_cast<const char*>(d.data()), static_cast<std::streamsize>(d.size()));
      return 0;
    } else {
      std::fprintf(stderr, "hidg_console: bad argument %s %s\n", flag.c_str(), value.c_str());
      return 2;
    }
  }
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGTERM);
  sigaddset(&signals, SIGINT);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);

  const int fd = ::open(device.c_str(), O_RDWR);
  if (fd < 0) {
    std::fprintf(stderr, "hidg_console: open %s: %s\n", device.c_str(), std::strerror(errno));
    return 1;
  }
  FirmwareHost fw(md::default_console_firmware());
  fw.start();
  std::thread input([&] {
    std::uint64_t counter = 0;
    std::array<std::uint8_t, protocol::kMaxReportSize> report{};
    for (;;) {
      const std::size_t n = fw.wait_input_report(report, counter, 100);
      // Blocks until the host has taken the previous report.
      if (n > 0 && ::write(fd, report.data(), n) < 0) usleep(1000);
    }
  });
  std::thread output([&] {
    std::array<std::uint8_t, 64> buf{};
    for (;;) {
      const ssize_t n = ::read(fd, buf.data(), buf.size());
      if (n > 0) {
        fw.on_output_report(std::span(buf.data(), static_cast<std::size_t>(n)));
      } else {
        usleep(1000);
      }
    }
  });
  int sig = 0;
  sigwait(&signals, &sig);
  const auto s = fw.stats();
  char d[300];
  std::snprintf(
      d, sizeof d,
      "outputs accepted %llu rejected %llu, sequence repeats/reorders %llu, skipped %llu; "
      "inputs %llu; watchdog trips %llu",
      static_cast<unsigned long long>(s.firmware.output_accepted),
      static_cast<unsigned long long>(s.firmware.output_rejected),
      static_cast<unsigned long long>(s.output_sequence_reorders),
      static_cast<unsigned long long>(s.output_sequence_gaps),
      static_cast<unsigned long long>(s.firmware.input_reports),
      static_cast<unsigned long long>(s.firmware.watchdog_trips));
  result(prefix + "_fw_stream",
         s.firmware.output_accepted > 0 && s.firmware.output_rejected == 0 &&
             s.output_sequence_reorders == 0,
         d);
  std::fflush(stdout);
  _exit(0);  // the I/O threads may sit in blocking reads and writes
}
