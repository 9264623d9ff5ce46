#pragma once
// haptic-server's side of the drift alarm and the recalibration,
// on the main thread: it runs the identification the loop handed over
// (Recalibration::identify_pending, which allocates: never on the loop
// thread) and logs requests, results and drift alarms. Also keeps the
// events for the report.

#include <cstdarg>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "haptics/drift_advice.hpp"
#include "haptics/recalibration.hpp"
#include "realtime/joint_names.hpp"
#include "server_say.hpp"

namespace tsmh::haptic_server {

struct CalibrationEvent {
  double t_s;        ///< since the server started
  std::string kind;  ///< drift_alarm, drift_cleared, requested, applied, refused
  int joint;         ///< -1: every joint concerned
  double scale;      ///< drift: the scale the data ask for; applied: the new scale
  std::string detail;
  /// applied: the levels' scales sliding positive / negative; NaN otherwise.
  double scale_positive = std::numeric_limits<double>::quiet_NaN();
  double scale_negative = std::numeric_limits<double>::quiet_NaN();
};

class CalibrationLog {
 public:
  /// `live`: stderr carries the live status line, which each message clears.
  /// `advice`: what the drift warning may recommend; `paper_joints[j]`: joint
  /// j runs on the built-in `paper` preset (the warning names it as a cause).
  CalibrationLog(haptics::Recalibration& calib, std::int64_t start_ns, bool live,
                 haptics::DriftAdviceContext advice = {}, std::vector<bool> paper_joints = {})
      : calib_(calib),
        start_ns_(start_ns),
        live_(live),
        advice_(std::move(advice)),
        paper_joints_(std::move(paper_joints)) {}

  void poll(std::int64_t now_ns) {
    const double t = static_cast<double>(now_ns - start_ns_) * 1e-9;
    calib_.identify_pending();  // off the loop: the loop never waits for it
    const auto state = calib_.state();
    if (state != state_ && state == haptics::CalibrationState::kCollecting) {
      say("t = %.1f s: recalibration requested (joint mask 0x%x): move the instrument in free "
          "space for %.1f s",
          t, calib_.last_mask(), calib_.config().collect_s);
      events_.push_back({t, "requested", -1, 1.0, ""});
    }
    state_ = state;
    const auto results = calib_.results();
    if (results != results_) {
      results_ = results;
      report_result(t);
    }
    const auto alarms = calib_.drift_alarms();
    for (int j = 0; j < calib_.joints(); ++j) {
      const bool now = (alarms >> j) & 1U, was = (alarms_ >> j) & 1U;
      if (now && !was) {
        advice_.paper_preset =
            static_cast<std::size_t>(j) < paper_joints_.size() && paper_joints_[j];
        say("t = %.1f s: warning: %s", t,
            haptics::drift_advice(j, calib_.drift_scale(j), advice_).c_str());
        events_.push_back({t, "drift_alarm", j, calib_.drift_scale(j), ""});
      } else if (!now && was) {
        say("t = %.1f s: friction drift on %s cleared", t, realtime::joint_name(j).c_str());
        events_.push_back({t, "drift_cleared", j, calib_.drift_scale(j), ""});
      }
    }
    alarms_ = alarms;
  }

  const std::vector<CalibrationEvent>& events() const { return events_; }

 private:
  void report_result(double t) {
    const std::uint32_t mask = calib_.last_mask();
    if (calib_.state() == haptics::CalibrationState::kApplied) {
      for (int j = 0; j < calib_.joints(); ++j) {
        if (((mask >> j) & 1U) == 0) continue;
        const auto f = calib_.figures(j);
        say("t = %.1f s: recalibration applied: %s friction scale -> %.3f (sliding + %.3f, "
            "- %.3f; one common scale %.3f) (residual %.4f -> %.4f N m rms over %zu samples, one "
            "common scale %.4f; stroke %.2f rad); ramping in at %.2f/s",
            t, realtime::joint_name(j).c_str(), f.scale, f.scale_positive, f.scale_negative,
            f.scale_common, f.rms_old, f.rms_new, f.samples, f.rms_common, f.span_rad,
            calib_.config().ramp_per_s);
        events_.push_back({t, "applied", j, f.scale, "", f.scale_positive, f.scale_negative});
      }
      return;
    }
    const int j = calib_.reason_joint();
    const auto f = calib_.figures(j < 0 ? 0 : j);
    char detail[256];
    std::snprintf(detail, sizeof detail,
                  "%s (%s: stroke %.2f rad, sliding %.2f s each way, %d angle bins judged, "
                  "%zu samples, scale found %.3f, residual %.4f -> %.4f N m)",
                  std::string(to_string(calib_.reason())).c_str(),
                  realtime::joint_name(j < 0 ? 0 : j).c_str(), f.span_rad, f.sliding_s,
                  f.contact_bins, f.samples, f.scale, f.rms_old, f.rms_new);
    say("t = %.1f s: recalibration refused: %s; the model is unchanged", t, detail);
    events_.push_back({t, "refused", j, f.scale, std::string(to_string(calib_.reason()))});
  }

  __attribute__((format(printf, 2, 3))) void say(const char* fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    vsay(live_, fmt, ap);
    va_end(ap);
  }

  haptics::Recalibration& calib_;
  std::int64_t start_ns_;
  bool live_;
  haptics::DriftAdviceContext advice_;
  std::vector<bool> paper_joints_;
  haptics::CalibrationState state_ = haptics::CalibrationState::kIdle;
  std::uint64_t results_ = 0;
  std::uint32_t alarms_ = 0;
  std::vector<CalibrationEvent> events_;
};

}  // namespace tsmh::haptic_server
