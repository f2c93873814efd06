// A column table for particle lists, packings, truth and histories: named
// columns of numbers (double) or text. Column names carry physical units
// (`volume_mm3`, `r_m`). CSV reading checks the header and every cell and
// throws InputError("FILE:LINE: problem"); writing is atomic.
#pragma once
#include <cstdint>
#include <filesystem>
#include <initializer_list>
#include <string>
#include <vector>

namespace tg {

struct Column {
  std::string name;
  std::vector<double> num;        // numeric column
  std::vector<std::string> text;  // text column (is_text)
  bool is_text = false;
  int64_t size() const { return is_text ? static_cast<int64_t>(text.size()) : static_cast<int64_t>(num.size()); }
};

class Table {
 public:
  int64_t rows() const { return cols_.empty() ? 0 : cols_.front().size(); }
  const std::vector<Column>& columns() const { return cols_; }
  bool has(const std::string& name) const { return find(name) >= 0; }
  int find(const std::string& name) const;

  // Adding a column whose length differs from the others is a UsageError.
  void add(std::string name, std::vector<double> values);
  void add_text(std::string name, std::vector<std::string> values);

  // Throws InputError("<source>: missing column 'name'") when absent.
  const std::vector<double>& num(const std::string& name) const;
  const std::vector<std::string>& text(const std::string& name) const;

  // Where the table came from, for error messages ("particles.csv").
  std::string source = "table";

 private:
  std::vector<Column> cols_;
};

// A table built row by row: the columns named once, then one call a row with
// the values in column order. A column is text when its first row's value is
// text, numeric otherwise; later rows must agree (UsageError).
//   RowTable t({"file", "step", "strain"});
//   t.row({"a.h5", 10, 0.01});
//   write_csv(t.table(), "index.csv");
class RowTable {
 public:
  struct Cell {
    Cell(double v) : num(v) {}
    Cell(int v) : num(v) {}
    Cell(int64_t v) : num(static_cast<double>(v)) {}
    Cell(size_t v) : num(static_cast<double>(v)) {}
    Cell(std::string v) : text(std::move(v)), is_text(true) {}
    Cell(const char* v) : text(v), is_text(true) {}
    double num = 0;
    std::string text;
    bool is_text = false;
  };
  explicit RowTable(std::vector<std::string> names) : names_(std::move(names)), cols_(names_.size()) {}
  void row(std::initializer_list<Cell> cells);
  Table table() const;

 private:
  std::vector<std::string> names_;
  std::vector<Column> cols_;
  int64_t rows_ = 0;
};

// Numbers are written in their shortest exact form (round-trip safe).
void write_csv(const Table& t, const std::filesystem::path& path);
std::string to_csv(const Table& t);

// Reads a CSV with a header line. A column is numeric when every cell parses
// as a number (nan/inf included: callers check their own ranges), else text.
// `required` columns must be present and numeric.
Table read_csv(const std::filesystem::path& path, const std::vector<std::string>& required = {});
Table parse_csv(const std::string& text, const std::string& source, const std::vector<std::string>& required = {});

}  // namespace tg
