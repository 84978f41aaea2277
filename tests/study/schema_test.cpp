// Issue 28: each shipped data/**/*.schema.json against the field table its reader reads with
// (json_input::ObjectSpec): the same properties, types, choices, bounds, lengths, sizes, required
// fields and closedness, so a schema and its reader cannot disagree.
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "adaptive/detail/calibration_fields.h"
#include "display/display_calibration.h"
#include "json/json_fields.h"

namespace fs = std::filesystem;
namespace ji = penumbra::json_input;
using nlohmann::json;

namespace {

const char* schema_type(ji::Type t) {
  switch (t) {
    case ji::Type::number: return "number";
    case ji::Type::integer: return "integer";
    case ji::Type::string: return "string";
    case ji::Type::boolean: return "boolean";
    case ji::Type::object: return "object";
    case ji::Type::array: return "array";
    case ji::Type::any: return "";
  }
  return "";
}

class Compare {
 public:
  std::vector<std::string> differences;

  void object(const json& schema, const ji::ObjectSpec& spec, const std::string& at) {
    std::set<std::string> in_schema, in_reader, required_schema, required_reader;
    if (schema.contains("properties"))
      for (const auto& [name, _] : schema["properties"].items()) in_schema.insert(name);
    for (const ji::Field& f : spec.fields) {
      in_reader.insert(f.name);
      if (f.required) required_reader.insert(f.name);
    }
    for (const auto& name : in_schema)
      if (!in_reader.count(name)) differ(at + name, "in the schema, not read by the reader");
    for (const auto& name : in_reader)
      if (!in_schema.count(name)) differ(at + name, "read by the reader, not in the schema");
    if (schema.contains("required"))
      for (const auto& name : schema["required"]) required_schema.insert(name.get<std::string>());
    if (required_schema != required_reader) differ(at + "(required)", "the schema's required fields differ from the reader's");
    const bool closed = schema.contains("additionalProperties") && schema["additionalProperties"] == false;
    if (closed != spec.closed)
      differ(at + "(additionalProperties)", spec.closed ? "the reader refuses unknown keys, the schema allows them"
                                                        : "the schema refuses unknown keys, the reader allows them");
    for (const ji::Field& f : spec.fields)
      if (schema.contains("properties") && schema["properties"].contains(f.name)) field(schema["properties"][f.name], f, at + f.name);
  }

  void field(const json& s, const ji::Field& f, const std::string& at) {
    if (f.constant) {
      if (!s.contains("const") || s["const"] != *f.constant) differ(at, "const differs");
      return;
    }
    // Types: a choice's enum stands for its type.
    std::set<std::string> want, have;
    if (f.type != ji::Type::any && f.choices.empty()) want.insert(schema_type(f.type));
    if (f.nullable) want.insert("null");
    if (s.contains("type")) {
      if (s["type"].is_string()) have.insert(s["type"].get<std::string>());
      else for (const auto& t : s["type"]) have.insert(t.get<std::string>());
    }
    if (want != have) differ(at, "type differs (schema " + s.value("type", json()).dump() + ")");
    std::vector<std::string> choices;
    if (s.contains("enum")) choices = s["enum"].get<std::vector<std::string>>();
    if (choices != f.choices) differ(at, "the choices differ (schema " + s.value("enum", json()).dump() + ")");
    bound(s, "minimum", "exclusiveMinimum", f.min, f.exclusive_min, at);
    bound(s, "maximum", "exclusiveMaximum", f.max, f.exclusive_max, at);
    size(s, "minLength", f.min_length, at);
    size(s, "maxLength", f.max_length, at);
    size(s, "minItems", f.min_items, at);
    size(s, "maxItems", f.max_items, at);
    if (f.items) {
      if (!s.contains("items")) differ(at, "the reader checks its items, the schema states none");
      else field(s["items"], *f.items, at + "[]");
    } else if (s.contains("items")) {
      differ(at, "the schema states its items, the reader does not check them");
    }
    if (f.object) object(s, *f.object, at + ".");
    else if (s.contains("properties")) differ(at, "the schema states its properties, the reader does not read them");
  }

 private:
  void differ(const std::string& at, const std::string& what) { differences.push_back(at + ": " + what); }
  void bound(const json& s, const char* inclusive, const char* exclusive, const std::optional<double>& value, bool is_exclusive,
             const std::string& at) {
    const char* key = is_exclusive ? exclusive : inclusive;
    const char* other = is_exclusive ? inclusive : exclusive;
    if (value) {
      if (!s.contains(key) || s[key].get<double>() != *value)
        differ(at, std::string(key) + " differs (reader " + ji::format_bound(*value) + ", schema " + s.value(key, json()).dump() + ")");
      if (s.contains(other)) differ(at, std::string("the schema has ") + other);
    } else if (s.contains(key) || s.contains(other)) {
      differ(at, std::string("the schema bounds it (") + key + "), the reader does not");
    }
  }
  void size(const json& s, const char* key, const std::optional<std::size_t>& value, const std::string& at) {
    if (value ? !s.contains(key) || s[key].get<std::size_t>() != *value : s.contains(key))
      differ(at, std::string(key) + " differs");
  }
};

json read(const fs::path& p) {
  std::ifstream in(p);
  return json::parse(in);
}

std::vector<std::string> compare(const fs::path& schema, const ji::ObjectSpec& spec) {
  Compare c;
  c.object(read(schema), spec, "");
  return c.differences;
}

const fs::path kData = PENUMBRA_DATA_DIR;

}  // namespace

TEST(Schemas, CalibrationSchemaIsItsReader) {
  EXPECT_EQ(compare(kData / "calibration" / "calibration.schema.json", penumbra::adaptive::calibration_fields()),
            std::vector<std::string>{});
}

TEST(Schemas, DisplayCalibrationSchemaIsItsReader) {
  EXPECT_EQ(compare(kData / "display" / "display-calibration.schema.json", penumbra::display::calibration_fields()),
            std::vector<std::string>{});
}

// Every shipped schema is compared above: a new one needs its reader's table here.
TEST(Schemas, EveryShippedSchemaIsCompared) {
  std::set<std::string> found;
  for (const auto& e : fs::recursive_directory_iterator(kData))
    if (e.path().filename().string().ends_with(".schema.json")) found.insert(fs::relative(e.path(), kData).generic_string());
  EXPECT_EQ(found, (std::set<std::string>{"calibration/calibration.schema.json", "display/display-calibration.schema.json"}));
}

// The comparison itself finds what differs.
TEST(Schemas, ComparisonFindsDifferences) {
  const ji::ObjectSpec spec{{{.name = "a", .type = ji::Type::number, .required = true, .min = 0, .max = 1},
                             {.name = "b", .type = ji::Type::string, .choices = {"x", "y"}}}};
  Compare same;
  same.object(json::parse(R"({"required": ["a"], "additionalProperties": false, "properties": {
                  "a": {"type": "number", "minimum": 0, "maximum": 1}, "b": {"enum": ["x", "y"]}}})"),
              spec, "");
  EXPECT_EQ(same.differences, std::vector<std::string>{});
  Compare other;
  other.object(json::parse(R"({"properties": {"a": {"type": "integer", "minimum": 0, "exclusiveMaximum": 1},
                                                "c": {"type": "string"}}})"),
               spec, "");
  EXPECT_EQ(other.differences,
            (std::vector<std::string>{"c: in the schema, not read by the reader", "b: read by the reader, not in the schema",
                                      "(required): the schema's required fields differ from the reader's",
                                      "(additionalProperties): the reader refuses unknown keys, the schema allows them",
                                      "a: type differs (schema \"integer\")",
                                      "a: maximum differs (reader 1, schema null)", "a: the schema has exclusiveMaximum"}));
}
