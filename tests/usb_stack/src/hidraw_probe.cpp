// Host side of the raw HID case: finds the stand-in console's hidraw node by
// VID/PID, checks what the kernel made of its report descriptor, and
// exchanges numbered reports with usb_stack_hidg_echo on the gadget side.
// It proves the kernel path (usbhid, hidraw, report-ID byte) without our
// codec; the driver cases prove our code on top of it.

#include <fcntl.h>
#include <linux/hidraw.h>
#include <linux/input.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "guest_report.hpp"
#include "raw_descriptor.hpp"
#include "stats.hpp"

namespace raw = tsmh::usb_stack::raw;
using tsmh::usb_stack::metric;
using tsmh::usb_stack::result;
using tsmh::usb_stack::Verdict;

namespace {

/// "/dev/hidrawN" whose HID_ID (sysfs uevent) matches USB VID:PID, or "".
std::string find_hidraw(unsigned vid, unsigned pid) {
  char want[64];
  std::snprintf(want, sizeof want, "HID_ID=0003:%08X:%08X", vid, pid);
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator("/sys/class/hidraw", ec)) {
    std::ifstream uevent(e.path() / "device" / "uevent");
    for (std::string line; std::getline(uevent, line);) {
      if (line == want) return "/dev/" + e.path().filename().string();
    }
  }
  return "";
}

std::string hex(const std::uint8_t* p, std::size_t n) {
  std::string s;
  char b[4];
  for (std::size_t i = 0; i < n; ++i) {
    std::snprintf(b, sizeof b, "%02x", p[i]);
    s += b;
  }
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  unsigned vid = 0x1209;
  unsigned pid = 0x0001;
  int count = 200;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    const char* value = argv[i + 1];
    if (flag == "--vid") {
      vid = static_cast<unsigned>(std::strtoul(value, nullptr, 0));
    } else if (flag == "--pid") {
      pid = static_cast<unsigned>(std::strtoul(value, nullptr, 0));
    } else if (flag == "--count") {
      count = std::atoi(value);
    } else if (flag == "--write-descriptor") {
      std::ofstream(value, std::ios::binary)
          .write(reinterpret_cast<const char*>(raw::kReportDescriptor.data()),
                 static_cast<std::streamsize>(raw::kReportDescriptor.size()));
      return 0;
    } else {
      std::fprintf(stderr, "hidraw_probe: unknown flag %s\n", flag.c_str());
      return 2;
    }
  }

  const std::string node = find_hidraw(vid, pid);
  result("raw_hidraw_found", !node.empty(), node.empty() ? "no hidraw with this VID:PID" : node);
  if (node.empty()) return 1;
  const int fd = ::open(node.c_str(), O_RDWR);
  if (fd < 0) {
    result("raw_hidraw_open", false, std::strerror(errno));
    return 1;
  }

  hidraw_devinfo info{};
  if (::ioctl(fd, HIDIOCGRAWINFO, &info) < 0) {
    result("raw_hidraw_info", false, std::strerror(errno));
  } else {
    char d[96];
    std::snprintf(d, sizeof d, "bustype=%u vid=%04x pid=%04x", info.bustype,
                  static_cast<unsigned>(info.vendor) & 0xffffU,
                  static_cast<unsigned>(info.product) & 0xffffU);
    result("raw_hidraw_info",
           info.bustype == BUS_USB && (static_cast<unsigned>(info.vendor) & 0xffffU) == vid &&
               (static_cast<unsigned>(info.product) & 0xffffU) == pid,
           d);
  }

  // The kernel hands hidraw exactly the descriptor the device served.
  hidraw_report_descriptor rd{};
  int size = 0;
  if (::ioctl(fd, HIDIOCGRDESCSIZE, &size) < 0 || size <= 0) {
    result("raw_report_descriptor", false, "HIDIOCGRDESCSIZE failed");
  } else {
    rd.size = static_cast<__u32>(size);
    const bool got = ::ioctl(fd, HIDIOCGRDESC, &rd) >= 0;
    const bool same = got && rd.size == raw::kReportDescriptor.size() &&
                      std::memcmp(rd.value, raw::kReportDescriptor.data(), rd.size) == 0;
    result("raw_report_descriptor", same,
           (same ? "identical, " : "differs: ") + std::to_string(rd.size) + " bytes " +
               (same ? std::string() : hex(rd.value, rd.size)));
  }

  // Numbered reports: we write the ID byte first, and read it back first.
  std::vector<double> rtt_us;
  int bad = 0;
  int timeouts = 0;
  std::string first_problem;
  for (int k = 0; k < count; ++k) {
    std::array<std::uint8_t, raw::kReportLength> out{};
    out[0] = raw::kOutputId;
    for (std::size_t i = 1; i < out.size(); ++i)
      out[i] = static_cast<std::uint8_t>(k + 7 * i);
    const auto t0 = std::chrono::steady_clock::now();
    if (::write(fd, out.data(), out.size()) != static_cast<ssize_t>(out.size())) {
      first_problem = std::string("write: ") + std::strerror(errno);
      ++bad;
      break;
    }
    pollfd p{fd, POLLIN, 0};
    if (::poll(&p, 1, 1000) <= 0) {
      if (first_problem.empty())
        first_problem = "no reply within 1 s to report " + std::to_string(k);
      ++timeouts;
      continue;
    }
    std::array<std::uint8_t, 64> in{};
    const ssize_t n = ::read(fd, in.data(), in.size());
    const auto t1 = std::chrono::steady_clock::now();
    bool ok = n == static_cast<ssize_t>(raw::kReportLength) && in[0] == raw::kInputId;
    for (std::size_t i = 1; ok && i < raw::kReportLength; ++i)
      ok = in[i] == raw::echo(out[i]);
    if (!ok) {
      if (first_problem.empty())
        first_problem = "report " + std::to_string(k) + ": got " +
                        hex(in.data(), n > 0 ? static_cast<std::size_t>(n) : 0);
      ++bad;
      continue;
    }
    rtt_us.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
  }
  const auto pc = tsmh::usb_stack::percentiles(rtt_us);
  result("raw_round_trip", bad == 0 && timeouts == 0 && static_cast<int>(pc.count) == count,
         std::to_string(pc.count) + "/" + std::to_string(count) + " echoed" +
             (first_problem.empty() ? "" : "; first problem: " + first_problem));
  metric("raw_rtt_p50", pc.p50, "us");
  metric("raw_rtt_p99", pc.p99, "us");
  metric("raw_rtt_max", pc.max, "us");

  // GET_REPORT(Feature) travels on ep0; what the gadget answers is a property
  // of usb_f_hid, recorded so the driver cases can be read against it.
  std::array<std::uint8_t, raw::kReportLength> feat{};
  feat[0] = raw::kFeatureId;
  const int fr = ::ioctl(fd, HIDIOCGFEATURE(feat.size()), feat.data());
  if (fr < 0) {
    result("raw_get_feature", Verdict::kSkip,
           std::string("usb_f_hid rejects GET_REPORT(Feature): ") + std::strerror(errno));
  } else {
    result("raw_get_feature", Verdict::kSkip,
           "usb_f_hid answers GET_REPORT(Feature) itself, not userspace: " + std::to_string(fr) +
               " bytes " + hex(feat.data(), static_cast<std::size_t>(fr)));
  }
  ::close(fd);
  return 0;
}
