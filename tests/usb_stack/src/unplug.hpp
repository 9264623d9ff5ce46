#pragma once
// Pulling the virtual cable, for the driver cases: writing a gadget's UDC
// file (bind/unbind) off the loop thread, and watching the device node the
// driver uses for the kernel's hang-up.

#include <fcntl.h>
#include <poll.h>
#include <unistd.h>

#include <atomic>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <string>
#include <thread>

#include "realtime/clock.hpp"

namespace tsmh::usb_stack {

/// sysfs directory that exists exactly while the kernel has the device.
inline std::string sysfs_of(const std::string& path) {
  if (path.rfind("/dev/", 0) == 0) return "/sys/class/hidraw/" + path.substr(5);
  if (path.rfind("usb:", 0) == 0) return "/sys/bus/usb/devices/" + path.substr(4);
  return "";
}

/// Our own file descriptor on the device node the driver uses (the hidraw
/// node, or the usbfs node of "usb:B-P"): the kernel marks it POLLHUP/POLLERR
/// the moment it tears the device down, the same wake-up the driver gets.
/// That moment is what the driver's reaction is measured from.
class UnplugWatch {
 public:
  explicit UnplugWatch(const std::string& path) {
    std::string node = path;
    if (path.rfind("usb:", 0) == 0) {
      const std::string dir = "/sys/bus/usb/devices/" + path.substr(4);
      int bus = 0, dev = 0;
      std::ifstream(dir + "/busnum") >> bus;
      std::ifstream(dir + "/devnum") >> dev;
      char b[64];
      std::snprintf(b, sizeof b, "/dev/bus/usb/%03d/%03d", bus, dev);
      node = b;
    }
    fd_ = ::open(node.c_str(), O_RDONLY | O_NONBLOCK);
  }
  ~UnplugWatch() {
    if (fd_ >= 0) ::close(fd_);
  }
  UnplugWatch(const UnplugWatch&) = delete;
  UnplugWatch& operator=(const UnplugWatch&) = delete;
  bool valid() const { return fd_ >= 0; }
  bool hung_up() const {
    pollfd p{fd_, 0, 0};
    return ::poll(&p, 1, 0) > 0 && (p.revents & (POLLHUP | POLLERR | POLLNVAL)) != 0;
  }

 private:
  int fd_ = -1;
};

inline bool exists(const std::string& p) {
  return !p.empty() && ::access(p.c_str(), F_OK) == 0;
}

/// Writes the UDC file on a helper thread (bind/unbind block for a while)
/// and records when the write returned.
class UdcWriter {
 public:
  UdcWriter(std::string file, std::string value)
      : thread_([this, file = std::move(file), value = std::move(value)] {
          std::ofstream f(file);
          f << value << '\n';
          f.flush();
          ok_ = static_cast<bool>(f);
          done_ns_ = realtime::monotonic_now_ns();
        }) {}
  ~UdcWriter() { thread_.join(); }
  std::int64_t done_ns() const { return done_ns_; }
  bool ok() const { return ok_; }

 private:
  std::atomic<std::int64_t> done_ns_{0};
  std::atomic<bool> ok_{false};
  std::thread thread_;
};

}  // namespace tsmh::usb_stack
