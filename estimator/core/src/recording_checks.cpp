#include "estimator/recording_checks.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <cstdio>

#include "realtime/quantile.hpp"

namespace tsmh::estimator {
namespace {

constexpr std::array<std::string_view, 9> kContract = {"t",  "x_in", "tau_in", "tau_out", "x_out",
                                                       "T1", "T3",   "xd_in",  "xdd_in"};
// Columns our own writers add beside the contract's (virtual-slave
// --truth-columns, tsm simulate's output): known, ignored without a word.
constexpr std::array<std::string_view, 9> kOwnExtras = {
    "reference",     "x_out_true",  "T2", "T4",         "friction_true",
    "contact_force", "indentation", "F",  "tau_out_est"};

std::string folded(std::string_view w) {
  std::string out;
  for (const char c : w) {
    if (c == '_' || c == '-' || c == ' ') continue;
    out += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  }
  return out;
}

// Levenshtein with adjacent swaps counted once.
std::size_t distance(std::string_view a, std::string_view b) {
  std::vector<std::vector<std::size_t>> d(a.size() + 1, std::vector<std::size_t>(b.size() + 1));
  for (std::size_t i = 0; i <= a.size(); ++i)
    d[i][0] = i;
  for (std::size_t j = 0; j <= b.size(); ++j)
    d[0][j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    for (std::size_t j = 1; j <= b.size(); ++j) {
      d[i][j] = std::min(
          {d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + (a[i - 1] == b[j - 1] ? 0u : 1u)});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1])
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  }
  return d[a.size()][b.size()];
}

template <std::size_t N>
bool among(std::string_view w, const std::array<std::string_view, N>& names) {
  return std::find(names.begin(), names.end(), w) != names.end();
}

}  // namespace

std::string contract_column_for(std::string_view word) {
  if (among(word, kContract)) return {};
  const std::string w = folded(word);
  if (w == "time" || w == "times" || w == "timestamp" || w == "ts") return "t";
  for (const auto c : kContract) {
    // One letter off is a typo only for names long enough that one letter
    // does not make another word (x_in vs x_out differ by more).
    const std::string f = folded(c);
    if (w == f || (f.size() >= 4 && distance(w, f) <= 1)) return std::string(c);
  }
  return {};
}

std::vector<std::string> header_warnings(const Table& table) {
  std::vector<std::string> out;
  for (const auto& name : table.names) {
    if (among(std::string_view(name), kContract) || among(std::string_view(name), kOwnExtras))
      continue;
    const std::string meant = contract_column_for(name);
    if (!meant.empty()) {
      out.push_back("column '" + name + "' is not a column of the CSV contract; did you mean " +
                    meant + "?" +
                    (table.has(meant) ? "" : " (" + meant + " is absent, so it is not read)") +
                    "; '" + name + "' is ignored");
    } else {
      out.push_back("column '" + name +
                    "' is not a column of the CSV contract (t, x_in, tau_in, tau_out, x_out, T1, "
                    "T3, xd_in, xdd_in); ignored");
    }
  }
  return out;
}

std::string time_unit_warning(const std::vector<double>& t) {
  if (t.size() < 100) return {};
  std::vector<double> steps(t.size() - 1);
  for (std::size_t i = 1; i < t.size(); ++i)
    steps[i - 1] = t[i] - t[i - 1];
  const double median = realtime::median(std::move(steps));
  if (!(median >= 0.5)) return {};
  char b[400];
  std::snprintf(b, sizeof b,
                "the t column looks like milliseconds (or a finer unit); expected seconds: its "
                "median step is %.4g, which in seconds is a %.3g Hz recording over %.4g s (a "
                "1 kHz recording in milliseconds has steps of 1); divide t by 1000 if it is in ms",
                median, 1.0 / median, t.back() - t.front());
  return b;
}

}  // namespace tsmh::estimator
