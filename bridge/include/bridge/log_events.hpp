#pragma once
// The events of an LCM log file (lcm-logger), read and validated by us
// instead of liblcm's reader, which trusts each event's length fields: a
// data length of 0x7fffffff makes it read far past its buffer (SIGSEGV).
// The format, as LCM documents it (lcm-proj.github.io, "LCM Log
// File format"), big-endian:
//
//   uint32 sync word 0xEDA1DA01 | int64 event number | int64 timestamp (us)
//   int32 channel length | int32 data length | channel bytes | data bytes
//
// Every header is checked before its lengths are used: sync word, channel
// length 1..kMaxLogChannelLength, data length 0..kMaxDataLength and both inside
// the file. A bad header in the middle of the file starts a corrupt region:
// the reader scans for the next valid header (as liblcm does) and counts the
// bytes and, from the event numbers, the events lost. A header or body cut
// off by the end of the file is a truncation. Reading never throws and
// allocates only to describe damage; the caller decides what it accepts.

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>

namespace tsmh::bridge {

inline constexpr std::uint32_t kLogSyncWord = 0xEDA1DA01;
inline constexpr std::size_t kLogHeaderSize = 28;
inline constexpr std::int32_t kMaxLogChannelLength = 1024;
inline constexpr std::int32_t kMaxDataLength = 256 * 1024 * 1024;

struct LogEvent {
  std::int64_t eventnum = 0;
  std::int64_t timestamp = 0;  ///< us, as the logger stamped it
  std::string_view channel;
  std::span<const std::uint8_t> data;
  std::size_t offset = 0;  ///< byte offset of the event's sync word
};

/// What the reader found wrong, for the user.
struct LogDamage {
  std::size_t corrupt_regions = 0;  ///< stretches of bytes that were not valid events
  std::size_t corrupt_bytes = 0;
  std::size_t first_corrupt_offset = 0;
  std::string first_corrupt_reason;  ///< e.g. "data length 2147483647 exceeds the 120 bytes left"
  std::int64_t events_lost = 0;      ///< event numbers skipped over corrupt regions and truncation
  bool truncated = false;            ///< the file ends inside an event
  std::size_t truncated_offset = 0;  ///< where that event starts
  std::string truncated_reason;      ///< e.g. "event 4711 needs 380 bytes, 120 are left"

  bool any() const noexcept { return truncated || corrupt_regions > 0; }
  /// One line: "", or e.g. "the file ends inside event 4711 at byte 123456
  /// (...); 1 event lost" / "2 corrupt regions (340 bytes, first at byte ...)".
  std::string describe() const;
};

/// Reads events from the bytes of a whole log (e.g. a mapped file).
class LogEventReader {
 public:
  explicit LogEventReader(std::span<const std::uint8_t> bytes) noexcept : bytes_(bytes) {}

  /// The next intact event; false at the end of the file (clean or not: see
  /// damage()).
  bool next(LogEvent& out) noexcept;
  const LogDamage& damage() const noexcept { return damage_; }

 private:
  enum class Header { kOk, kTruncated, kCorrupt };
  // Checks the header at `at`; fills `out` when kOk, `why` otherwise.
  Header check(std::size_t at, LogEvent& out, std::string* why) const noexcept;

  std::span<const std::uint8_t> bytes_;
  std::size_t pos_ = 0;
  bool have_last_ = false;
  std::int64_t last_eventnum_ = 0;
  LogDamage damage_;
};

/// A whole file mapped read-only (mmap); empty for an empty file. Throws
/// std::runtime_error naming the path when it cannot be opened or mapped.
class MappedFile {
 public:
  explicit MappedFile(const std::string& path);
  ~MappedFile();
  MappedFile(const MappedFile&) = delete;
  MappedFile& operator=(const MappedFile&) = delete;
  std::span<const std::uint8_t> bytes() const noexcept { return {data_, size_}; }

 private:
  const std::uint8_t* data_ = nullptr;
  std::size_t size_ = 0;
};

}  // namespace tsmh::bridge
