// text/fields.h: the one split of comma-separated lines and lists.
#include <gtest/gtest.h>

#include <string>
#include <vector>

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

}  // namespace
}  // namespace penumbra::text
