#include "master_devices/libusb_transport.hpp"

#include <fcntl.h>
#include <libusb.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <charconv>
#include <condition_variable>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <thread>
#include <utility>
#include <vector>

#include "master_devices/clock.hpp"
#include "master_devices/protocol.hpp"

namespace tsmh::master_devices {

namespace {
// Vendor control requests carrying feature reports, numbered as HID's
// GET_REPORT / SET_REPORT so a firmware can share the handler.
constexpr std::uint8_t kGetReport = 0x01;
constexpr std::uint8_t kSetReport = 0x09;
constexpr std::uint16_t kFeatureType = 0x0300;  // wValue high byte 3 = Feature
// bmRequestType: direction | vendor | interface recipient.
constexpr std::uint8_t kVendorInterfaceIn = 0xC1;
constexpr std::uint8_t kVendorInterfaceOut = 0x41;

std::string usb_error(int code) {
  return libusb_error_name(code);
}

class LibusbTransport;
}  // namespace

std::string usb_port_path(int bus, const std::uint8_t* ports, int count) {
  std::string path = "usb:" + std::to_string(bus) + "-";
  for (int i = 0; i < count; ++i) {
    if (i > 0) path += ".";
    path += std::to_string(ports[i]);
  }
  return path;
}

struct LibusbProvider::Impl {
  Options options;
  libusb_context* ctx = nullptr;
  std::string init_error;
  bool hotplug = false;
  libusb_hotplug_callback_handle hotplug_handle{};
  std::atomic<bool> stopping{false};
  std::thread events;

  std::mutex mutex;  // arrival, open
  std::function<void()> arrival;
  std::vector<LibusbTransport*> open;
  std::atomic<std::uint64_t> fallback_opens{0};

  void add(LibusbTransport* t) {
    std::lock_guard lock(mutex);
    open.push_back(t);
  }
  void remove(LibusbTransport* t) {
    std::lock_guard lock(mutex);
    open.erase(std::remove(open.begin(), open.end(), t), open.end());
  }
};

namespace {

std::string path_of(libusb_device* dev) {
  std::array<std::uint8_t, 8> ports{};
  const int n = libusb_get_port_numbers(dev, ports.data(), static_cast<int>(ports.size()));
  return usb_port_path(libusb_get_bus_number(dev), ports.data(), std::max(n, 0));
}

class LibusbTransport final : public Transport {
 public:
  LibusbTransport(LibusbProvider::Impl& provider, libusb_device_handle* handle, int wrapped_fd,
                  int interface, std::uint8_t ep_in, std::uint8_t ep_out, int in_size,
                  TransportDeviceInfo info)
      : provider_(provider),
        handle_(handle),
        wrapped_fd_(wrapped_fd),
        device_(libusb_get_device(handle)),
        interface_(interface),
        ep_in_(ep_in),
        ep_out_(ep_out),
        info_(std::move(info)) {
    const int n = std::max(1, provider_.options.in_transfers);
    in_buffers_.assign(static_cast<std::size_t>(n),
                       std::vector<std::uint8_t>(static_cast<std::size_t>(in_size)));
    // Filled here once so that libusb_cancel_transfer() is always safe to
    // call on them (it needs the device handle even when not in flight).
    for (int i = 0; i < n; ++i) {
      libusb_transfer* t = libusb_alloc_transfer(0);
      libusb_fill_interrupt_transfer(t, handle_, ep_in_,
                                     in_buffers_[static_cast<std::size_t>(i)].data(), in_size,
                                     &LibusbTransport::in_done, this, 0);
      in_.push_back(t);
    }
    out_ = libusb_alloc_transfer(0);
    libusb_fill_interrupt_transfer(out_, handle_, ep_out_, out_buffer_.data(), 0,
                                   &LibusbTransport::out_done, this, 100);
    provider_.add(this);
  }

  ~LibusbTransport() override {
    stop();
    provider_.remove(this);
    for (libusb_transfer* t : in_)
      libusb_free_transfer(t);
    libusb_free_transfer(out_);
    libusb_release_interface(handle_, interface_);
    libusb_close(handle_);
    if (wrapped_fd_ >= 0) ::close(wrapped_fd_);  // libusb leaves a wrapped fd to us
  }

  const TransportDeviceInfo& info() const override { return info_; }
  libusb_device* device() const { return device_; }

  std::size_t get_feature(std::uint8_t report_id, std::span<std::uint8_t> out) override {
    const int n = libusb_control_transfer(handle_, kVendorInterfaceIn, kGetReport,
                                          static_cast<std::uint16_t>(kFeatureType | report_id),
                                          static_cast<std::uint16_t>(interface_), out.data(),
                                          static_cast<std::uint16_t>(out.size()),
                                          provider_.options.control_timeout_ms);
    if (n < 0) {
      throw TransportError(info_.path + ": GET_REPORT(Feature " + std::to_string(report_id) +
                           "): " + usb_error(n));
    }
    return static_cast<std::size_t>(n);
  }

  void set_feature(std::span<const std::uint8_t> report) override {
    if (report.empty()) throw TransportError(info_.path + ": empty feature report");
    std::array<std::uint8_t, protocol::kMaxReportSize> copy{};  // libusb wants a mutable buffer
    const std::size_t size = std::min(report.size(), copy.size());
    std::copy_n(report.begin(), size, copy.begin());
    const int n = libusb_control_transfer(handle_, kVendorInterfaceOut, kSetReport,
                                          static_cast<std::uint16_t>(kFeatureType | report[0]),
                                          static_cast<std::uint16_t>(interface_), copy.data(),
                                          static_cast<std::uint16_t>(size),
                                          provider_.options.control_timeout_ms);
    if (n < 0) throw TransportError(info_.path + ": SET_REPORT(Feature): " + usb_error(n));
  }

  void start(TransportListener& listener) override {
    stop();
    listener_ = &listener;
    stopping_ = false;
    lost_ = false;
    out_busy_ = false;
    pending_size_ = 0;
    for (std::size_t i = 0; i < in_.size(); ++i) {
      libusb_fill_interrupt_transfer(in_[i], handle_, ep_in_, in_buffers_[i].data(),
                                     static_cast<int>(in_buffers_[i].size()),
                                     &LibusbTransport::in_done, this, 0);
      const int rc = libusb_submit_transfer(in_[i]);
      if (rc != 0) {
        stop();
        throw TransportError(info_.path + ": submitting IN transfer: " + usb_error(rc));
      }
      std::lock_guard lock(mutex_);
      ++in_flight_;
    }
  }

  void stop() noexcept override {
    stopping_ = true;
    for (libusb_transfer* t : in_)
      libusb_cancel_transfer(t);  // errors: not in flight
    libusb_cancel_transfer(out_);
    std::unique_lock lock(mutex_);
    // Cancelled transfers complete on the event thread; wait for all of them
    // so no callback can touch the listener afterwards.
    done_.wait_for(lock, std::chrono::seconds(2), [this] { return in_flight_ == 0; });
    listener_ = nullptr;
  }

  bool write_output(std::span<const std::uint8_t> report) noexcept override {
    // Runs on the event thread (inside on_input_report), like out_done():
    // out_busy_ and pending_ need no lock.
    if (stopping_ || lost_ || report.size() > out_buffer_.size()) return false;
    if (out_busy_) {
      // Newest wins: a torque command superseded before it left is dropped.
      std::copy(report.begin(), report.end(), pending_.begin());
      pending_size_ = report.size();
      return true;
    }
    return submit_out(report);
  }

  void report_lost(const char* why) noexcept {
    if (lost_.exchange(true)) return;
    if (listener_ != nullptr) listener_->on_link_lost(why);
  }

 private:
  bool submit_out(std::span<const std::uint8_t> report) noexcept {
    std::copy(report.begin(), report.end(), out_buffer_.begin());
    libusb_fill_interrupt_transfer(out_, handle_, ep_out_, out_buffer_.data(),
                                   static_cast<int>(report.size()), &LibusbTransport::out_done,
                                   this, 100);
    if (libusb_submit_transfer(out_) != 0) return false;
    out_busy_ = true;
    std::lock_guard lock(mutex_);
    ++in_flight_;
    return true;
  }

  void finished() {
    std::lock_guard lock(mutex_);
    --in_flight_;
    done_.notify_all();
  }

  static void LIBUSB_CALL in_done(libusb_transfer* t) {
    static_cast<LibusbTransport*>(t->user_data)->handle_in(t);
  }
  static void LIBUSB_CALL out_done(libusb_transfer* t) {
    static_cast<LibusbTransport*>(t->user_data)->handle_out(t);
  }

  void handle_in(libusb_transfer* t) {
    switch (t->status) {
      case LIBUSB_TRANSFER_COMPLETED:
        if (!stopping_ && !lost_ && listener_ != nullptr) {
          listener_->on_input_report(
              std::span<const std::uint8_t>(t->buffer, static_cast<std::size_t>(t->actual_length)),
              provider_.options.clock->now_ns());
        }
        [[fallthrough]];
      case LIBUSB_TRANSFER_TIMED_OUT:
        if (!stopping_ && !lost_) {
          if (libusb_submit_transfer(t) == 0) return;
          report_lost("resubmitting IN transfer failed");
        }
        break;
      case LIBUSB_TRANSFER_CANCELLED:
        break;
      case LIBUSB_TRANSFER_NO_DEVICE:
        report_lost("device unplugged");
        break;
      case LIBUSB_TRANSFER_STALL:
        report_lost("IN endpoint stalled");
        break;
      case LIBUSB_TRANSFER_OVERFLOW:
        report_lost("IN transfer overflow");
        break;
      case LIBUSB_TRANSFER_ERROR:
        report_lost("IN transfer error");
        break;
    }
    finished();
  }

  void handle_out(libusb_transfer* t) {
    out_busy_ = false;
    if (t->status == LIBUSB_TRANSFER_NO_DEVICE) report_lost("device unplugged");
    if (!stopping_ && !lost_ && pending_size_ > 0) {
      const std::size_t size = pending_size_;
      pending_size_ = 0;
      std::array<std::uint8_t, protocol::kMaxReportSize> next = pending_;
      submit_out(std::span<const std::uint8_t>(next.data(), size));
    }
    finished();
  }

  LibusbProvider::Impl& provider_;
  libusb_device_handle* handle_;
  int wrapped_fd_;  // usbfs fd we opened (sysfs fallback), else -1
  libusb_device* device_;
  int interface_;
  std::uint8_t ep_in_;
  std::uint8_t ep_out_;
  TransportDeviceInfo info_;

  std::vector<libusb_transfer*> in_;
  std::vector<std::vector<std::uint8_t>> in_buffers_;
  libusb_transfer* out_ = nullptr;
  std::array<std::uint8_t, protocol::kMaxReportSize> out_buffer_{};
  std::array<std::uint8_t, protocol::kMaxReportSize> pending_{};
  std::size_t pending_size_ = 0;
  bool out_busy_ = false;

  TransportListener* listener_ = nullptr;
  std::atomic<bool> stopping_{true};
  std::atomic<bool> lost_{false};
  std::mutex mutex_;
  std::condition_variable done_;
  int in_flight_ = 0;
};

int LIBUSB_CALL on_hotplug(libusb_context*, libusb_device* dev, libusb_hotplug_event event,
                           void* user) {
  auto* impl = static_cast<LibusbProvider::Impl*>(user);
  std::function<void()> arrival;
  {
    std::lock_guard lock(impl->mutex);
    if (event == LIBUSB_HOTPLUG_EVENT_DEVICE_LEFT) {
      for (LibusbTransport* t : impl->open) {
        if (t->device() == dev) t->report_lost("device left (hotplug)");
      }
    } else {
      arrival = impl->arrival;
    }
  }
  if (arrival) arrival();
  return 0;  // stay registered
}

// One line of a sysfs attribute, without the newline; nullopt-like "" + false when unreadable.
bool read_attribute(const std::filesystem::path& file, std::string& out) {
  std::ifstream f(file);
  if (!f) return false;
  std::getline(f, out);
  return !f.bad();
}

template <class T>
bool parse_number(const std::string& text, int base, T& out) {
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, out, base);
  return ec == std::errc() && ptr == end && !text.empty();
}

std::string ascii_string(libusb_device_handle* h, std::uint8_t index) {
  if (index == 0) return "";
  std::array<unsigned char, 128> buf{};
  const int n =
      libusb_get_string_descriptor_ascii(h, index, buf.data(), static_cast<int>(buf.size()));
  return n > 0 ? std::string(buf.begin(), buf.begin() + n) : "";
}

}  // namespace

std::vector<SysfsUsbDevice> scan_sysfs_usb(const std::string& root, std::uint16_t vendor_id,
                                           std::uint16_t product_id) {
  std::vector<SysfsUsbDevice> out;
  std::error_code ec;
  std::filesystem::directory_iterator it(root, ec);
  if (ec) return out;
  for (; it != std::filesystem::directory_iterator(); it.increment(ec)) {
    if (ec) break;
    SysfsUsbDevice d;
    d.name = it->path().filename().string();
    // Devices are "<bus>-<port>[.<port>...]"; root hubs are "usbN", interfaces contain ':'.
    if (d.name.empty() || d.name.find(':') != std::string::npos ||
        d.name.find('-') == std::string::npos || d.name.rfind("usb", 0) == 0)
      continue;
    const std::filesystem::path dir = it->path();
    std::string vid, pid, bus, dev;
    if (!read_attribute(dir / "idVendor", vid) || !read_attribute(dir / "idProduct", pid) ||
        !read_attribute(dir / "busnum", bus) || !read_attribute(dir / "devnum", dev))
      continue;
    if (!parse_number(vid, 16, d.vendor_id) || !parse_number(pid, 16, d.product_id) ||
        !parse_number(bus, 10, d.busnum) || !parse_number(dev, 10, d.devnum))
      continue;
    if (d.vendor_id != vendor_id || d.product_id != product_id) continue;
    read_attribute(dir / "serial", d.serial);  // optional strings
    read_attribute(dir / "manufacturer", d.manufacturer);
    read_attribute(dir / "product", d.product);
    out.push_back(std::move(d));
  }
  std::sort(out.begin(), out.end(),
            [](const SysfsUsbDevice& a, const SysfsUsbDevice& b) { return a.name < b.name; });
  return out;
}

LibusbProvider::LibusbProvider() : LibusbProvider(Options{}) {}

LibusbProvider::LibusbProvider(Options options) : impl_(std::make_unique<Impl>()) {
  impl_->options = std::move(options);
  if (!impl_->options.clock) impl_->options.clock = monotonic_clock();
  // Our own context: no process-wide libusb state shared with anyone.
  const int rc = libusb_init(&impl_->ctx);
  if (rc != 0) {
    impl_->ctx = nullptr;
    impl_->init_error = "libusb_init: " + usb_error(rc);
    return;
  }
  if (libusb_has_capability(LIBUSB_CAP_HAS_HOTPLUG)) {
    const int hrc = libusb_hotplug_register_callback(
        impl_->ctx,
        static_cast<libusb_hotplug_event>(LIBUSB_HOTPLUG_EVENT_DEVICE_ARRIVED |
                                          LIBUSB_HOTPLUG_EVENT_DEVICE_LEFT),
        static_cast<libusb_hotplug_flag>(0), LIBUSB_HOTPLUG_MATCH_ANY, LIBUSB_HOTPLUG_MATCH_ANY,
        LIBUSB_HOTPLUG_MATCH_ANY, &on_hotplug, impl_.get(), &impl_->hotplug_handle);
    impl_->hotplug = hrc == LIBUSB_SUCCESS;
  }
  Impl* impl = impl_.get();
  impl_->events = std::thread([impl] {
    while (!impl->stopping) {
      timeval tv{0, 100'000};
      libusb_handle_events_timeout_completed(impl->ctx, &tv, nullptr);
    }
  });
}

LibusbProvider::~LibusbProvider() {
  if (impl_->ctx == nullptr) return;
  impl_->stopping = true;
  libusb_interrupt_event_handler(impl_->ctx);
  if (impl_->events.joinable()) impl_->events.join();
  if (impl_->hotplug) libusb_hotplug_deregister_callback(impl_->ctx, impl_->hotplug_handle);
  libusb_exit(impl_->ctx);
}

const std::string& LibusbProvider::init_error() const {
  return impl_->init_error;
}
bool LibusbProvider::hotplug_supported() const {
  return impl_->hotplug;
}
std::uint64_t LibusbProvider::fallback_opens() const {
  return impl_->fallback_opens.load();
}

void LibusbProvider::set_arrival_callback(std::function<void()> callback) {
  std::lock_guard lock(impl_->mutex);
  impl_->arrival = std::move(callback);
}

std::vector<TransportDeviceInfo> LibusbProvider::enumerate(std::uint16_t vendor_id,
                                                           std::uint16_t product_id) {
  std::vector<TransportDeviceInfo> out;
  if (impl_->ctx == nullptr) return out;
  std::vector<std::pair<int, int>> bus_address;  // per entry of `out`, from libusb
  libusb_device** list = nullptr;
  const ssize_t n = libusb_get_device_list(impl_->ctx, &list);
  for (ssize_t i = 0; i < n; ++i) {
    libusb_device_descriptor desc{};
    if (libusb_get_device_descriptor(list[i], &desc) != 0) continue;
    if (desc.idVendor != vendor_id || desc.idProduct != product_id) continue;
    TransportDeviceInfo info{path_of(list[i]), desc.idVendor, desc.idProduct, "", "", ""};
    libusb_device_handle* h = nullptr;
    if (libusb_open(list[i], &h) == 0) {  // strings need access; without it they stay ""
      info.serial = ascii_string(h, desc.iSerialNumber);
      info.manufacturer = ascii_string(h, desc.iManufacturer);
      info.product = ascii_string(h, desc.iProduct);
      libusb_close(h);
    }
    out.push_back(std::move(info));
    bus_address.emplace_back(libusb_get_bus_number(list[i]), libusb_get_device_address(list[i]));
  }
  if (list != nullptr) libusb_free_device_list(list, 1);
  // Consoles libusb does not list (no udevd to announce them), from sysfs;
  // at a port where libusb still lists a device that has left, sysfs's wins.
  if (!impl_->options.sysfs_root.empty()) {
    for (SysfsUsbDevice& d : scan_sysfs_usb(impl_->options.sysfs_root, vendor_id, product_id)) {
      TransportDeviceInfo info{
          "usb:" + d.name,           d.vendor_id,         d.product_id, std::move(d.serial),
          std::move(d.manufacturer), std::move(d.product)};
      const auto same_port =
          std::find_if(out.begin(), out.end(),
                       [&](const TransportDeviceInfo& i) { return i.path == info.path; });
      if (same_port == out.end()) {
        out.push_back(std::move(info));
        bus_address.emplace_back(d.busnum, d.devnum);
      } else if (bus_address[static_cast<std::size_t>(same_port - out.begin())] !=
                 std::pair<int, int>(d.busnum, d.devnum)) {
        *same_port = std::move(info);
      }
    }
  }
  return out;
}

std::unique_ptr<Transport> LibusbProvider::open(const TransportDeviceInfo& device) {
  if (impl_->ctx == nullptr) throw TransportError(device.path + ": " + impl_->init_error);
  // What the kernel has at this port now (the sysfs fallback's view).
  const SysfsUsbDevice* now = nullptr;
  std::vector<SysfsUsbDevice> sysfs;
  if (!impl_->options.sysfs_root.empty() && device.path.rfind("usb:", 0) == 0) {
    sysfs = scan_sysfs_usb(impl_->options.sysfs_root, device.vendor_id, device.product_id);
    for (const SysfsUsbDevice& d : sysfs)
      if ("usb:" + d.name == device.path) now = &d;
  }
  libusb_device** list = nullptr;
  const ssize_t n = libusb_get_device_list(impl_->ctx, &list);
  libusb_device* found = nullptr;
  for (ssize_t i = 0; i < n; ++i) {
    // Same port, and the same device there (not one that has left since).
    if (path_of(list[i]) == device.path &&
        (now == nullptr || (libusb_get_bus_number(list[i]) == now->busnum &&
                            libusb_get_device_address(list[i]) == now->devnum)))
      found = list[i];
  }
  libusb_device_handle* h = nullptr;
  int wrapped_fd = -1;
  int orc = found != nullptr ? libusb_open(found, &h) : LIBUSB_ERROR_NO_DEVICE;
  if (list != nullptr) libusb_free_device_list(list, 1);
  std::string how = "libusb_open";
  if (found == nullptr && now != nullptr) {
    // Fallback: libusb never heard of it; open its usbfs node ourselves.
    char node[64];
    std::snprintf(node, sizeof node, "/%03d/%03d", now->busnum, now->devnum);
    const std::string file = impl_->options.usbfs_root + node;
    how = "opening " + file;
    wrapped_fd = ::open(file.c_str(), O_RDWR | O_CLOEXEC);
    if (wrapped_fd < 0) {
      const int e = errno;
      throw TransportError(
          device.path + ": " + how + ": " + std::strerror(e) +
          (e == EACCES ? " (install the udev rules, see docs/master-devices.md)" : ""));
    }
    how = "libusb_wrap_sys_device(" + file + ")";
    orc = libusb_wrap_sys_device(impl_->ctx, wrapped_fd, &h);
    if (orc != 0) ::close(wrapped_fd);
  }
  if (orc != 0) {
    throw TransportError(device.path + ": " + how + ": " + usb_error(orc) +
                         (orc == LIBUSB_ERROR_ACCESS
                              ? " (install the udev rules, see docs/master-devices.md)"
                              : ""));
  }
  const auto close_handle = [&] {
    libusb_close(h);
    if (wrapped_fd >= 0) ::close(wrapped_fd);
  };

  // The vendor interface with an interrupt IN and OUT endpoint.
  libusb_config_descriptor* config = nullptr;
  int interface = -1;
  std::uint8_t ep_in = 0;
  std::uint8_t ep_out = 0;
  int in_size = 64;
  if (libusb_get_active_config_descriptor(libusb_get_device(h), &config) == 0) {
    for (int i = 0; i < config->bNumInterfaces && interface < 0; ++i) {
      const libusb_interface& itf = config->interface[i];
      if (itf.num_altsetting < 1) continue;
      const libusb_interface_descriptor& alt = itf.altsetting[0];
      if (alt.bInterfaceClass != impl_->options.interface_class) continue;
      std::uint8_t in = 0;
      std::uint8_t out = 0;
      int size = 64;
      for (int e = 0; e < alt.bNumEndpoints; ++e) {
        const libusb_endpoint_descriptor& ep = alt.endpoint[e];
        if ((ep.bmAttributes & LIBUSB_TRANSFER_TYPE_MASK) != LIBUSB_TRANSFER_TYPE_INTERRUPT)
          continue;
        if (ep.bEndpointAddress & LIBUSB_ENDPOINT_IN) {
          in = ep.bEndpointAddress;
          size =
              std::max<int>(ep.wMaxPacketSize & 0x7FF, static_cast<int>(protocol::kMaxReportSize));
        } else {
          out = ep.bEndpointAddress;
        }
      }
      if (in != 0 && out != 0) {
        interface = alt.bInterfaceNumber;
        ep_in = in;
        ep_out = out;
        in_size = size;
      }
    }
    libusb_free_config_descriptor(config);
  }
  if (interface < 0) {
    close_handle();
    throw TransportError(device.path +
                         ": no vendor-class interface with interrupt IN and OUT endpoints");
  }
  libusb_set_auto_detach_kernel_driver(h, 1);
  const int crc = libusb_claim_interface(h, interface);
  if (crc != 0) {
    close_handle();
    throw TransportError(device.path + ": claiming interface " + std::to_string(interface) + ": " +
                         usb_error(crc));
  }
  if (wrapped_fd >= 0) impl_->fallback_opens++;
  return std::make_unique<LibusbTransport>(*impl_, h, wrapped_fd, interface, ep_in, ep_out, in_size,
                                           device);
}

}  // namespace tsmh::master_devices
