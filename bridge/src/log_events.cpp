#include "bridge/log_events.hpp"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <stdexcept>

namespace tsmh::bridge {
namespace {

std::uint32_t be32(const std::uint8_t* p) noexcept {
  return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) |
         std::uint32_t{p[3]};
}

std::uint64_t be64(const std::uint8_t* p) noexcept {
  return (std::uint64_t{be32(p)} << 32) | be32(p + 4);
}

std::int64_t add_saturating(std::int64_t a, std::int64_t b) noexcept {
  return a > INT64_MAX - b ? INT64_MAX : a + b;  // both >= 0
}

}  // namespace

std::string LogDamage::describe() const {
  std::string s;
  if (corrupt_regions > 0) {
    s += std::to_string(corrupt_regions) + " corrupt region(s), " + std::to_string(corrupt_bytes) +
         " bytes skipped, the first at byte " + std::to_string(first_corrupt_offset) + " (" +
         first_corrupt_reason + ")";
  }
  if (truncated) {
    if (!s.empty()) s += "; ";
    s += "the file ends inside the event at byte " + std::to_string(truncated_offset) + " (" +
         truncated_reason + ")";
  }
  if (any()) s += "; " + std::to_string(events_lost) + " event(s) lost";
  return s;
}

LogEventReader::Header LogEventReader::check(std::size_t at, LogEvent& out,
                                             std::string* why) const noexcept {
  const std::size_t left = bytes_.size() - at;
  if (left < kLogHeaderSize) {
    if (left >= 4 && be32(bytes_.data() + at) != kLogSyncWord) {
      if (why) *why = "no sync word";
      return Header::kCorrupt;
    }
    if (why) *why = "a " + std::to_string(left) + "-byte piece of a 28-byte event header";
    return Header::kTruncated;
  }
  const std::uint8_t* p = bytes_.data() + at;
  if (be32(p) != kLogSyncWord) {
    if (why) *why = "no sync word";
    return Header::kCorrupt;
  }
  const auto eventnum = static_cast<std::int64_t>(be64(p + 4));
  const auto timestamp = static_cast<std::int64_t>(be64(p + 12));
  const auto channel_len = static_cast<std::int32_t>(be32(p + 20));
  const auto data_len = static_cast<std::int32_t>(be32(p + 24));
  if (channel_len < 1 || channel_len > kMaxLogChannelLength) {
    if (why)
      *why = "channel length " + std::to_string(channel_len) + " outside 1.." +
             std::to_string(kMaxLogChannelLength);
    return Header::kCorrupt;
  }
  if (data_len < 0 || data_len > kMaxDataLength) {
    if (why)
      *why = "data length " + std::to_string(data_len) + " outside 0.." +
             std::to_string(kMaxDataLength);
    return Header::kCorrupt;
  }
  const std::size_t need =
      kLogHeaderSize + static_cast<std::size_t>(channel_len) + static_cast<std::size_t>(data_len);
  if (need > left) {
    if (why)
      *why = "event " + std::to_string(eventnum) + " needs " + std::to_string(need) + " bytes, " +
             std::to_string(left) + " are left";
    return Header::kTruncated;
  }
  out.eventnum = eventnum;
  out.timestamp = timestamp;
  out.channel = std::string_view(reinterpret_cast<const char*>(p + kLogHeaderSize),
                                 static_cast<std::size_t>(channel_len));
  out.data = bytes_.subspan(at + kLogHeaderSize + static_cast<std::size_t>(channel_len),
                            static_cast<std::size_t>(data_len));
  out.offset = at;
  return Header::kOk;
}

bool LogEventReader::next(LogEvent& out) noexcept {
  if (pos_ >= bytes_.size()) return false;
  std::string why;
  const Header h = check(pos_, out, &why);
  if (h == Header::kOk) {
    pos_ += kLogHeaderSize + out.channel.size() + out.data.size();
  } else {
    // Is there an intact event further on? Then this is a corrupt region
    // (whatever its lengths claim); if not, the file was cut off here.
    std::size_t at = pos_ + 1;
    for (; at + 4 <= bytes_.size(); ++at) {
      if (be32(bytes_.data() + at) == kLogSyncWord && check(at, out, nullptr) == Header::kOk) break;
    }
    if (at + 4 > bytes_.size()) {
      damage_.truncated = true;
      damage_.truncated_offset = pos_;
      damage_.truncated_reason =
          h == Header::kTruncated ? why : "an unreadable header (" + why + ")";
      damage_.events_lost = add_saturating(damage_.events_lost, 1);
      pos_ = bytes_.size();
      return false;
    }
    if (damage_.corrupt_regions++ == 0) {
      damage_.first_corrupt_offset = pos_;
      damage_.first_corrupt_reason = why;
    }
    damage_.corrupt_bytes += at - pos_;
    // The event numbers say how many were lost (at least the damaged one).
    // (Unsigned: hostile event numbers must not overflow the subtraction.)
    const std::uint64_t gap =
        have_last_ && out.eventnum > last_eventnum_
            ? static_cast<std::uint64_t>(out.eventnum) - static_cast<std::uint64_t>(last_eventnum_)
            : 2;
    const std::uint64_t skipped = gap > static_cast<std::uint64_t>(INT64_MAX) ? INT64_MAX : gap - 1;
    damage_.events_lost =
        add_saturating(damage_.events_lost, skipped > 0 ? static_cast<std::int64_t>(skipped) : 1);
    pos_ = at + kLogHeaderSize + out.channel.size() + out.data.size();
  }
  have_last_ = true;
  last_eventnum_ = out.eventnum;
  return true;
}

MappedFile::MappedFile(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw std::runtime_error(path + ": cannot open (" + std::strerror(errno) + ")");
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    throw std::runtime_error(path + ": not a regular file");
  }
  size_ = static_cast<std::size_t>(st.st_size);
  if (size_ > 0) {
    void* p = ::mmap(nullptr, size_, PROT_READ, MAP_PRIVATE, fd, 0);
    if (p == MAP_FAILED) {
      const int err = errno;
      ::close(fd);
      throw std::runtime_error(path + ": cannot map (" + std::strerror(err) + ")");
    }
    data_ = static_cast<const std::uint8_t*>(p);
  }
  ::close(fd);
}

MappedFile::~MappedFile() {
  if (data_) ::munmap(const_cast<std::uint8_t*>(data_), size_);
}

}  // namespace tsmh::bridge
