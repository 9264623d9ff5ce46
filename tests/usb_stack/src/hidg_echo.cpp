// Device side of the raw HID case: answers every output report read from
// /dev/hidg0 (report ID 2) with an input report (ID 1) whose payload is the
// echo of the output's payload. Runs until --seconds elapse or it is killed.

#include <fcntl.h>
#include <poll.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "raw_descriptor.hpp"

namespace raw = tsmh::usb_stack::raw;

int main(int argc, char** argv) {
  std::string device = "/dev/hidg0";
  double seconds = 30.0;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    if (flag == "--device") {
      device = argv[i + 1];
    } else if (flag == "--seconds") {
      seconds = std::atof(argv[i + 1]);
    } else {
      std::fprintf(stderr, "hidg_echo: unknown flag %s\n", flag.c_str());
      return 2;
    }
  }
  const int fd = ::open(device.c_str(), O_RDWR);
  if (fd < 0) {
    std::fprintf(stderr, "hidg_echo: open %s: %s\n", device.c_str(), std::strerror(errno));
    return 1;
  }
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  long echoed = 0;
  long ignored = 0;
  while (std::chrono::steady_clock::now() < end) {
    pollfd p{fd, POLLIN, 0};
    if (::poll(&p, 1, 100) <= 0) continue;
    std::array<std::uint8_t, 64> in{};
    const ssize_t n = ::read(fd, in.data(), in.size());
    if (n < 0) {
      if (errno == EINTR || errno == EAGAIN) continue;
      std::fprintf(stderr, "hidg_echo: read %s: %s\n", device.c_str(), std::strerror(errno));
      break;
    }
    // Numbered reports arrive from the host with their ID byte first.
    if (static_cast<std::size_t>(n) != raw::kReportLength || in[0] != raw::kOutputId) {
      ++ignored;
      continue;
    }
    std::array<std::uint8_t, raw::kReportLength> out{};
    out[0] = raw::kInputId;
    for (std::size_t i = 1; i < out.size(); ++i)
      out[i] = raw::echo(in[i]);
    if (::write(fd, out.data(), out.size()) != static_cast<ssize_t>(out.size())) {
      std::fprintf(stderr, "hidg_echo: write %s: %s\n", device.c_str(), std::strerror(errno));
      break;
    }
    ++echoed;
  }
  std::fprintf(stderr, "hidg_echo: echoed %ld reports, ignored %ld\n", echoed, ignored);
  ::close(fd);
  return 0;
}
