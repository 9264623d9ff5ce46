#pragma once
// Reading recorded LCM logs (lcm-logger files): one joint's SLAVE_STATE stream
// matched with SLAVE_TRUTH by seq, as plain vectors, for `tsm convert`,
// `tsm fit` and `tsm gap`. Independent of the estimator library on purpose
// (bridge depends only on lcmtypes); the caller builds its own Recording.

#include <cstdint>
#include <filesystem>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "bridge/link_auth.hpp"
#include "bridge/log_events.hpp"

namespace tsmh::bridge {

/// A log that cannot be used. what() is "FILE: DETAIL"; DETAIL names, where
/// it applies, the event number, channel, joint and field.
class LogError : public std::runtime_error {
 public:
  LogError(const std::string& file, const std::string& detail)
      : std::runtime_error(file + ": " + detail), file_(file), detail_(detail) {}
  const std::string& file() const noexcept { return file_; }
  const std::string& detail() const noexcept { return detail_; }

 private:
  std::string file_;
  std::string detail_;
};

/// True when the file starts with LCM's log event sync word (0xEDA1DA01).
bool is_lcm_log(const std::filesystem::path& path);

struct JointSeries {
  std::string source;  ///< the log file
  int joint = 0;
  std::string prefix;
  double radius_m = 0;           ///< from SLAVE_STATE radius_m[joint] (constant over the log)
  std::vector<double> t;         ///< s, from utime, relative to the first row; strictly increasing
  std::vector<double> x_in;      ///< rad
  std::vector<double> x_out;     ///< rad; empty when any row had NaN (joint without encoder)
  std::vector<double> T1, T3;    ///< N
  std::vector<double> tau_out;   ///< N m from SLAVE_TRUTH; empty when the log has none
  std::int64_t first_utime = 0;  ///< utime of row 0, µs (CLOCK_MONOTONIC of the slave)

  // What was read and what was left out, for the user.
  std::size_t state_messages = 0;   ///< SLAVE_STATE events on the channel
  std::size_t truth_messages = 0;   ///< SLAVE_TRUTH events on the channel
  std::size_t skipped_invalid = 0;  ///< undecodable, wrong joint count, NaN/Inf
  std::size_t skipped_not_increasing =
      0;  ///< utime not after the previous row (duplicates, reordering)
  std::size_t rows_without_truth =
      0;             ///< dropped because SLAVE_TRUTH was present but not for this seq
  LogDamage damage;  ///< truncation / corrupt regions (only with accept_damage)
  /// Events of the two channels left out because LogReadOptions::verify_key
  /// was given and they had no MAC trailer, or one that does not verify.
  std::size_t skipped_no_mac = 0;
  std::size_t skipped_bad_mac = 0;
  /// verify_key was given but no event of the two channels carries a MAC (a
  /// log recorded before authentication, or from unkeyed senders): read
  /// unverified, as without a key. The caller says so.
  bool no_macs = false;

  std::size_t rows() const noexcept { return t.size(); }
};

struct LogReadOptions {
  /// Use the intact events of a log that is cut off or has corrupt regions
  /// (JointSeries::damage says what was lost) instead of refusing it.
  bool accept_damage = false;
  /// Authenticated logs (docs/bridge.md, "Authentication"): with a key, only
  /// events whose MAC verifies with it are used (the others are counted in
  /// skipped_no_mac / skipped_bad_mac) unless no event has a MAC at all
  /// (JointSeries::no_macs); with skip_mac, trailers are stripped
  /// unverified. With neither, a log whose events carry MACs is an error
  /// (they would be used without anyone having checked them).
  const LinkKey* verify_key = nullptr;
  bool skip_mac = false;
};

/// Reads the channel `prefix`SLAVE_STATE (and `prefix`SLAVE_TRUTH) of `path`
/// and extracts joint `joint`. When the log has SLAVE_TRUTH, only rows with a
/// matching seq are kept (tau_out is required downstream). Throws LogError
/// when the file cannot be read, has no usable SLAVE_STATE on that channel
/// (the message lists the channels it found), the joint does not exist, or
/// the radius changes.
/// Every event header is validated before use (log_events.hpp); a
/// truncated or corrupt log is a LogError saying where and how many events
/// were lost, unless `options.accept_damage`.
JointSeries read_joint_series(const std::filesystem::path& path, int joint,
                              std::string_view prefix = {}, const LogReadOptions& options = {});
/// The same over the bytes of a log already in memory (`file` names it in
/// errors); what the fuzz target drives.
JointSeries read_joint_series(std::span<const std::uint8_t> bytes, const std::string& file,
                              int joint, std::string_view prefix = {},
                              const LogReadOptions& options = {});

}  // namespace tsmh::bridge
