#include "json/json_fields.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace penumbra::json_input {

using nlohmann::json;

const Field* ObjectSpec::field(std::string_view name) const {
  for (const Field& f : fields)
    if (f.name == name) return &f;
  return nullptr;
}

std::shared_ptr<const ObjectSpec> spec(ObjectSpec s) { return std::make_shared<const ObjectSpec>(std::move(s)); }
std::shared_ptr<const Field> item(Field f) { return std::make_shared<const Field>(std::move(f)); }

std::string describe(const json& v) {
  switch (v.type()) {
    case json::value_t::object: return "an object";
    case json::value_t::array: return "an array of " + std::to_string(v.size()) + " element" + (v.size() == 1 ? "" : "s");
    case json::value_t::null: return "null";
    default: break;
  }
  return printable(dump(v), 60);
}

std::string format_bound(double d) {
  char b[32];
  if (d == std::trunc(d) && std::abs(d) < 1e15) std::snprintf(b, sizeof b, "%.0f", d);
  else std::snprintf(b, sizeof b, "%g", d);
  return b;
}

std::string or_list(std::span<const std::string> names) {
  std::string s;
  for (std::size_t i = 0; i < names.size(); ++i)
    s += (i == 0 ? "" : i + 1 == names.size() ? " or " : ", ") + names[i];
  return s;
}

namespace {

const char* plural(Type t) {
  switch (t) {
    case Type::number: return "numbers";
    case Type::integer: return "integers";
    case Type::string: return "strings";
    case Type::object: return "objects";
    case Type::boolean: return "booleans";
    default: return "elements";
  }
}

// "an array of 3 numbers", "a non-empty array of at most 256 objects", ...
std::string array_phrase(const Field& f) {
  const char* what = f.items ? plural(f.items->type) : "elements";
  const std::size_t lo = f.min_items.value_or(0);
  if (lo == 0 && !f.max_items) return f.items ? std::string("an array of ") + what : "an array";
  if (f.max_items && lo == *f.max_items) return "an array of " + std::to_string(lo) + " " + what;
  std::string s = lo == 1 ? "a non-empty array of " : "an array of ";
  if (lo > 1) s += "at least " + std::to_string(lo) + (f.max_items ? " and " : " ");
  if (f.max_items) s += "at most " + std::to_string(*f.max_items) + " ";
  return s + what;
}

// The bare type: "a number", "an integer or null", "an array of 3 numbers".
std::string type_phrase(const Field& f) {
  std::string s;
  switch (f.type) {
    case Type::number: s = "a number"; break;
    case Type::integer: s = "an integer"; break;
    case Type::string: s = "a string"; break;
    case Type::boolean: s = "true or false"; break;
    case Type::object: s = "an object"; break;
    case Type::array: s = array_phrase(f); break;
    case Type::any: s = "a value"; break;
  }
  return f.nullable ? s + " or null" : s;
}

// The type with its range: "a number in [0, 1]", "a positive number", "an integer in [1, 10000]".
}  // namespace

std::string range_phrase(const Field& f) {
  const bool integer = f.type == Type::integer;
  const std::string noun = integer ? "integer" : "number";
  std::string s;
  if (f.min && f.max) {
    s = std::string(integer ? "an " : "a ") + noun + " in " + (f.exclusive_min ? "(" : "[") + format_bound(*f.min) + ", " +
        format_bound(*f.max) + (f.exclusive_max ? ")" : "]");
  } else if (f.min && *f.min == 0) {
    s = std::string("a ") + (f.exclusive_min ? "positive " : "non-negative ") + noun;
  } else if (f.min) {
    s = std::string(integer ? "an " : "a ") + noun + (f.exclusive_min ? " > " : " >= ") + format_bound(*f.min);
  } else if (f.max) {
    s = std::string(integer ? "an " : "a ") + noun + (f.exclusive_max ? " < " : " <= ") + format_bound(*f.max);
  } else {
    s = std::string(integer ? "an " : "a ") + noun;
  }
  if (!f.unit.empty()) s += " " + f.unit;
  return f.nullable ? s + " or null" : s;
}

namespace {

bool has_type(const json& v, Type t) {
  switch (t) {
    case Type::number: return v.is_number();
    case Type::integer: return v.is_number_integer();
    case Type::string: return v.is_string();
    case Type::boolean: return v.is_boolean();
    case Type::object: return v.is_object();
    case Type::array: return v.is_array();
    case Type::any: return true;
  }
  return false;
}

// Whether a JSON integer lies in [min, max] (exclusive where said), without the rounding of a
// conversion to double for huge values.
bool integer_in_range(const json& v, const Field& f) {
  if (v.is_number_unsigned()) {
    const std::uint64_t u = v.get<std::uint64_t>();
    if (f.max && (static_cast<double>(u) > *f.max || (f.exclusive_max && static_cast<double>(u) >= *f.max))) return false;
    if (f.max && *f.max < 1.8e19 && u > static_cast<std::uint64_t>(*f.max)) return false;
    if (f.min && (f.exclusive_min ? static_cast<double>(u) <= *f.min : static_cast<double>(u) < *f.min)) return false;
    return true;
  }
  const std::int64_t i = v.get<std::int64_t>();
  const double d = static_cast<double>(i);
  if (f.min && (f.exclusive_min ? d <= *f.min : d < *f.min)) return false;
  if (f.max && (f.exclusive_max ? d >= *f.max : d > *f.max)) return false;
  return true;
}

}  // namespace

bool number_in_range(double d, const Field& f) {
  if (f.min && !(f.exclusive_min ? d > *f.min : d >= *f.min)) return false;
  if (f.max && !(f.exclusive_max ? d < *f.max : d <= *f.max)) return false;
  return true;
}

std::string Reader::bad_choice(std::string_view noun, std::string_view value, std::span<const std::string> choices) {
  return std::string(noun) + " '" + printable(value, 60) + "': expected " + or_list(choices);
}

std::string Reader::unknown_key(std::span<const std::string> allowed, std::string_view context) {
  std::string list;
  for (const std::string& a : allowed) list += (list.empty() ? "" : ", ") + a;
  return "unknown key" + (context.empty() ? std::string() : " " + std::string(context)) + " (allowed: " + list + ")";
}

void Reader::fail(const std::string& path, const std::string& what) const {
  throw FieldError(file_ + ": " + (path.empty() ? "(top level)" : path) + ": " + what);
}

void Reader::object(const json& v, const std::string& path, const ObjectSpec& spec, std::string_view context) const {
  if (!v.is_object()) fail(path, "expected an object, got " + describe(v));
  if (spec.closed)
    for (auto it = v.begin(); it != v.end(); ++it)
      if (!spec.field(it.key())) {
        std::vector<std::string> allowed;
        for (const Field& f : spec.fields) allowed.push_back(f.name);
        fail(child(path, printable(it.key(), 60)), unknown_key(allowed, context));
      }
  for (const Field& f : spec.fields)
    if (f.required && !v.contains(f.name)) fail(child(path, f.name), f.why.empty() ? "missing" : "missing (" + f.why + ")");
}

void Reader::check(const json& v, const std::string& path, const Field& f) const {
  if (v.is_null() && f.nullable) return;
  if (f.constant && !(has_type(v, f.type) && v.is_number() && v.get<double>() == *f.constant))
    fail(path, "expected " + format_bound(*f.constant) + (f.constant_note.empty() ? "" : " (" + f.constant_note + ")") + ", got " +
                   describe(v));
  if (!has_type(v, f.type)) {
    if (!f.choices.empty()) fail(path, std::string(f.noun.empty() ? f.name : f.noun) + " " + describe(v) + ": expected " + or_list(f.choices));
    fail(path, "expected " + type_phrase(f) + ", got " + describe(v));
  }
  switch (f.type) {
    case Type::number:
      if (!number_in_range(v.get<double>(), f)) fail(path, "expected " + range_phrase(f) + ", got " + describe(v));
      break;
    case Type::integer:
      if (!integer_in_range(v, f)) fail(path, "expected " + range_phrase(f) + ", got " + describe(v));
      break;
    case Type::string: {
      const auto& s = v.get_ref<const std::string&>();
      if (!f.choices.empty() && std::find(f.choices.begin(), f.choices.end(), s) == f.choices.end())
        fail(path, bad_choice(f.noun.empty() ? f.name : f.noun, s, f.choices));
      if (f.min_length && s.size() < *f.min_length)
        fail(path, *f.min_length == 1 ? "expected a non-empty string, got \"\""
                                      : "expected a string of at least " + std::to_string(*f.min_length) + " bytes, got " + describe(v));
      if (f.max_length && s.size() > *f.max_length)
        fail(path, "expected a string of at most " + std::to_string(*f.max_length) + " bytes, got " + std::to_string(s.size()));
      break;
    }
    case Type::array:
      if ((f.min_items && v.size() < *f.min_items) || (f.max_items && v.size() > *f.max_items))
        fail(path, "expected " + type_phrase(f) + ", got " + describe(v));
      if (f.items)
        for (std::size_t i = 0; i < v.size(); ++i) check(v[i], element(path, i), *f.items);
      break;
    case Type::object:
      if (f.object) {
        object(v, path, *f.object);
        for (const Field& field : f.object->fields)
          if (const auto it = v.find(field.name); it != v.end()) check(*it, child(path, field.name), field);
      }
      break;
    default: break;
  }
}

const json* Reader::get(const json& obj, const std::string& path, const ObjectSpec& spec, std::string_view name) const {
  const Field* f = spec.field(name);
  if (!f) throw std::logic_error("json_fields: no field '" + std::string(name) + "' in the table of " + (path.empty() ? "(top level)" : path));
  return get(obj, path, *f);
}

const json* Reader::get(const json& obj, const std::string& path, const Field& f) const {
  const auto it = obj.find(f.name);
  if (it == obj.end()) {
    if (f.required) fail(child(path, f.name), f.why.empty() ? "missing" : "missing (" + f.why + ")");
    return nullptr;
  }
  check(*it, child(path, f.name), f);
  return it->is_null() && f.nullable ? nullptr : &*it;
}

double Reader::number(const json& obj, const std::string& path, const ObjectSpec& spec, std::string_view name, double fallback) const {
  const json* v = get(obj, path, spec, name);
  return v ? v->get<double>() : fallback;
}

std::int64_t Reader::integer(const json& obj, const std::string& path, const ObjectSpec& spec, std::string_view name,
                             std::int64_t fallback) const {
  const json* v = get(obj, path, spec, name);
  return v ? v->get<std::int64_t>() : fallback;
}

std::uint64_t Reader::unsigned_integer(const json& obj, const std::string& path, const ObjectSpec& spec, std::string_view name,
                                       std::uint64_t fallback) const {
  const json* v = get(obj, path, spec, name);
  return v ? v->get<std::uint64_t>() : fallback;
}

bool Reader::boolean(const json& obj, const std::string& path, const ObjectSpec& spec, std::string_view name, bool fallback) const {
  const json* v = get(obj, path, spec, name);
  return v ? v->get<bool>() : fallback;
}

std::string Reader::string(const json& obj, const std::string& path, const ObjectSpec& spec, std::string_view name,
                           const std::string& fallback) const {
  const json* v = get(obj, path, spec, name);
  return v ? v->get<std::string>() : fallback;
}

}  // namespace penumbra::json_input
