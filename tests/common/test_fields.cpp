// text/fields.h: the one split of comma-separated lines and lists.
#include <gtest/gtest.h>

#include <stdexcept>
#include <string>
#include <vector>

#include <string>
#include <vector>

#include "text/csv_row.h"
#include "text/fields.h"

namespace penumbra::text {
namespace {

using V = std::vector<std::string>;

TEST(Fields, EmptyFieldsAreKeptAndNothingIsTrimmed) {
  EXPECT_EQ(split_fields("a,b,c"), (V{"a", "b", "c"}));
  EXPECT_EQ(split_fields("a,,b"), (V{"a", "", "b"}));
  EXPECT_EQ(split_fields("a,"), (V{"a", ""})) << "a trailing comma is an empty last field";
  EXPECT_EQ(split_fields(",a"), (V{"", "a"}));
  EXPECT_EQ(split_fields(""), (V{""})) << "an empty line is one empty field";
  EXPECT_EQ(split_fields(","), (V{"", ""}));
  EXPECT_EQ(split_fields(" a , b "), (V{" a ", " b "}));
  EXPECT_EQ(split_fields("1;2", ';'), (V{"1", "2"}));
  EXPECT_EQ(split_fields(std::string("a\0b,c", 5)), (V{std::string("a\0b", 3), "c"})) << "bytes pass as they are";
}

TEST(Fields, TrimRemovesSpacesTabsAndCarriageReturnsAtTheEnds) {
  EXPECT_EQ(trim("  a b\t\r"), "a b");
  EXPECT_EQ(trim(" \t\r "), "");
  EXPECT_EQ(trim(""), "");
  EXPECT_EQ(trim("x"), "x");
  EXPECT_EQ(trim("\na\n"), "\na\n") << "newlines are not a field's padding";
}

// The typed row every CSV reader checks its fields through: one wording for a wrong column count
// and for each kind of bad field, the bad value escaped.
TEST(CsvRow, OneWordingForEveryKindOfBadField) {
  const std::vector<std::string> names = {"level", "n", "task", "seed"};
  auto error = [&](const std::string& line, auto read) {
    try {
      const CsvRow row("data.csv", 7, names, split_fields(line));
      read(row);
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  auto all = [](const CsvRow& r) { (void)r.real(0), (void)r.integer(1, 0, 10), (void)r.one_of(2, {"2afc", "yesno"}), (void)r.unsigned_integer(3); };
  EXPECT_EQ(error("0.5,3,2afc,18446744073709551615", all), "no error");
  EXPECT_EQ(error("0.5,3,2afc", all), "data.csv:7: expected 4 columns, found 3");
  EXPECT_EQ(error("inf,3,2afc,1", all), "data.csv:7: column 'level': expected a finite number (found 'inf')");
  EXPECT_EQ(error(",3,2afc,1", all), "data.csv:7: column 'level': expected a finite number (found '')");
  EXPECT_EQ(error("1,11,2afc,1", all), "data.csv:7: column 'n': expected an integer in [0, 10] (found '11')");
  EXPECT_EQ(error("1,2.5,2afc,1", all), "data.csv:7: column 'n': expected an integer in [0, 10] (found '2.5')");
  EXPECT_EQ(error("1,2,2AFC,1", all), "data.csv:7: column 'task': expected 2afc|yesno (found '2AFC')");
  EXPECT_EQ(error("1,2,2afc,-1", all), "data.csv:7: column 'seed': expected an unsigned integer (found '-1')");
  EXPECT_EQ(error("1,2,2afc,18446744073709551616", all), "data.csv:7: column 'seed': expected an unsigned integer (found '18446744073709551616')");
  EXPECT_EQ(error("1,2,2afc,1\x01", all).find("data.csv:7: column 'seed': expected an unsigned integer (found '1"), 0u);
  try {
    CsvRow("levels.csv", 2, {"level", "correct"}, {"1"}, "level,correct");
    ADD_FAILURE() << "a short row was taken";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "levels.csv:2: expected 2 columns (level,correct), found 1");
  }
}

}  // namespace
}  // namespace penumbra::text
