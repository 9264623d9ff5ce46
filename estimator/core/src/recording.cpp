#include "estimator/recording.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <sstream>

#include "estimator/recording_checks.hpp"
#include "realtime/quantile.hpp"

namespace tsmh::estimator {
namespace {

std::optional<double> parse_radius(const Table& table) {
  const auto it = table.meta.find("radius_m");
  if (it == table.meta.end()) return std::nullopt;
  double v = 0.0;
  const auto& s = it->second;
  const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec != std::errc() || ptr != s.data() + s.size() || !std::isfinite(v))
    throw DataError(
        table.source, 0, "radius_m",
        "comment '# radius_m: " + excerpt(s) + "' is not a number; " + kRadiusRangeText);
  // 1e308 passed as "> 0" and simulate wrote -inf rows with exit 0.
  if (!(v >= kMinRadiusM && v <= kMaxRadiusM))
    throw DataError(
        table.source, 0, "radius_m",
        "comment '# radius_m: " + excerpt(s) + "' is out of range; " + kRadiusRangeText);
  return v;
}

std::vector<double> optional_column(const Table& table, const char* name) {
  return table.has(name) ? table.column(name) : std::vector<double>{};
}

// Finite and increasing is not enough: a last t of 1e300 gave a "fit" with no
// validation samples and RMSE NaN. Times beyond ~30 years, or one step longer
// than a minute and than 10^4 typical steps, are not a recording.
void check_time_column(const Table& table, const std::vector<double>& t) {
  constexpr double kMaxAbsTime = 1e9;  // s
  const auto line_of = [&](std::size_t i) {
    return i < table.line_of_row.size() ? table.line_of_row[i] : 0L;
  };
  for (std::size_t i = 0; i < t.size(); ++i) {
    if (std::fabs(t[i]) > kMaxAbsTime) {
      std::ostringstream what;
      what.precision(6);
      what << "time " << t[i] << " s is beyond " << kMaxAbsTime
           << " s (about 30 years): not a time in seconds";
      throw DataError(table.source, line_of(i), "t", what.str());
    }
  }
  if (t.size() < 3) return;
  std::vector<double> steps(t.size() - 1);
  for (std::size_t i = 1; i < t.size(); ++i)
    steps[i - 1] = t[i] - t[i - 1];
  const double median = realtime::median(steps);
  const double limit = std::max(60.0, 1e4 * median);
  for (std::size_t i = 0; i < steps.size(); ++i) {
    if (steps[i] > limit) {
      std::ostringstream what;
      what.precision(6);
      what << "time jumps by " << steps[i] << " s (from " << t[i] << " to " << t[i + 1]
           << "), more than a minute and 10^4 times the typical step of " << median
           << " s: not one recording";
      throw DataError(table.source, line_of(i + 1), "t", what.str());
    }
  }
}

}  // namespace

std::vector<double> Recording::measured_friction() const {
  std::vector<double> f(size());
  for (std::size_t i = 0; i < size(); ++i)
    f[i] = (tau_in[i] - tau_out[i]) / radius_m;
  return f;
}

Recording recording_from_table(const Table& table, std::optional<double> radius_override,
                               const RecordingRequirements& need) {
  Recording rec;
  rec.source = table.source;
  rec.notes = table.notes;
  if (radius_override) {
    if (!(*radius_override >= kMinRadiusM && *radius_override <= kMaxRadiusM))
      throw DataError(table.source, 0, "", std::string("--radius: ") + kRadiusRangeText);
    rec.radius_m = *radius_override;
  } else if (auto r = parse_radius(table)) {
    rec.radius_m = *r;
  }
  // A required column missing while a near-miss is there ("tauin", "time")
  // is named with it; the other header words are warned about.
  for (const char* required : {"t", "x_in"}) {
    if (table.has(required)) continue;
    for (const auto& name : table.names) {
      if (contract_column_for(name) == required)
        throw DataError(table.source, 0, required,
                        "required column is missing; the header has '" + name + "': did you mean " +
                            required + "?");
    }
  }
  rec.warnings = header_warnings(table);
  rec.t = table.column("t");
  rec.x_in = table.column("x_in");
  rec.tau_out = optional_column(table, "tau_out");
  rec.x_out = optional_column(table, "x_out");
  rec.T1 = optional_column(table, "T1");
  rec.T3 = optional_column(table, "T3");
  rec.xd_in = optional_column(table, "xd_in");
  rec.xdd_in = optional_column(table, "xdd_in");
  if (table.has("tau_in")) {
    rec.tau_in = table.column("tau_in");
  } else if (!rec.T1.empty() && !rec.T3.empty() && std::isfinite(rec.radius_m)) {
    rec.tau_in.resize(rec.size());
    for (std::size_t i = 0; i < rec.size(); ++i)
      rec.tau_in[i] = rec.radius_m * (rec.T1[i] - rec.T3[i]);
  }
  if (rec.xd_in.empty() != rec.xdd_in.empty()) {
    throw DataError(table.source, 0, rec.xd_in.empty() ? "xd_in" : "xdd_in",
                    "exact derivatives need both xd_in and xdd_in");
  }
  for (std::size_t i = 1; i < rec.size(); ++i) {
    if (!(rec.t[i] > rec.t[i - 1])) {
      const long line = i < table.line_of_row.size() ? table.line_of_row[i] : 0;
      std::ostringstream what;
      what.precision(17);
      what << "time is not strictly increasing (" << rec.t[i] << " after " << rec.t[i - 1] << ")";
      throw DataError(table.source, line, "t", what.str());
    }
  }
  if (rec.size() == 0)
    throw DataError(table.source, 0, "", "no data rows (the file has only a header)");
  check_time_column(table, rec.t);
  if (auto w = time_unit_warning(rec.t); !w.empty()) rec.warnings.push_back(std::move(w));
  check_requirements(rec, need);
  return rec;
}

void check_requirements(const Recording& rec, const RecordingRequirements& need) {
  if (need.radius && !(std::isfinite(rec.radius_m) && rec.radius_m > 0.0))
    throw DataError(rec.source, 0, "",
                    "no pulley radius: add '# radius_m: R' to the file or pass --radius");
  if (need.tau_in && !rec.has_tau_in())
    throw DataError(rec.source, 0, "tau_in",
                    "required column is missing (give tau_in, or T1 and T3 with a radius)");
  if (need.tau_out && !rec.has_tau_out())
    throw DataError(rec.source, 0, "tau_out",
                    "required column is missing (measured distal torque)");
}

Table recording_to_table(const Recording& rec) {
  Table table;
  table.source = rec.source;
  if (std::isfinite(rec.radius_m)) {
    char buf[32];
    const auto res = std::to_chars(buf, buf + sizeof buf, rec.radius_m);
    table.meta["radius_m"] = std::string(buf, res.ptr);
  }
  const auto add = [&](const char* name, const std::vector<double>& v) {
    if (!v.empty()) table.set(name, v);
  };
  add("t", rec.t);
  add("x_in", rec.x_in);
  add("tau_in", rec.tau_in);
  add("tau_out", rec.tau_out);
  add("x_out", rec.x_out);
  add("T1", rec.T1);
  add("T3", rec.T3);
  add("xd_in", rec.xd_in);
  add("xdd_in", rec.xdd_in);
  return table;
}

Recording read_recording_csv(const std::filesystem::path& path,
                             std::optional<double> radius_override,
                             const RecordingRequirements& need) {
  return recording_from_table(read_csv_table(path), radius_override, need);
}

void write_recording_csv(const Recording& rec, const std::filesystem::path& path) {
  write_csv_table(recording_to_table(rec), path);
}

}  // namespace tsmh::estimator
