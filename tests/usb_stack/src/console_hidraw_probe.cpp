// Host side, kernel level: finds the console's hidraw node by VID/PID and
// checks, with our codec but without our driver, what the kernel does with
// the console's report descriptor and reports: the descriptor hidraw hands
// out, GET_REPORT(Feature), the report-ID byte, input sequence continuity,
// and the output -> device -> input round trip (the firmware echoes the
// newest accepted output sequence in every input report).
//
// Usage: usb_stack_console_hidraw_probe --prefix P [--vid V --pid P]
//          [--count N] [--features expect|record]
// --features record: GET_REPORT(Feature) is reported (SKIP) rather than
// judged, for gadgets (usb_f_hid) whose kernel side answers it by itself.

#include <fcntl.h>
#include <linux/hidraw.h>
#include <linux/input.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "guest_report.hpp"
#include "master_devices/protocol.hpp"
#include "realtime/clock.hpp"
#include "realtime/quantile.hpp"

namespace protocol = tsmh::master_devices::protocol;
using tsmh::usb_stack::metric;
using tsmh::usb_stack::result;
using tsmh::usb_stack::Verdict;

namespace {

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

/// Reads one report within timeout_ms; returns its size (0 on timeout, -1 on error).
ssize_t read_report(int fd, std::span<std::uint8_t> buf, int timeout_ms) {
  pollfd p{fd, POLLIN, 0};
  const int r = ::poll(&p, 1, timeout_ms);
  if (r < 0) return -1;
  if (r == 0) return 0;
  return ::read(fd, buf.data(), buf.size());
}

}  // namespace

int main(int argc, char** argv) {
  unsigned vid = 0x1209;
  unsigned pid = 0x0001;
  int count = 1000;
  bool expect_features = true;
  std::string p = "console";
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    const std::string value = argv[i + 1];
    if (flag == "--vid") {
      vid = static_cast<unsigned>(std::strtoul(value.c_str(), nullptr, 0));
    } else if (flag == "--pid") {
      pid = static_cast<unsigned>(std::strtoul(value.c_str(), nullptr, 0));
    } else if (flag == "--count") {
      count = std::atoi(value.c_str());
    } else if (flag == "--prefix") {
      p = value;
    } else if (flag == "--features" && (value == "expect" || value == "record")) {
      expect_features = value == "expect";
    } else {
      std::fprintf(stderr, "console_hidraw_probe: bad argument %s %s\n", flag.c_str(),
                   value.c_str());
      return 2;
    }
  }

  const std::string node = find_hidraw(vid, pid);
  if (node.empty()) {
    result(p + "_hidraw", false, "no hidraw node with this VID:PID");
    return 1;
  }
  const int fd = ::open(node.c_str(), O_RDWR);
  if (fd < 0) {
    result(p + "_hidraw", false, node + ": " + std::strerror(errno));
    return 1;
  }
  hidraw_devinfo info{};
  const bool info_ok = ::ioctl(fd, HIDIOCGRAWINFO, &info) >= 0 && info.bustype == BUS_USB &&
                       (static_cast<unsigned>(info.vendor) & 0xffffU) == vid &&
                       (static_cast<unsigned>(info.product) & 0xffffU) == pid;
  result(p + "_hidraw", info_ok,
         node + (info_ok ? ": bus USB, VID:PID match" : ": HIDIOCGRAWINFO mismatch"));

  // The kernel must hand out exactly our descriptor (it parsed it to bind).
  const auto ours = protocol::hid_report_descriptor();
  hidraw_report_descriptor rd{};
  int size = 0;
  bool same = ::ioctl(fd, HIDIOCGRDESCSIZE, &size) >= 0 && size > 0;
  if (same) {
    rd.size = static_cast<__u32>(size);
    same = ::ioctl(fd, HIDIOCGRDESC, &rd) >= 0 && rd.size == ours.size() &&
           std::memcmp(rd.value, ours.data(), ours.size()) == 0;
  }
  result(p + "_report_descriptor", same,
         same ? "hidraw returns our " + std::to_string(ours.size()) + "-byte descriptor"
              : "differs: " + hex(rd.value, rd.size));

  // GET_REPORT(Feature DEVICE_INFO) through the kernel's control path.
  std::array<std::uint8_t, protocol::kMaxReportSize> feat{};
  feat[0] = protocol::kDeviceInfoReportId;
  const int fr = ::ioctl(fd, HIDIOCGFEATURE(protocol::kDeviceInfoReportSize), feat.data());
  std::string fdetail;
  bool fok = false;
  if (fr < 0) {
    fdetail = std::string("HIDIOCGFEATURE: ") + std::strerror(errno);
  } else {
    const auto d =
        protocol::decode_device_info(std::span(feat.data(), static_cast<std::size_t>(fr)));
    fok = d.ok();
    fdetail = fok ? "DEVICE_INFO decoded: dof " + std::to_string(d.value.dof) + ", rate " +
                        std::to_string(d.value.nominal_rate_hz) + " Hz"
                  : std::to_string(fr) + " bytes " +
                        hex(feat.data(), static_cast<std::size_t>(fr)) + ": " +
                        protocol::describe(d.error);
  }
  // SET_REPORT(Feature CALIBRATION), then read it back: the handshake's second half.
  protocol::Calibration cal;
  cal.watchdog_ms = 40;
  cal.current_limit_ma = {1000, 1000};
  cal.direction = {1, 1};
  std::array<std::uint8_t, protocol::kMaxReportSize> cb{};
  const std::size_t cn = protocol::encode(cal, cb).value;
  std::string sdetail;
  bool sok = false;
  if (::ioctl(fd, HIDIOCSFEATURE(cn), cb.data()) < 0) {
    sdetail = std::string("HIDIOCSFEATURE: ") + std::strerror(errno);
  } else {
    std::array<std::uint8_t, protocol::kMaxReportSize> back{};
    back[0] = protocol::kCalibrationReportId;
    const int br = ::ioctl(fd, HIDIOCGFEATURE(protocol::kCalibrationReportSize), back.data());
    const auto d =
        br < 0 ? protocol::Result<protocol::Calibration>{}
               : protocol::decode_calibration(std::span(back.data(), static_cast<std::size_t>(br)));
    sok = br >= 0 && d.ok() && d.value == cal;
    sdetail = br < 0 ? std::string("read back: ") + std::strerror(errno)
              : sok  ? "CALIBRATION written and read back identical"
                     : "read back differs: " + hex(back.data(), static_cast<std::size_t>(br));
  }
  if (expect_features) {
    result(p + "_get_feature", fok, fdetail);
    result(p + "_set_feature", sok, sdetail);
  } else {
    result(p + "_get_feature", Verdict::kSkip, "recorded, not judged: " + fdetail);
    result(p + "_set_feature", Verdict::kSkip, "recorded, not judged: " + sdetail);
  }

  // Stream: every input report decodes, its sequence follows the previous
  // one; one output report per input report, and the time until an input
  // report echoes its sequence is the stack's round trip.
  std::vector<double> rtt_us;
  std::vector<double> interval_us;
  int bad = 0;
  int gaps = 0;
  int timeouts = 0;
  std::string first_problem;
  bool have_prev = false;
  std::uint16_t prev_seq = 0;
  std::int64_t prev_t = 0;
  std::uint16_t out_seq = 100;
  std::int64_t pending_t = 0;  // write time of the output report awaiting its echo
  std::uint16_t pending_seq = 0;
  for (int k = 0; k < count; ++k) {
    std::array<std::uint8_t, 64> in{};
    const ssize_t n = read_report(fd, in, 1000);
    const std::int64_t t = tsmh::realtime::monotonic_now_ns();
    if (n <= 0) {
      ++timeouts;
      if (first_problem.empty())
        first_problem = n == 0 ? "no input report within 1 s" : std::strerror(errno);
      if (timeouts > 3) break;
      continue;
    }
    const auto r = protocol::decode_input(std::span(in.data(), static_cast<std::size_t>(n)));
    if (!r.ok()) {
      ++bad;
      if (first_problem.empty()) first_problem = protocol::describe(r.error);
      continue;
    }
    if (have_prev) {
      if (protocol::sequence_delta(prev_seq, r.value.sequence) != 1) ++gaps;
      interval_us.push_back(static_cast<double>(t - prev_t) * 1e-3);
    }
    have_prev = true;
    prev_seq = r.value.sequence;
    prev_t = t;
    if (pending_t != 0 && r.value.last_output_sequence == pending_seq) {
      rtt_us.push_back(static_cast<double>(t - pending_t) * 1e-3);
      pending_t = 0;
    }
    if (pending_t == 0) {
      protocol::OutputReport o;
      o.sequence = ++out_seq;
      std::array<std::uint8_t, protocol::kOutputReportSize> ob{};
      protocol::encode(o, ob);
      pending_t = tsmh::realtime::monotonic_now_ns();
      pending_seq = o.sequence;
      if (::write(fd, ob.data(), ob.size()) != static_cast<ssize_t>(ob.size())) {
        if (first_problem.empty()) first_problem = std::string("write: ") + std::strerror(errno);
        ++bad;
        pending_t = 0;
      }
    }
  }
  const auto rtt = tsmh::realtime::percentiles(rtt_us);
  const auto gap = tsmh::realtime::percentiles(interval_us);
  char d[300];
  std::snprintf(d, sizeof d,
                "%d input reports, %d malformed, %d sequence gaps, %d timeouts; %zu output reports "
                "echoed by the firmware%s%s",
                count, bad, gaps, timeouts, rtt.count,
                first_problem.empty() ? "" : "; first problem: ", first_problem.c_str());
  // Gaps are reported, not judged here: a host that reads late loses input
  // reports by design (the device sends only the newest).
  result(p + "_stream", bad == 0 && timeouts == 0 && rtt.count > 0, d);
  metric(p + "_input_gaps", gaps, "reports");
  metric(p + "_input_interval_p50", gap.p50, "us");
  metric(p + "_input_interval_p99", gap.p99, "us");
  metric(p + "_round_trip_p50", rtt.p50, "us");
  metric(p + "_round_trip_p99", rtt.p99, "us");
  metric(p + "_round_trip_max", rtt.max, "us");
  ::close(fd);
  return 0;
}
