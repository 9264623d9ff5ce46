#pragma once
// A serial port (a USB CDC-ACM board's /dev/ttyACM*, or a pty in tests) in
// raw mode for a binary protocol: RAII on the descriptor, non-blocking, and
// reads that wait at most a given time, so a thread using it always sees its
// stop flag within that time. Errors name the port and the cause.

#include <cstddef>
#include <cstdint>
#include <string>

namespace tsmh::master_devices {

class SerialPort {
 public:
  enum class Io : std::uint8_t {
    kOk,       ///< bytes moved (possibly fewer than asked)
    kTimeout,  ///< nothing within the time
    kGone,     ///< the device went away (unplugged: EIO, ENODEV, hang-up)
    kError,    ///< another error (errno in error())
  };

  SerialPort() = default;
  /// Opens `path` (O_NONBLOCK, O_NOCTTY, close-on-exec), takes it exclusively
  /// (TIOCEXCL: another process's open fails with EBUSY), sets raw 8N1 with
  /// no flow control and no echo, and discards whatever was queued. Throws
  /// std::runtime_error naming the path and the cause (no permission: the
  /// dialout group; busy: another program has it).
  explicit SerialPort(const std::string& path);
  ~SerialPort() { close(); }
  SerialPort(SerialPort&& other) noexcept;
  SerialPort& operator=(SerialPort&& other) noexcept;
  SerialPort(const SerialPort&) = delete;
  SerialPort& operator=(const SerialPort&) = delete;

  bool is_open() const { return fd_ >= 0; }
  /// The descriptor (-1 when closed): for a crash handler's copy of the port.
  int fd() const { return fd_; }
  const std::string& path() const { return path_; }
  void close() noexcept;

  /// Writes all of `n` bytes or fails (a full output queue for more than
  /// `timeout_ms` is kTimeout).
  Io write_all(const std::uint8_t* data, std::size_t n, int timeout_ms) noexcept;
  /// Reads up to `n` bytes, waiting at most `timeout_ms` for the first.
  Io read_some(std::uint8_t* data, std::size_t n, std::size_t& got, int timeout_ms) noexcept;
  /// Drops every byte queued for reading (a late reply to an earlier request).
  void discard_input() noexcept;
  /// errno of the last kGone / kError.
  int error() const { return errno_; }

 private:
  int fd_ = -1;
  int errno_ = 0;
  std::string path_;
};

}  // namespace tsmh::master_devices
