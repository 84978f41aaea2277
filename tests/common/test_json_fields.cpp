// The typed-field reader every JSON reader uses (common/json/json_fields.h): each kind of error in
// its one wording, and the extremes JSON allows.
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "json/json_fields.h"

namespace ji = penumbra::json_input;
using nlohmann::json;

namespace {

const ji::ObjectSpec& table() {
  static const ji::ObjectSpec spec{{
      {.name = "n", .type = ji::Type::number, .min = 0, .max = 1},
      {.name = "open", .type = ji::Type::number, .min = 0, .max = 180, .exclusive_min = true, .exclusive_max = true},
      {.name = "pos", .type = ji::Type::number, .min = 0, .exclusive_min = true},
      {.name = "c", .type = ji::Type::number, .min = 0.01, .max = 1000, .unit = "texels"},
      {.name = "i", .type = ji::Type::integer, .min = 1, .max = 10000},
      {.name = "u", .type = ji::Type::integer, .min = 0, .max = 2147483647},
      {.name = "big", .type = ji::Type::integer, .min = 0},
      {.name = "maybe", .type = ji::Type::number, .nullable = true, .min = 0, .max = 5},
      {.name = "b", .type = ji::Type::boolean},
      {.name = "s", .type = ji::Type::string, .max_length = 4},
      {.name = "ne", .type = ji::Type::string, .min_length = 1},
      {.name = "k", .type = ji::Type::string, .choices = {"disk", "grid", "poisson"}, .noun = "kernel"},
      {.name = "v", .type = ji::Type::integer, .constant = 2, .constant_note = "this version"},
      {.name = "req", .type = ji::Type::string, .required = true, .why = "every test needs it"},
      {.name = "xyz", .type = ji::Type::array, .min_items = 3, .max_items = 3, .items = ji::item({.type = ji::Type::number})},
      {.name = "list", .type = ji::Type::array, .min_items = 1, .max_items = 256,
       .items = ji::item({.type = ji::Type::object,
                          .object = ji::spec({{{.name = "level", .type = ji::Type::integer, .required = true, .min = 0, .max = 255},
                                               {.name = "deep", .type = ji::Type::object, .object = ji::spec({{
                                                   {.name = "pcf", .type = ji::Type::object, .object = ji::spec({{
                                                       {.name = "kernel", .type = ji::Type::string, .choices = {"disk"}, .noun = "kernel"}}})}}})}}})})},
      {.name = "any", .type = ji::Type::any},
      {.name = "anyarray", .type = ji::Type::array},
  }};
  return spec;
}

// The error of reading `text` (one field, all fields of the table read), or "ok".
std::string error(const std::string& text) {
  const ji::Reader r("f.json");
  try {
    const json j = ji::parse(text, "f.json");
    r.object(j, "", table());
    for (const ji::Field& f : table().fields) r.get(j, "", table(), f.name);
  } catch (const ji::JsonError& e) {
    return e.what();
  }
  return "ok";
}

std::string with(const std::string& fields) { return error(R"({"req": "x")" + (fields.empty() ? "" : ", " + fields) + "}"); }

}  // namespace

TEST(JsonFields, AcceptsWhatTheTableAllows) {
  EXPECT_EQ(with(""), "ok");
  EXPECT_EQ(with(R"("n": 0, "open": 1e-9, "pos": 5e-324, "c": 1000, "i": 10000, "u": 2147483647, "big": 18446744073709551615,
                    "maybe": null, "b": false, "s": "four", "ne": "x", "k": "poisson", "v": 2, "xyz": [1, 2.5, -3],
                    "list": [{"level": 0}, {"level": 255, "deep": {"pcf": {"kernel": "disk"}}}], "any": {"x": [null]})"),
            "ok");
  EXPECT_EQ(with(R"("v": 2.0)"), "f.json: v: expected 2 (this version), got 2.0");  // an integer constant
}

TEST(JsonFields, WrongType) {
  EXPECT_EQ(with(R"("n": "0.5")"), "f.json: n: expected a number, got \"0.5\"");
  EXPECT_EQ(with(R"("n": true)"), "f.json: n: expected a number, got true");
  EXPECT_EQ(with(R"("n": null)"), "f.json: n: expected a number, got null");
  EXPECT_EQ(with(R"("maybe": "x")"), "f.json: maybe: expected a number or null, got \"x\"");
  EXPECT_EQ(with(R"("i": 2.5)"), "f.json: i: expected an integer, got 2.5");
  EXPECT_EQ(with(R"("i": 2.0)"), "f.json: i: expected an integer, got 2.0");  // JSON's 2.0 is not an integer
  EXPECT_EQ(with(R"("i": 1e2)"), "f.json: i: expected an integer, got 100.0");
  EXPECT_EQ(with(R"("b": "yes")"), "f.json: b: expected true or false, got \"yes\"");
  EXPECT_EQ(with(R"("b": 1)"), "f.json: b: expected true or false, got 1");
  EXPECT_EQ(with(R"("s": 3)"), "f.json: s: expected a string, got 3");
  EXPECT_EQ(with(R"("xyz": {"a": 1})"), "f.json: xyz: expected an array of 3 numbers, got an object");
  EXPECT_EQ(with(R"("xyz": [1, "2", 3])"), "f.json: xyz[1]: expected a number, got \"2\"");
  EXPECT_EQ(with(R"("list": [7])"), "f.json: list[0]: expected an object, got 7");
  EXPECT_EQ(with(R"("any": 1, "anyarray": {})"), "f.json: anyarray: expected an array, got an object");
  EXPECT_EQ(error("[1, 2]"), "f.json: (top level): expected an object, got an array of 2 elements");
  EXPECT_EQ(error("\"x\""), "f.json: (top level): expected an object, got \"x\"");
}

TEST(JsonFields, OutOfRange) {
  EXPECT_EQ(with(R"("n": 1.5)"), "f.json: n: expected a number in [0, 1], got 1.5");
  EXPECT_EQ(with(R"("n": -0.0)"), "ok");
  EXPECT_EQ(with(R"("open": 180)"), "f.json: open: expected a number in (0, 180), got 180");
  EXPECT_EQ(with(R"("open": 0)"), "f.json: open: expected a number in (0, 180), got 0");
  EXPECT_EQ(with(R"("pos": -1)"), "f.json: pos: expected a positive number, got -1");
  EXPECT_EQ(with(R"("pos": 0)"), "f.json: pos: expected a positive number, got 0");
  EXPECT_EQ(with(R"("c": 1e308)"), "f.json: c: expected a number in [0.01, 1000] texels, got 1e+308");
  EXPECT_EQ(with(R"("c": 1e-300)"), "f.json: c: expected a number in [0.01, 1000] texels, got 1e-300");
  EXPECT_EQ(with(R"("i": 0)"), "f.json: i: expected an integer in [1, 10000], got 0");
  EXPECT_EQ(with(R"("i": -9223372036854775808)"), "f.json: i: expected an integer in [1, 10000], got -9223372036854775808");
  EXPECT_EQ(with(R"("u": 2147483648)"), "f.json: u: expected an integer in [0, 2147483647], got 2147483648");
  EXPECT_EQ(with(R"("u": -1)"), "f.json: u: expected an integer in [0, 2147483647], got -1");
  EXPECT_EQ(with(R"("u": 18446744073709551615)"), "f.json: u: expected an integer in [0, 2147483647], got 18446744073709551615");
  EXPECT_EQ(with(R"("big": -1)"), "f.json: big: expected a non-negative integer, got -1");
  // Beyond 2^64 a JSON integer is read as a double: no longer an integer.
  EXPECT_EQ(with(R"("big": 18446744073709551616)"), "f.json: big: expected an integer, got 1.8446744073709552e+19");
  EXPECT_EQ(with(R"("maybe": 6)"), "f.json: maybe: expected a number in [0, 5] or null, got 6");
  EXPECT_EQ(with(R"("v": 3)"), "f.json: v: expected 2 (this version), got 3");
  EXPECT_EQ(with(R"("v": "2")"), "f.json: v: expected 2 (this version), got \"2\"");
  EXPECT_EQ(with(R"("s": "fives")"), "f.json: s: expected a string of at most 4 bytes, got 5");
  EXPECT_EQ(with(R"("ne": "")"), "f.json: ne: expected a non-empty string, got \"\"");
  EXPECT_EQ(with(R"("list": [{"level": 256}])"), "f.json: list[0].level: expected an integer in [0, 255], got 256");
}

TEST(JsonFields, NotJsonNumbersAreRefusedByTheParser) {
  // NaN and infinity are not JSON; a number beyond a double overflows: json_input says so first.
  EXPECT_EQ(with(R"("n": NaN)").rfind("f.json:1:", 0), 0u);
  EXPECT_NE(with(R"("n": NaN)").find("malformed JSON"), std::string::npos);
  EXPECT_NE(with(R"("n": Infinity)").find("malformed JSON"), std::string::npos);
  EXPECT_NE(with(R"("n": 1e400)").find("malformed JSON: number overflow"), std::string::npos);
  EXPECT_EQ(with(R"("n": -1e400)").rfind("f.json:1:", 0), 0u);
}

TEST(JsonFields, BadChoice) {
  EXPECT_EQ(with(R"("k": "cone")"), "f.json: k: kernel 'cone': expected disk, grid or poisson");
  EXPECT_EQ(with(R"("k": 3)"), "f.json: k: kernel 3: expected disk, grid or poisson");
  EXPECT_EQ(with(R"("k": "Disk")"), "f.json: k: kernel 'Disk': expected disk, grid or poisson");
  EXPECT_EQ(with(R"("k": "a\nb")"), "f.json: k: kernel 'a\\x0ab': expected disk, grid or poisson");
  EXPECT_EQ(with(R"("list": [{"level": 1, "deep": {"pcf": {"kernel": "grid"}}}])"),
            "f.json: list[0].deep.pcf.kernel: kernel 'grid': expected disk");
}

TEST(JsonFields, MissingRequired) {
  EXPECT_EQ(error("{}"), "f.json: req: missing (every test needs it)");
  EXPECT_EQ(with(R"("list": [{"level": 1}, {}])"), "f.json: list[1].level: missing");
}

TEST(JsonFields, UnknownKey) {
  EXPECT_EQ(with(R"("list": [{"level": 1, "levle": 2}])"), "f.json: list[0].levle: unknown key (allowed: level, deep)");
  const std::string top = with(R"("colour": 1)");
  EXPECT_EQ(top.rfind("f.json: colour: unknown key (allowed: n, open, pos, c, i, u, big, maybe, b, s, ne, k, v, req, xyz, list, any, anyarray)", 0), 0u) << top;
  // A key's control bytes are escaped: the error stays one line.
  EXPECT_EQ(with("\"a\\nb\": 1").find('\n'), std::string::npos);
  EXPECT_EQ(ji::Reader::unknown_key(std::vector<std::string>{"shape", "radius"}, "for shape 'sphere'"),
            "unknown key for shape 'sphere' (allowed: shape, radius)");
  // An open object takes any other key.
  const ji::ObjectSpec open{{{.name = "a", .type = ji::Type::number}}, false};
  EXPECT_NO_THROW(ji::Reader("f.json").object(json{{"b", 1}}, "", open));
}

TEST(JsonFields, ArraySizes) {
  EXPECT_EQ(with(R"("xyz": [1, 2])"), "f.json: xyz: expected an array of 3 numbers, got an array of 2 elements");
  EXPECT_EQ(with(R"("xyz": [])"), "f.json: xyz: expected an array of 3 numbers, got an array of 0 elements");
  EXPECT_EQ(with(R"("list": [])"), "f.json: list: expected a non-empty array of at most 256 objects, got an array of 0 elements");
  std::string many = "[";
  for (int i = 0; i < 257; ++i) many += std::string(i ? ", " : "") + "{\"level\": 1}";
  EXPECT_EQ(with("\"list\": " + many + "]"), "f.json: list: expected a non-empty array of at most 256 objects, got an array of 257 elements");
}

TEST(JsonFields, DeepNestingAndLongValues) {
  // The path of a deep field; json_input's depth limit comes before any field is read.
  const std::string deep = with(R"("list": [{"level": 1, "deep": {"pcf": {"kernel": 1}}}])");
  EXPECT_EQ(deep, "f.json: list[0].deep.pcf.kernel: kernel 1: expected disk");
  std::string nested(70, '[');
  nested += std::string(70, ']');
  EXPECT_NE(error(nested).find("nested deeper than 64 levels"), std::string::npos);
  // A long value is shortened in the error.
  const std::string long_value = with("\"s\": \"" + std::string(1000, 'x') + "\"");
  EXPECT_LT(long_value.size(), 200u) << long_value;
  EXPECT_LT(with("\"n\": \"" + std::string(100000, 'y') + "\"").size(), 200u);
}

TEST(JsonFields, TypedGetters) {
  const ji::Reader r("f.json");
  const json j = ji::parse(R"({"req": "x", "n": 0.25, "i": 7, "b": true, "big": 18446744073709551615, "maybe": null})", "f.json");
  EXPECT_DOUBLE_EQ(r.number(j, "", table(), "n", 9), 0.25);
  EXPECT_DOUBLE_EQ(r.number(j, "", table(), "open", 9), 9);  // absent: the default
  EXPECT_DOUBLE_EQ(r.number(j, "", table(), "maybe", 3), 3);  // null where nullable: the default
  EXPECT_EQ(r.integer(j, "", table(), "i", 1), 7);
  EXPECT_EQ(r.unsigned_integer(j, "", table(), "big"), 18446744073709551615ull);
  EXPECT_TRUE(r.boolean(j, "", table(), "b"));
  EXPECT_EQ(r.string(j, "", table(), "s", "dflt"), "dflt");
  EXPECT_EQ(r.string(j, "", table(), "req"), "x");
  EXPECT_THROW(r.get(j, "", table(), "no-such-field"), std::logic_error);  // a reader's own mistake
}
