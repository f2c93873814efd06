#include "core/table.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <random>

#include "core/errors.hpp"

namespace tg {

TEST(Table, CsvRoundTripIsExact) {
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> u(-1e6, 1e6);
  std::vector<double> a(100), b(100);
  for (int i = 0; i < 100; ++i) { a[i] = u(rng) * std::pow(10.0, i % 30 - 15); b[i] = i; }
  Table t;
  t.add("x_m", a);
  t.add("id", b);
  t.add_text("kind", std::vector<std::string>(100, "grain"));
  const auto dir = std::filesystem::temp_directory_path() / "tg_table_test";
  std::filesystem::create_directories(dir);
  write_csv(t, dir / "t.csv");
  const Table r = read_csv(dir / "t.csv", {"x_m", "id"});
  ASSERT_EQ(r.rows(), 100);
  for (int i = 0; i < 100; ++i) {
    EXPECT_EQ(r.num("x_m")[i], a[i]);  // bit-exact: shortest round-trip form
    EXPECT_EQ(r.num("id")[i], i);
  }
  EXPECT_EQ(r.text("kind")[5], "grain");
  std::filesystem::remove_all(dir);
}

TEST(Table, ErrorsNameFileLineAndColumn) {
  try {
    parse_csv("x_m,y_m\n1,2\n3\n", "p.csv");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "p.csv:3: 1 cells, header has 2");
  }
  try {
    parse_csv("x_m,y_m\n1,2\n", "p.csv", {"r_m"});
    FAIL();
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "p.csv: missing column 'r_m'");
  }
  try {
    parse_csv("r_m\n1\nabc\n", "p.csv", {"r_m"});
    FAIL();
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "p.csv: column 'r_m', data row 2: 'abc' is not a number");
  }
  EXPECT_THROW(parse_csv("", "e.csv"), InputError);
}

TEST(Table, NanIsParsedForCallersToCheck) {
  const Table t = parse_csv("r_m\nnan\n1e-3\n", "p.csv", {"r_m"});
  EXPECT_TRUE(std::isnan(t.num("r_m")[0]));
  EXPECT_EQ(t.num("r_m")[1], 1e-3);
}

TEST(Table, MismatchedColumnLengthIsRejected) {
  Table t;
  t.add("a", {1, 2});
  EXPECT_THROW(t.add("b", {1}), UsageError);
  EXPECT_THROW(t.add("a", {1, 2}), UsageError);
}

TEST(Table, TextCellsWithCommasQuotesAndBreaksRoundTrip) {
  // RFC 4180: such cells are quoted, inner quotes doubled; the reader undoes it.
  const std::vector<std::string> names{"stage 1, 4.4 %", "say \"hi\"", "two\nlines", " edge ", "#not a comment", "",
                                       "plain"};
  Table t;
  t.add_text("name", names);
  t.add("v", {1, 2, 3, 4, 5, 6, 7});
  const std::string csv = to_csv(t);
  EXPECT_NE(csv.find("\"stage 1, 4.4 %\""), std::string::npos) << csv;
  EXPECT_NE(csv.find("\"say \"\"hi\"\"\""), std::string::npos) << csv;
  const Table r = parse_csv(csv, "mem.csv", {"v"});
  ASSERT_EQ(r.rows(), 7);
  EXPECT_EQ(r.text("name"), names);
  EXPECT_EQ(r.num("v")[6], 7);
}

TEST(Table, QuotedCellNeverClosedNamesTheLine) {
  try {
    parse_csv("a,b\n1,2\n\"open,3\n", "q.csv");
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("q.csv:3"), std::string::npos) << e.what();
  }
}

}  // namespace tg
