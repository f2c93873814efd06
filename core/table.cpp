#include "core/table.hpp"

#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>

#include "core/atomic_file.hpp"
#include "core/errors.hpp"

namespace tg {

int Table::find(const std::string& name) const {
  for (size_t c = 0; c < cols_.size(); ++c)
    if (cols_[c].name == name) return static_cast<int>(c);
  return -1;
}

void Table::add(std::string name, std::vector<double> values) {
  if (!cols_.empty() && static_cast<int64_t>(values.size()) != rows())
    throw UsageError("column '" + name + "' has " + std::to_string(values.size()) + " rows, table has " +
                     std::to_string(rows()));
  if (has(name)) throw UsageError("duplicate column '" + name + "'");
  cols_.push_back(Column{std::move(name), std::move(values), {}, false});
}

void Table::add_text(std::string name, std::vector<std::string> values) {
  if (!cols_.empty() && static_cast<int64_t>(values.size()) != rows())
    throw UsageError("column '" + name + "' has " + std::to_string(values.size()) + " rows, table has " +
                     std::to_string(rows()));
  if (has(name)) throw UsageError("duplicate column '" + name + "'");
  cols_.push_back(Column{std::move(name), {}, std::move(values), true});
}

const std::vector<double>& Table::num(const std::string& name) const {
  const int c = find(name);
  if (c < 0) throw InputError(source + ": missing column '" + name + "'");
  if (cols_[c].is_text) throw InputError(source + ": column '" + name + "' is not numeric");
  return cols_[c].num;
}

const std::vector<std::string>& Table::text(const std::string& name) const {
  const int c = find(name);
  if (c < 0) throw InputError(source + ": missing column '" + name + "'");
  if (!cols_[c].is_text) throw InputError(source + ": column '" + name + "' is not text");
  return cols_[c].text;
}

void RowTable::row(std::initializer_list<Cell> cells) {
  if (cells.size() != names_.size())
    throw UsageError("table row has " + std::to_string(cells.size()) + " values for " + std::to_string(names_.size()) +
                     " columns");
  size_t c = 0;
  for (const Cell& v : cells) {
    Column& col = cols_[c++];
    if (rows_ == 0) col.is_text = v.is_text;
    if (v.is_text != col.is_text) throw UsageError("column '" + names_[c - 1] + "' mixes text and numbers");
    if (v.is_text) col.text.push_back(v.text);
    else col.num.push_back(v.num);
  }
  ++rows_;
}

Table RowTable::table() const {
  Table t;
  for (size_t c = 0; c < cols_.size(); ++c) {
    if (cols_[c].is_text) t.add_text(names_[c], cols_[c].text);
    else t.add(names_[c], cols_[c].num);
  }
  return t;
}

namespace {

void append_number(std::string& out, double v) {
  if (std::isnan(v)) { out += "nan"; return; }
  if (std::isinf(v)) { out += v > 0 ? "inf" : "-inf"; return; }
  char buf[32];
  auto r = std::to_chars(buf, buf + sizeof buf, v);
  out.append(buf, r.ptr);
}

bool parse_number(std::string_view s, double& v) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  if (s.empty()) return false;
  if (s.front() == '+') s.remove_prefix(1);
  auto r = std::from_chars(s.data(), s.data() + s.size(), v);
  return r.ec == std::errc() && r.ptr == s.data() + s.size();
}

// RFC 4180 quoting: a text cell holding a comma, a quote, a line break or
// edge white space is written between double quotes, with inner quotes
// doubled, so a stage name or a path with a comma reads back as one cell.
void append_text(std::string& out, const std::string& cell) {
  const bool quote = cell.find_first_of(",\"\n\r") != std::string::npos ||
                     (!cell.empty() && (cell.front() == ' ' || cell.front() == '\t' || cell.back() == ' ' ||
                                        cell.back() == '\t' || cell.front() == '#'));
  if (!quote) {
    out += cell;
    return;
  }
  out += '"';
  for (char ch : cell) {
    if (ch == '"') out += '"';
    out += ch;
  }
  out += '"';
}

// One CSV record from `text` at `pos` (advanced past its line break): cells
// trimmed of edge white space unless quoted; quoted cells may hold commas,
// doubled quotes and line breaks. `lines` counts the line breaks consumed.
std::vector<std::string> next_record(const std::string& text, size_t& pos, int64_t& lines, const std::string& source) {
  std::vector<std::string> cells;
  std::string cur;
  bool quoted = false, was_quoted = false;
  const int64_t first_line = lines + 1;
  auto finish_cell = [&] {
    if (!was_quoted) {
      const auto b = cur.find_first_not_of(" \t"), e = cur.find_last_not_of(" \t");
      cur = b == std::string::npos ? "" : cur.substr(b, e - b + 1);
    }
    cells.push_back(std::move(cur));
    cur.clear();
    was_quoted = false;
  };
  while (pos < text.size()) {
    const char ch = text[pos++];
    if (quoted) {
      if (ch == '"' && pos < text.size() && text[pos] == '"') {
        cur += '"';
        ++pos;
      } else if (ch == '"') {
        quoted = false;
      } else {
        if (ch == '\n') ++lines;
        cur += ch;
      }
    } else if (ch == '"' && cur.find_first_not_of(" \t") == std::string::npos) {
      cur.clear();
      quoted = was_quoted = true;
    } else if (ch == ',') {
      finish_cell();
    } else if (ch == '\n') {
      ++lines;
      finish_cell();
      return cells;
    } else if (ch != '\r') {
      cur += ch;
    }
  }
  if (quoted) throw InputError(source + ":" + std::to_string(first_line) + ": quoted cell never closed");
  finish_cell();
  return cells;
}

}  // namespace

std::string to_csv(const Table& t) {
  std::string out;
  const auto& cols = t.columns();
  for (size_t c = 0; c < cols.size(); ++c) out += (c ? "," : "") + cols[c].name;
  out += '\n';
  for (int64_t r = 0; r < t.rows(); ++r) {
    for (size_t c = 0; c < cols.size(); ++c) {
      if (c) out += ',';
      if (cols[c].is_text) append_text(out, cols[c].text[r]);
      else append_number(out, cols[c].num[r]);
    }
    out += '\n';
  }
  return out;
}

void write_csv(const Table& t, const std::filesystem::path& path) { write_file_atomic(path, to_csv(t)); }

Table parse_csv(const std::string& text, const std::string& source, const std::vector<std::string>& required) {
  size_t pos = 0;
  int64_t lineno = 0;
  // Blank lines and lines starting with '#' are skipped (comments).
  auto skip = [&](const std::vector<std::string>& row, size_t start) {
    return (row.size() == 1 && row[0].empty() && text[start] != '"') || text[start] == '#';
  };
  std::vector<std::string> header;
  while (pos < text.size() && header.empty()) {
    const size_t start = pos;
    auto row = next_record(text, pos, lineno, source);
    if (!skip(row, start)) header = std::move(row);
  }
  if (header.empty()) throw InputError(source + ": empty file, expected a CSV header line");
  for (size_t c = 0; c < header.size(); ++c) {
    if (header[c].empty()) throw InputError(source + ":" + std::to_string(lineno) + ": empty column name");
    for (size_t d = 0; d < c; ++d)
      if (header[d] == header[c]) throw InputError(source + ": duplicate column '" + header[c] + "'");
  }
  std::vector<std::vector<std::string>> cells(header.size());
  while (pos < text.size()) {
    const size_t start = pos;
    const int64_t line = lineno + 1;
    auto row = next_record(text, pos, lineno, source);
    if (skip(row, start)) continue;
    if (row.size() != header.size())
      throw InputError(source + ":" + std::to_string(line) + ": " + std::to_string(row.size()) +
                       " cells, header has " + std::to_string(header.size()));
    for (size_t c = 0; c < row.size(); ++c) cells[c].push_back(std::move(row[c]));
  }
  Table t;
  t.source = source;
  for (size_t c = 0; c < header.size(); ++c) {
    std::vector<double> nums(cells[c].size());
    bool numeric = true;
    for (size_t r = 0; r < cells[c].size() && numeric; ++r) numeric = parse_number(cells[c][r], nums[r]);
    if (numeric) t.add(header[c], std::move(nums));
    else t.add_text(header[c], std::move(cells[c]));
  }
  for (const auto& name : required) {
    const int c = t.find(name);
    if (c < 0) throw InputError(source + ": missing column '" + name + "'");
    if (t.columns()[c].is_text) {
      // Name the first bad cell so the user can find it.
      const auto& col = t.columns()[c].text;
      for (size_t r = 0; r < col.size(); ++r) {
        double v;
        if (!parse_number(col[r], v))
          throw InputError(source + ": column '" + name + "', data row " + std::to_string(r + 1) + ": '" + col[r] +
                           "' is not a number");
      }
    }
  }
  return t;
}

Table read_csv(const std::filesystem::path& path, const std::vector<std::string>& required) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw InputError(path.string() + ": cannot open");
  std::ostringstream ss;
  ss << f.rdbuf();
  return parse_csv(ss.str(), path.string(), required);
}

}  // namespace tg
