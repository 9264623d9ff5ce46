#include "master_devices/serial_port.hpp"

#include <fcntl.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <utility>

namespace tsmh::master_devices {

namespace {

bool is_gone(int e) {
  return e == EIO || e == ENODEV || e == ENXIO || e == EPIPE;
}

}  // namespace

SerialPort::SerialPort(const std::string& path) : path_(path) {
  fd_ = ::open(path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd_ < 0) {
    const int e = errno;
    std::string hint;
    if (e == EACCES || e == EPERM)
      hint = " (no permission: add yourself to the 'dialout' group, then log in again)";
    else if (e == ENOENT)
      hint = " (no such port: plugged in? `tsm-devices list` shows the serial boards)";
    else if (e == EBUSY)
      hint = " (another program has the port open)";
    throw std::runtime_error(path + ": cannot open: " + std::strerror(e) + hint);
  }
  auto fail = [&](const char* what) {
    const int e = errno;
    ::close(fd_);
    fd_ = -1;
    throw std::runtime_error(path + ": " + what + ": " + std::strerror(e) +
                             (e == ENOTTY ? " (not a serial port)" : ""));
  };
  // Exclusive: a second driver or a terminal program on the same board would
  // interleave its bytes with ours.
  if (::ioctl(fd_, TIOCEXCL) != 0) fail("TIOCEXCL");
  termios t{};
  if (::tcgetattr(fd_, &t) != 0) fail("tcgetattr");
  ::cfmakeraw(&t);
  t.c_cflag |= CLOCAL | CREAD;
  t.c_cflag &= ~static_cast<tcflag_t>(CRTSCTS | CSTOPB | PARENB);
  t.c_cc[VMIN] = 0;
  t.c_cc[VTIME] = 0;
  // CDC-ACM ignores the line rate; a real UART bridge would not, so name one.
  ::cfsetispeed(&t, B115200);
  ::cfsetospeed(&t, B115200);
  if (::tcsetattr(fd_, TCSANOW, &t) != 0) fail("tcsetattr (raw mode)");
  ::tcflush(fd_, TCIOFLUSH);
}

SerialPort::SerialPort(SerialPort&& other) noexcept
    : fd_(std::exchange(other.fd_, -1)), errno_(other.errno_), path_(std::move(other.path_)) {}

SerialPort& SerialPort::operator=(SerialPort&& other) noexcept {
  if (this != &other) {
    close();
    fd_ = std::exchange(other.fd_, -1);
    errno_ = other.errno_;
    path_ = std::move(other.path_);
  }
  return *this;
}

void SerialPort::close() noexcept {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

SerialPort::Io SerialPort::write_all(const std::uint8_t* data, std::size_t n,
                                     int timeout_ms) noexcept {
  std::size_t done = 0;
  while (done < n) {
    const ssize_t w = ::write(fd_, data + done, n - done);
    if (w > 0) {
      done += static_cast<std::size_t>(w);
      continue;
    }
    if (w < 0 && errno == EINTR) continue;
    if (w < 0 && errno != EAGAIN) {
      errno_ = errno;
      return is_gone(errno_) ? Io::kGone : Io::kError;
    }
    pollfd p{fd_, POLLOUT, 0};
    const int r = ::poll(&p, 1, timeout_ms);
    if (r == 0) return Io::kTimeout;
    if (r < 0 && errno != EINTR) {
      errno_ = errno;
      return Io::kError;
    }
    if (r > 0 && (p.revents & (POLLHUP | POLLERR | POLLNVAL))) {
      errno_ = EIO;
      return Io::kGone;
    }
  }
  return Io::kOk;
}

SerialPort::Io SerialPort::read_some(std::uint8_t* data, std::size_t n, std::size_t& got,
                                     int timeout_ms) noexcept {
  got = 0;
  pollfd p{fd_, POLLIN, 0};
  int r = ::poll(&p, 1, timeout_ms);
  if (r < 0) {
    if (errno == EINTR) return Io::kTimeout;
    errno_ = errno;
    return Io::kError;
  }
  if (r == 0) return Io::kTimeout;
  const ssize_t k = ::read(fd_, data, n);
  if (k > 0) {
    got = static_cast<std::size_t>(k);
    return Io::kOk;
  }
  if (k < 0 && (errno == EAGAIN || errno == EINTR)) return Io::kTimeout;
  // read() 0 on a tty that polled readable, or a hang-up: the device is gone.
  errno_ = k == 0 ? EIO : errno;
  if (k == 0 || is_gone(errno_) || (p.revents & (POLLHUP | POLLERR))) return Io::kGone;
  return Io::kError;
}

void SerialPort::discard_input() noexcept {
  if (fd_ >= 0) ::tcflush(fd_, TCIFLUSH);
}

}  // namespace tsmh::master_devices
