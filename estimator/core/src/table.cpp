#include "estimator/table.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <system_error>

#include "estimator/atomic_file.hpp"

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

Table read_csv_table(const std::filesystem::path& path) {
  const std::string file = path.string();
  std::ifstream in(path);
  if (!in) throw DataError(file, 0, "", "cannot open for reading");
  Table table;
  table.source = file;
  std::string line;
  long line_no = 0;
  bool have_header = false;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.size() > kMaxLineBytes)
      throw DataError(file, line_no, "",
                      "line is " + std::to_string(line.size()) + " bytes long (at most " +
                          std::to_string(kMaxLineBytes) + "): not a CSV line; it starts '" +
                          excerpt(line) + "'");
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
  if (in.bad()) throw DataError(file, line_no, "", "read error");
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
