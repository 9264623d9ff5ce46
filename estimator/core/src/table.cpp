#include "estimator/table.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <optional>
#include <sstream>
#include <system_error>

#include "estimator/atomic_file.hpp"
#include "files/input_file.hpp"

namespace tsmh::estimator {

std::string excerpt(std::string_view text, std::size_t max_chars) {
  std::string out;
  const std::size_t n = std::min(text.size(), max_chars);
  for (std::size_t i = 0; i < n; ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c == '\\' || c == '\'') {
      out += '\\';
      out += static_cast<char>(c);
    } else if (c >= 0x20 && c < 0x7f) {
      out += static_cast<char>(c);
    } else {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\x%02x", c);
      out += buf;
    }
  }
  if (text.size() > n) out += "... (" + std::to_string(text.size()) + " bytes)";
  return out;
}

namespace {

// A CSV line is at most this long; anything longer is not our data (a binary
// file, a line without newlines), and quoting it whole made a 300 MB error
// message.
constexpr std::size_t kMaxLineBytes = 1 << 20;

std::string describe(const std::string& file, long line, const std::string& column,
                     const std::string& what) {
  // Built with append(): GCC 12 warns falsely (-Wrestrict) on chained operator+.
  std::string s = file;
  if (line > 0) s.append(":").append(std::to_string(line));
  if (!column.empty()) s.append(": column '").append(excerpt(column)).append("'");
  s.append(": ").append(what);
  return s;
}

std::string_view trim(std::string_view s) {
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string_view::npos) return {};
  const auto e = s.find_last_not_of(" \t\r");
  return s.substr(b, e - b + 1);
}

std::vector<std::string_view> split(std::string_view line) {
  std::vector<std::string_view> out;
  std::size_t start = 0;
  while (true) {
    const auto comma = line.find(',', start);
    out.push_back(trim(line.substr(start, comma - start)));
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  return out;
}

}  // namespace

DataError::DataError(const std::string& file, long line, const std::string& column,
                     const std::string& what)
    : std::runtime_error(describe(file, line, column, what)),
      file_(file),
      line_(line),
      column_(column) {}

bool Table::has(const std::string& name) const {
  return std::find(names.begin(), names.end(), name) != names.end();
}

const std::vector<double>& Table::column(const std::string& name) const {
  const auto it = std::find(names.begin(), names.end(), name);
  if (it == names.end()) throw DataError(source, 0, name, "required column is missing");
  return columns[static_cast<std::size_t>(it - names.begin())];
}

void Table::set(const std::string& name, std::vector<double> values) {
  if (!columns.empty() && values.size() != rows())
    throw std::invalid_argument("Table::set: column '" + name + "' has the wrong length");
  const auto it = std::find(names.begin(), names.end(), name);
  if (it != names.end()) {
    columns[static_cast<std::size_t>(it - names.begin())] = std::move(values);
  } else {
    names.push_back(name);
    columns.push_back(std::move(values));
  }
}

namespace {

// Lines of a file, each at most kMaxLineBytes, read in chunks: a 1 GB file
// without a newline is refused after 1 MiB, not after reading it all.
class LineSource {
 public:
  explicit LineSource(files::InputFile& in) : in_(in) {}

  /// The next line without its '\n'; false at the end. `too_long` is set
  /// (and the line cut after kMaxLineBytes + 1 bytes) when it has no end in sight.
  bool next(std::string& line, bool& too_long) {
    line.clear();
    too_long = false;
    while (true) {
      if (pos_ == end_) {
        end_ = in_.read_some(buf_, sizeof buf_);
        pos_ = 0;
        if (end_ == 0) return !line.empty();
      }
      const char* start = buf_ + pos_;
      const auto* nl = static_cast<const char*>(std::memchr(start, '\n', end_ - pos_));
      const std::size_t n = nl ? static_cast<std::size_t>(nl - start) : end_ - pos_;
      line.append(start, n);
      pos_ += n + (nl ? 1 : 0);
      if (line.size() > kMaxLineBytes) {
        too_long = true;
        return true;
      }
      if (nl) return true;
    }
  }

 private:
  files::InputFile& in_;
  char buf_[65536];
  std::size_t pos_ = 0;
  std::size_t end_ = 0;
};

}  // namespace

Table read_csv_table(const std::filesystem::path& path) {
  const std::string file = path.string();
  // A regular file within the recording bound, opened without blocking: a
  // FIFO or a device is refused at once.
  std::optional<files::InputFile> input;
  try {
    input.emplace(path, files::kMaxRecordingBytes);
  } catch (const files::FileError& e) {
    throw DataError(file, 0, "", e.why());
  }
  LineSource in(*input);
  Table table;
  table.source = file;
  std::string line;
  long line_no = 0;
  bool have_header = false;
  bool too_long = false;
  while (true) {
    try {
      if (!in.next(line, too_long)) break;
    } catch (const files::FileError& e) {
      throw DataError(file, line_no + 1, "", e.why());
    }
    ++line_no;
    // A spreadsheet's UTF-8 byte-order mark: skipped, and said so.
    if (line_no == 1 && line.compare(0, 3, "\xEF\xBB\xBF") == 0) {
      line.erase(0, 3);
      table.notes.push_back(file + ": skipped the UTF-8 byte-order mark at the start of the file");
    }
    if (too_long)
      throw DataError(file, line_no, "",
                      "line is longer than " + std::to_string(kMaxLineBytes) +
                          " bytes: not a CSV line; it starts '" + excerpt(line) + "'");
    if (const auto nul = line.find('\0'); nul != std::string::npos)
      throw DataError(file, line_no, "",
                      "binary data (a NUL byte at column " + std::to_string(nul + 1) +
                          "): not a CSV file; the line starts '" + excerpt(line) + "'");
    const std::string_view view = trim(line);
    if (view.empty()) continue;
    if (view.front() == '#') {
      const std::string_view body = trim(view.substr(1));
      const auto colon = body.find(':');
      if (colon != std::string_view::npos && colon > 0 &&
          body.substr(0, colon).find(' ') == std::string_view::npos) {
        table.meta[std::string(trim(body.substr(0, colon)))] =
            std::string(trim(body.substr(colon + 1)));
      }
      continue;
    }
    const auto cells = split(view);
    if (!have_header) {
      for (const auto& c : cells) {
        if (c.empty()) throw DataError(file, line_no, "", "empty column name in the header");
        if (table.has(std::string(c)))
          throw DataError(file, line_no, std::string(c), "column name appears twice in the header");
        table.names.emplace_back(c);
      }
      table.columns.resize(table.names.size());
      have_header = true;
      continue;
    }
    if (cells.size() != table.names.size()) {
      throw DataError(file, line_no, "",
                      "expected " + std::to_string(table.names.size()) + " values, found " +
                          std::to_string(cells.size()));
    }
    for (std::size_t i = 0; i < cells.size(); ++i) {
      const auto cell = cells[i];
      double v = 0.0;
      const auto* first = cell.data();
      const auto* last = cell.data() + cell.size();
      if (!cell.empty() && *first == '+') ++first;
      const auto [ptr, ec] = std::from_chars(first, last, v);
      if (cell.empty() || ec != std::errc() || ptr != last) {
        throw DataError(file, line_no, table.names[i], "not a number: '" + excerpt(cell) + "'");
      }
      if (!std::isfinite(v)) {
        throw DataError(file, line_no, table.names[i],
                        "value is " + excerpt(cell) + " (not finite)");
      }
      table.columns[i].push_back(v);
    }
    table.line_of_row.push_back(line_no);
  }
  if (!have_header)
    throw DataError(file, 0, "", "no header line (the file is empty or all comments)");
  return table;
}

void write_csv_table(const Table& table, const std::filesystem::path& path) {
  for (const auto& c : table.columns) {
    if (c.size() != table.rows())
      throw std::invalid_argument("write_csv_table: columns of unequal length for " +
                                  path.string());
  }
  write_file_atomically(path, [&](std::ostream& out) {
    for (const auto& [k, v] : table.meta)
      out << "# " << k << ": " << v << '\n';
    for (std::size_t i = 0; i < table.names.size(); ++i)
      out << (i ? "," : "") << table.names[i];
    out << '\n';
    char buf[32];
    std::string row;
    for (std::size_t r = 0; r < table.rows(); ++r) {
      row.clear();
      for (std::size_t i = 0; i < table.columns.size(); ++i) {
        if (i) row += ',';
        const auto res = std::to_chars(buf, buf + sizeof buf, table.columns[i][r]);
        row.append(buf, res.ptr);
      }
      row += '\n';
      out << row;
    }
  });
}

}  // namespace tsmh::estimator
