#pragma once
// What the gadget side tells the host side of a driver case without going
// through the USB stack under test: a small shared file (tmpfs) that the
// firmware program writes and the host program maps read-only. Both run in
// the same guest, so CLOCK_MONOTONIC is one clock for both.
//
// The firmware records when each input report left the gadget (its IN write
// completed: the host controller took it). The host side judges its unplug
// detection from the last one: an independent reference for "the device's
// last report", not derived from the driver's own dating of samples.

#include <fcntl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <atomic>
#include <cstdint>
#include <new>
#include <string>

namespace tsmh::usb_stack {

struct DeviceMailbox {
  std::atomic<std::int64_t> last_in_ns{0};    ///< CLOCK_MONOTONIC: the newest IN report left
  std::atomic<std::uint64_t> in_reports{0};   ///< IN reports that left
  std::atomic<std::int64_t> link_lost_ns{0};  ///< the gadget saw DISABLE/UNBIND/SUSPEND
};
static_assert(std::atomic<std::int64_t>::is_always_lock_free, "shared between processes");

/// Maps the mailbox file: `create` (the firmware) truncates and sizes it,
/// otherwise (the host) it must exist. valid() is false when that failed.
class MailboxMap {
 public:
  MailboxMap(const std::string& path, bool create) {
    if (path.empty()) return;
    const int fd = ::open(path.c_str(), create ? (O_RDWR | O_CREAT | O_TRUNC) : O_RDWR, 0644);
    if (fd < 0) return;
    if (create && ::ftruncate(fd, sizeof(DeviceMailbox)) != 0) {
      ::close(fd);
      return;
    }
    void* p = ::mmap(nullptr, sizeof(DeviceMailbox), PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
    ::close(fd);
    if (p == MAP_FAILED) return;
    box_ = create ? new (p) DeviceMailbox : static_cast<DeviceMailbox*>(p);
  }
  ~MailboxMap() {
    if (box_ != nullptr) ::munmap(box_, sizeof(DeviceMailbox));
  }
  MailboxMap(const MailboxMap&) = delete;
  MailboxMap& operator=(const MailboxMap&) = delete;

  bool valid() const { return box_ != nullptr; }
  DeviceMailbox* operator->() const { return box_; }

 private:
  DeviceMailbox* box_ = nullptr;
};

}  // namespace tsmh::usb_stack
