#pragma once
// Typed fields of a parsed JSON document: the one way every reader of a file a person may have
// edited (scene files, study configs, session.json, calibration.json, display-calibration.json)
// checks a value's type, range and choice, a required field and an unknown key. A reader declares
// its objects as tables of Field; the same tables are compared with the shipped JSON schemas
// (tests/study/schema_test.cpp; the wordings: tests/common/test_json_fields.cpp, tests/study/json_readers_test.cpp), so a schema and its reader
// cannot disagree.
//
// Every error is one line "FILE: field.path: what", `what` in one wording per kind:
//   not an object / wrong type   expected an object, got 7
//                                expected a number, got "50"      (an integer, a string, true or false,
//                                                                  an array; "or null" where null is allowed)
//   out of range                 expected a number in [0, 1], got 1.5     ("(0, 180)": open bounds;
//                                expected an integer in [1, 10000], got 0  "a positive number": (0, inf))
//   bad choice                   pattern 'zigzag': expected stair or step
//   missing required field       missing                          ("missing (why)" where a reader says why)
//   unknown key                  unknown key (allowed: a, b, c)   ("unknown key for shape 'box' (...)")
//   array size                   expected an array of 2 to 4 items, got an array of 5 elements
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "json/json_input.h"

namespace penumbra::json_input {

enum class Type { any, number, integer, string, boolean, object, array };

struct Field;

// The keys an object may hold. `closed`: any other key is refused (additionalProperties false).
struct ObjectSpec {
  std::vector<Field> fields;
  bool closed = true;
  const Field* field(std::string_view name) const;
};

struct Field {
  std::string name;
  Type type = Type::any;
  bool required = false;
  bool nullable = false;  // null is read as absent
  std::string why;        // a required field's "missing (why)"
  // numbers and integers
  std::optional<double> min, max;
  bool exclusive_min = false, exclusive_max = false;
  std::string unit;  // after the range: "expected a number in [0.01, 1000] texels"
  std::optional<double> constant;  // "expected 2 (constant_note), got 3", before the type
  std::string constant_note;
  // strings
  std::vector<std::string> choices;  // the value must be one of these
  std::string noun;                  // names the value in a bad-choice error ("pattern 'zigzag': ...")
  std::optional<std::size_t> min_length, max_length;  // bytes
  // arrays
  std::optional<std::size_t> min_items, max_items;
  std::shared_ptr<const Field> items;  // each element's field (its name is not used)
  // objects (and arrays' object items): the nested keys
  std::shared_ptr<const ObjectSpec> object;
  std::string description;  // documentation only (not compared)
};

// The error every check throws: "FILE: field.path: what".
class FieldError : public JsonError {
 public:
  using JsonError::JsonError;
};

// How a wrong value is shown after "got": short, one line ("an object", "an array of 2 elements",
// "null", or the JSON text, shortened).
std::string describe(const nlohmann::json& v);
// A number field's type and range as its error says it ("a number in (0, 180)", "a positive number"),
// and whether `d` lies in that range: for a reader that converts the value (a float) and checks again.
std::string range_phrase(const Field& f);
bool number_in_range(double d, const Field& f);
// A bound as the errors show it: integers whole, others %g.
std::string format_bound(double d);

class Reader {
 public:
  explicit Reader(std::string file) : file_(std::move(file)) {}
  const std::string& file() const { return file_; }

  [[noreturn]] void fail(const std::string& path, const std::string& what) const;

  // `v` must be an object with no key outside `spec` (when spec.closed); the required fields must
  // be there. `context` follows "unknown key" ("for shape 'box'").
  void object(const nlohmann::json& v, const std::string& path, const ObjectSpec& spec, std::string_view context = {}) const;

  // The checked value of `name` in `obj` (its Field in `spec`), or nullptr when absent or null
  // where nullable. Arrays: each element checked against `items`.
  const nlohmann::json* get(const nlohmann::json& obj, const std::string& path, const ObjectSpec& spec,
                            std::string_view name) const;
  // The same for a field that is not in a table (a reader that states each field where it reads it).
  const nlohmann::json* get(const nlohmann::json& obj, const std::string& path, const Field& f) const;
  // One value against one field (type, range, choice, length, items; nested objects' keys).
  void check(const nlohmann::json& v, const std::string& path, const Field& f) const;

  // Typed values; `fallback` when absent.
  double number(const nlohmann::json& obj, const std::string& path, const ObjectSpec& spec, std::string_view name,
                double fallback = 0) const;
  std::int64_t integer(const nlohmann::json& obj, const std::string& path, const ObjectSpec& spec, std::string_view name,
                       std::int64_t fallback = 0) const;
  std::uint64_t unsigned_integer(const nlohmann::json& obj, const std::string& path, const ObjectSpec& spec,
                                 std::string_view name, std::uint64_t fallback = 0) const;
  bool boolean(const nlohmann::json& obj, const std::string& path, const ObjectSpec& spec, std::string_view name,
               bool fallback = false) const;
  std::string string(const nlohmann::json& obj, const std::string& path, const ObjectSpec& spec, std::string_view name,
                     const std::string& fallback = {}) const;

  // The one bad-choice wording, for readers whose choices come from elsewhere (a parse function).
  static std::string bad_choice(std::string_view noun, std::string_view value, std::span<const std::string> choices);
  // The one unknown-key wording.
  static std::string unknown_key(std::span<const std::string> allowed, std::string_view context = {});

 private:
  std::string file_;
};

// "a, b or c".
std::string or_list(std::span<const std::string> names);

// A shared field table from a list (for nested objects and array items).
std::shared_ptr<const ObjectSpec> spec(ObjectSpec s);
std::shared_ptr<const Field> item(Field f);

}  // namespace penumbra::json_input
