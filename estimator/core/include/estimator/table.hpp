#pragma once
// A table of named numeric columns, as read from or written to the CSV data
// contract (docs/data-formats.md). Reading validates every cell; writing is
// atomic (a temporary file renamed into place) so nothing is half-written.

#include <filesystem>
#include <map>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace tsmh::estimator {

/// At most `max_chars` of `text` for an error message, escaped (\xNN for
/// bytes outside printable ASCII, \' and \\) and marked when cut ("... (N
/// bytes)"): a 300 MB line or a binary file is never echoed whole.
std::string excerpt(std::string_view text, std::size_t max_chars = 60);

/// Bad input data. The message names the file, line and column at fault.
class DataError : public std::runtime_error {
 public:
  DataError(const std::string& file, long line, const std::string& column, const std::string& what);
  const std::string& file() const { return file_; }
  long line() const { return line_; }  ///< 1-based line in the file, 0 when not line-specific
  const std::string& column() const { return column_; }

 private:
  std::string file_;
  long line_;
  std::string column_;
};

struct Table {
  std::vector<std::string> names;            ///< column names, in file order
  std::vector<std::vector<double>> columns;  ///< columns[i] holds names[i]
  std::vector<long> line_of_row;             ///< file line of each row (for error messages)
  std::map<std::string, std::string> meta;   ///< "# key: value" comment lines
  std::string source;                        ///< file name, for error messages
  std::vector<std::string> notes;            ///< what reading tolerated (a byte-order mark)

  std::size_t rows() const { return columns.empty() ? 0 : columns.front().size(); }
  bool has(const std::string& name) const;
  /// The column called `name`; throws DataError naming the file when absent.
  const std::vector<double>& column(const std::string& name) const;
  /// Adds (or replaces) a column; its size must equal rows() unless the table is empty.
  void set(const std::string& name, std::vector<double> values);
};

/// Reads a CSV file: one header line, '#' comment lines anywhere ("# key: value"
/// becomes meta), every cell a finite number. Only a regular file of at most
/// files::kMaxRecordingBytes with lines of at most 1 MiB, checked while
/// reading; a leading UTF-8 byte-order mark is skipped (and noted). Throws
/// DataError.
Table read_csv_table(const std::filesystem::path& path);

/// Writes `table` as CSV with its meta as "# key: value" lines first. Values are
/// written with enough digits to round-trip. Atomic: writes PATH.tmp-* then
/// renames. Throws std::runtime_error on I/O failure (and leaves no file).
void write_csv_table(const Table& table, const std::filesystem::path& path);

}  // namespace tsmh::estimator
