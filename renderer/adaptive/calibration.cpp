#include "adaptive/calibration.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <string>

#include "adaptive/detail/calibration_fields.h"
#include "json/json_fields.h"
#include "json/json_input.h"
#include "psychometric/psychometric.h"

namespace penumbra::adaptive {
namespace {

// The renderer keeps c as a float: bounds that no texel count leaves keep 1e308 from becoming inf
// and 1e-300 from becoming 0.
constexpr double kMinC = 0.01, kMaxC = 1000.0;
constexpr std::size_t kMaxEntries = 256;
constexpr std::size_t kMaxText = 4096;

[[noreturn]] void fail(const std::filesystem::path& path, const std::string& field, const std::string& what) {
  throw CalibrationError(path.string() + ": " + field + ": " + what);
}

using json_input::Field;
using json_input::ObjectSpec;
using json_input::Type;

Field text_field(std::string name, bool required = false) {
  return {.name = std::move(name), .type = Type::string, .required = required, .max_length = kMaxText};
}
Field c_field() { return {.name = "c", .type = Type::number, .required = true, .min = kMinC, .max = kMaxC, .unit = "texels"}; }
// [lo, hi] around a value; that lo <= value <= hi is checked by the reader.
Field interval_field(std::string name) {
  return {.name = std::move(name), .type = Type::array, .min_items = 2, .max_items = 2,
          .items = json_input::item({.type = Type::number, .min = 0, .max = kMaxC, .exclusive_min = true})};
}
Field names_field(std::string name) {
  return {.name = std::move(name), .type = Type::array, .max_items = 64,
          .items = json_input::item({.type = Type::string, .min_length = 1, .max_length = 128})};
}
Field count_field(std::string name) {
  return {.name = std::move(name), .type = Type::integer, .nullable = true, .min = 0, .max = 2147483647};
}

const std::shared_ptr<const ObjectSpec>& threshold_fields() {
  static const auto spec = json_input::spec({{
      // An empty task or family is the default (2afc, log-weibull): the choice is checked after.
      text_field("task"),
      {.name = "guess", .type = Type::number, .min = 0, .max = 0.99},
      {.name = "criterion_f", .type = Type::number, .min = 1e-6, .max = 1 - 1e-6},
      text_field("family"),
      {.name = "beta", .type = Type::number, .min = 0.01, .max = 1000},
      {.name = "beta_ci95", .type = Type::array, .min_items = 2, .max_items = 2,
       .items = json_input::item({.type = Type::number, .min = 0, .max = 1000, .exclusive_min = true})},
      {.name = "lapse", .type = Type::number, .min = 0, .max = 0.5},
  }, false});
  return spec;
}

// penumbra-fit's "population" block: the fields the renderer reads; the rest (method, interval,
// per_condition, ...) is documentation.
const std::shared_ptr<const ObjectSpec>& population_fields() {
  // No upper bounds: a wide population interval (few participants) is a reading, not a bad file,
  // and must not make the renderer refuse the entry's c. Null: what the fit could not close.
  const auto pair = [](std::string name) {
    return Field{.name = std::move(name), .type = Type::array, .nullable = true, .min_items = 2, .max_items = 2,
                 .items = json_input::item({.type = Type::number, .nullable = true, .min = 0})};
  };
  const auto value = [](std::string name) {
    return Field{.name = std::move(name), .type = Type::number, .required = true, .nullable = true, .min = 0};
  };
  static const auto spec = json_input::spec({{
      count_field("participants"),
      text_field("condition"),
      value("mean_c"),
      pair("mean_c_ci95"),
      value("sd_log10"),
      pair("sd_log10_ci95"),
      {.name = "observer_percentile", .type = Type::string, .min_length = 1, .max_length = 32},
      {.name = "percentile_c", .type = Type::number, .nullable = true, .min = 0},
      pair("percentile_c_ci95"),
  }, false});
  return spec;
}

const std::shared_ptr<const ObjectSpec>& entry_fields() {
  static const auto spec = json_input::spec({{
      {.name = "technique", .type = Type::string, .required = true, .min_length = 1, .max_length = kMaxText},
      text_field("kernel"),
      c_field(),
      interval_field("ci95"),
      text_field("condition"),
      {.name = "obtained_by", .type = Type::string, .required = true,
       .choices = {"study", "image-observer", "simulated", "mixed", "published"}, .noun = "obtained_by"},
      {.name = "observers", .type = Type::string},
      {.name = "pooled_observer_kinds", .type = Type::array, .items = json_input::item({.type = Type::string})},
      {.name = "usable", .type = Type::boolean},
      names_field("unusable_because"),
      count_field("participants"),
      count_field("trials"),
      {.name = "per_condition", .type = Type::array},
      names_field("flags"),
      {.name = "threshold", .type = Type::object, .object = threshold_fields()},
      {.name = "population", .type = Type::object, .nullable = true, .object = population_fields()},
  }, false});
  return spec;
}

// Version 1: one c at the top level.
const ObjectSpec& version_1_fields() {
  static const ObjectSpec spec{{c_field(), interval_field("ci95"), text_field("condition"), text_field("source")}, false};
  return spec;
}

// c and ci95 of an entry (or of a version-1 file): lo <= c <= hi.
void read_c(const json_input::Reader& r, const nlohmann::json& j, const std::string& at, const ObjectSpec& spec,
            CalibrationEntry& e) {
  e.c = r.number(j, at, spec, "c");
  e.ci95_lo = e.ci95_hi = e.c;
  if (const auto* ci = r.get(j, at, spec, "ci95")) {
    e.ci95_lo = (*ci)[0].get<double>();
    e.ci95_hi = (*ci)[1].get<double>();
    e.has_ci95 = true;
    if (!(e.ci95_lo <= e.c && e.c <= e.ci95_hi))
      r.fail(json_input::child(at, "ci95"), "expected 0 < lo <= c <= hi <= 1000, got " + json_input::printable(ci->dump()));
  }
}

// An entry's "threshold": what its c is a threshold of (penumbra-fit writes it; default.json states
// the published design's).
ThresholdDefinition read_threshold(const json_input::Reader& r, const nlohmann::json& j, const std::string& at) {
  const ObjectSpec& spec = *threshold_fields();
  ThresholdDefinition t;
  t.task = r.string(j, at, spec, "task");
  if (t.task.empty()) t.task = "2afc";
  static const std::vector<std::string> tasks = {"2afc", "yesno"};
  if (t.task != "2afc" && t.task != "yesno") r.fail(json_input::child(at, "task"), json_input::Reader::bad_choice("task", t.task, tasks));
  t.guess = r.number(j, at, spec, "guess", 0.5);
  t.criterion_f = r.number(j, at, spec, "criterion_f", t.criterion_f);
  t.family = r.string(j, at, spec, "family");
  if (t.family.empty()) t.family = "log-weibull";
  static const std::vector<std::string> families = {"log-weibull", "weibull", "normal", "logistic"};
  if (!psychometric::parse_model(t.family)) r.fail(json_input::child(at, "family"), json_input::Reader::bad_choice("family", t.family, families));
  t.beta = r.number(j, at, spec, "beta", 3.5);
  const auto* ci = r.get(j, at, spec, "beta_ci95");
  t.beta_assumed = !ci;
  t.beta_lo = t.beta_hi = t.beta;
  if (ci) {
    t.beta_lo = (*ci)[0].get<double>();
    t.beta_hi = (*ci)[1].get<double>();
    if (!(t.beta_lo <= t.beta && t.beta <= t.beta_hi))
      r.fail(json_input::child(at, "beta_ci95"), "expected [lo, hi] with 0 < lo <= beta <= hi <= 1000");
  }
  t.lapse = r.number(j, at, spec, "lapse", 0);
  return t;
}

Population read_population(const json_input::Reader& r, const nlohmann::json& j, const std::string& at) {
  const ObjectSpec& spec = *population_fields();
  Population p;
  p.participants = static_cast<int>(r.integer(j, at, spec, "participants"));
  p.condition = r.string(j, at, spec, "condition");
  const auto bounds = [&](const char* key, double& lo, double& hi) {
    if (const auto* v = r.get(j, at, spec, key)) {
      lo = (*v)[0].is_null() ? NAN : (*v)[0].get<double>();
      hi = (*v)[1].is_null() ? NAN : (*v)[1].get<double>();
    }
  };
  p.mean_c = r.number(j, at, spec, "mean_c", NAN);
  bounds("mean_c_ci95", p.mean_c_lo, p.mean_c_hi);
  p.sd_log10 = r.number(j, at, spec, "sd_log10", NAN);
  bounds("sd_log10_ci95", p.sd_log10_lo, p.sd_log10_hi);
  const std::string percentile = r.string(j, at, spec, "observer_percentile");
  if (!percentile.empty()) {
    char* end = nullptr;
    p.percentile = std::strtod(percentile.c_str(), &end);
    if (end != percentile.c_str() + percentile.size() || !(p.percentile > 0 && p.percentile < 100))
      r.fail(json_input::child(at, "observer_percentile"), "expected a percentile in (0, 100) such as \"90\", got \"" + percentile + "\"");
  }
  p.percentile_c = r.number(j, at, spec, "percentile_c", NAN);
  bounds("percentile_c_ci95", p.percentile_c_lo, p.percentile_c_hi);
  return p;
}

CalibrationEntry read_entry(const json_input::Reader& r, const nlohmann::json& j, std::size_t index) {
  const std::string at = json_input::element("entries", index);
  const ObjectSpec& spec = *entry_fields();
  r.object(j, at, spec);
  CalibrationEntry e;
  e.technique = r.string(j, at, spec, "technique");
  e.kernel = r.string(j, at, spec, "kernel");
  read_c(r, j, at, spec, e);
  e.condition = r.string(j, at, spec, "condition");
  e.obtained_by = *method_from_name(r.string(j, at, spec, "obtained_by"));
  e.participants = static_cast<int>(r.integer(j, at, spec, "participants"));
  e.trials = static_cast<long>(r.integer(j, at, spec, "trials"));
  for (const char* other : {"observers", "pooled_observer_kinds", "per_condition"}) r.get(j, at, spec, other);
  auto names = [&](const char* key) {
    std::vector<std::string> list;
    if (const auto* v = r.get(j, at, spec, key))
      for (const auto& n : *v) list.push_back(n.get<std::string>());
    return list;
  };
  e.flags = names("flags");
  e.usable = r.boolean(j, at, spec, "usable", e.usable);
  e.unusable_because = names("unusable_because");
  if (!e.usable && e.unusable_because.empty()) e.unusable_because.push_back("marked usable: false");
  if (r.get(j, at, spec, "threshold")) e.threshold = read_threshold(r, j["threshold"], json_input::child(at, "threshold"));
  if (r.get(j, at, spec, "population")) e.population = read_population(r, j["population"], json_input::child(at, "population"));
  return e;
}

std::string describe(const CalibrationEntry& e) {
  std::string s = e.label() + " entry (" + std::string(method_description(e.obtained_by));
  if (e.participants > 0) s += ", " + std::to_string(e.participants) + (e.participants == 1 ? " participant" : " participants");
  return s + ")";
}

CalibrationChoice from_entry(const CalibrationEntry& e, bool fallback, std::string from) {
  return {e.c, e.ci95_lo, e.ci95_hi, e.has_ci95, e, fallback, std::move(from)};
}

}  // namespace

std::string_view method_name(CalibrationMethod m) {
  switch (m) {
    case CalibrationMethod::published: return "published";
    case CalibrationMethod::study: return "study";
    case CalibrationMethod::image_observer: return "image-observer";
    case CalibrationMethod::simulated: return "simulated";
    case CalibrationMethod::mixed: return "mixed";
  }
  return "?";
}

std::string_view method_description(CalibrationMethod m) {
  switch (m) {
    case CalibrationMethod::published: return "published";
    case CalibrationMethod::study: return "people";
    case CalibrationMethod::image_observer: return "image observer";
    case CalibrationMethod::simulated: return "psychometric simulation";
    case CalibrationMethod::mixed: return "observer kinds pooled";
  }
  return "?";
}

const ThresholdDefinition& CalibrationEntry::definition() const {
  static const ThresholdDefinition published{};
  return threshold ? *threshold : published;
}

double c_at_visibility(double c, double criterion_f, double visibility, double beta, std::string_view family) {
  if (!(visibility > 0 && visibility < 1)) throw std::invalid_argument("visibility: expected a detection probability in (0, 1)");
  const auto model = psychometric::parse_model(family);
  if (!model) throw std::invalid_argument("family '" + std::string(family) + "': expected log-weibull, weibull, normal or logistic");
  if (visibility == criterion_f) return c;
  // c is a filter radius per artifact; the model's x is log10(a / r) (log families) or a / r.
  const bool linear = *model == psychometric::Model::weibull;
  const double x = psychometric::threshold_at(*model, linear ? 1.0 / c : -std::log10(c), criterion_f, visibility, beta);
  return linear ? 1.0 / x : std::pow(10.0, -x);
}

namespace {

// dF/dx at F for slope 1, x in log10 units.
double slope_at(psychometric::Model m, double f) {
  switch (m) {
    case psychometric::Model::weibull:
    case psychometric::Model::log_weibull: return std::log(10.0) * (1 - f) * -std::log(1 - f);
    case psychometric::Model::normal: {
      const double z = std::sqrt(2.0) * psychometric::inverse_erf(2 * f - 1);
      return std::exp(-0.5 * z * z) / std::sqrt(2 * 3.141592653589793);
    }
    case psychometric::Model::logistic: return f * (1 - f);
  }
  return NAN;
}

psychometric::Model family_model(std::string_view family) {
  const auto model = psychometric::parse_model(family);
  if (!model) throw std::invalid_argument("family '" + std::string(family) + "': expected log-weibull, weibull, normal or logistic");
  return *model;
}

}  // namespace

double family_slope(std::string_view from, double beta, std::string_view to, double criterion_f) {
  return beta * slope_at(family_model(from), criterion_f) / slope_at(family_model(to), criterion_f);
}

CAtPercentile c_at_observer_percentile(const CalibrationEntry& e, double percentile) {
  if (!(percentile > 0 && percentile < 100))
    throw std::invalid_argument("observer percentile: expected a number in (0, 100), got " + std::to_string(percentile));
  if (!e.population)
    throw std::invalid_argument(e.label() + " entry (" + std::string(method_description(e.obtained_by)) +
                                ") has no population block: only penumbra-fit's multilevel fit of several participants gives a "
                                "percentile observer's c");
  const Population& p = *e.population;
  if (!(p.mean_c > 0) || !(p.sd_log10 >= 0))
    throw std::invalid_argument(e.label() + " entry's population block has no mean c or spread (the multilevel fit did not give them)");
  CAtPercentile out;
  if (std::abs(percentile - p.percentile) < 1e-9 && std::isfinite(p.percentile_c)) {
    out.c = p.percentile_c;
    out.lo = p.percentile_c_lo;
    out.hi = p.percentile_c_hi;
    out.fitted = true;
    return out;
  }
  const double z = std::sqrt(2.0) * psychometric::inverse_erf(2 * percentile / 100 - 1);
  out.c = p.mean_c * std::pow(10.0, z * p.sd_log10);
  // A positive z grows with the spread, a negative one shrinks: the box's low and high corners.
  const double sd_for_lo = z >= 0 ? p.sd_log10_lo : p.sd_log10_hi, sd_for_hi = z >= 0 ? p.sd_log10_hi : p.sd_log10_lo;
  out.lo = p.mean_c_lo * std::pow(10.0, z * sd_for_lo);
  out.hi = p.mean_c_hi * std::pow(10.0, z * sd_for_hi);
  return out;
}

CAtVisibility c_at_visibility(const CalibrationEntry& e, double visibility) {
  const ThresholdDefinition& t = e.definition();
  const double c = c_at_visibility(e.c, t.criterion_f, visibility, t.beta, t.family);
  CAtVisibility out{c, INFINITY, 0, c, c};
  if (visibility == t.criterion_f) {
    out.lo = std::min(e.ci95_lo, c);
    out.hi = std::max(e.ci95_hi, c);
    return out;
  }
  for (const std::string_view family : {"log-weibull", "normal", "logistic"}) {
    for (const double c_end : {e.ci95_lo, e.ci95_hi})
      for (const double beta : {t.beta_lo, t.beta_hi}) {
        const double v = c_at_visibility(c_end, t.criterion_f, visibility, family_slope(t.family, beta, family, t.criterion_f), family);
        out.lo = std::min(out.lo, v);
        out.hi = std::max(out.hi, v);
      }
    const double v = c_at_visibility(e.c, t.criterion_f, visibility, family_slope(t.family, t.beta, family, t.criterion_f), family);
    out.family_lo = std::min(out.family_lo, v);
    out.family_hi = std::max(out.family_hi, v);
  }
  out.lo = std::min(out.lo, c);
  out.hi = std::max(out.hi, c);
  return out;
}

std::string CalibrationChoice::warnings() const {
  if (!entry) return "";
  std::string s;
  auto list = [](const std::vector<std::string>& v) {
    std::string out;
    for (const std::string& x : v) out += (out.empty() ? "" : ", ") + x;
    return out;
  };
  if (!entry->usable) s = "NOT USABLE: " + list(entry->unusable_because);
  if (!entry->flags.empty()) s += (s.empty() ? "" : "; ") + std::string("flags: ") + list(entry->flags);
  return s;
}

std::optional<CalibrationMethod> method_from_name(std::string_view name) {
  for (CalibrationMethod m : {CalibrationMethod::published, CalibrationMethod::study, CalibrationMethod::image_observer,
                              CalibrationMethod::simulated, CalibrationMethod::mixed})
    if (method_name(m) == name) return m;
  return std::nullopt;
}

CalibrationChoice Calibration::choose(std::string_view technique, std::string_view kernel, bool rotated) const {
  const std::string wanted = kernel.empty() ? std::string(technique) : std::string(technique) + " " + std::string(kernel);
  const std::string wanted_rotated = rotated ? wanted + " rotated per pixel" : wanted;
  // The kernel an entry was measured with: its own, PCF's assumed one when it states none.
  const auto measured_kernel = [](const CalibrationEntry& e) -> std::string {
    return e.technique == "pcf" && e.kernel.empty() ? std::string(kAssumedPcfKernel) : e.kernel;
  };
  const auto fallback = [&](const CalibrationEntry& e, std::string reason, std::string would) {
    CalibrationChoice c = from_entry(e, true, describe(e) + ", not measured for " + wanted_rotated + ": " + reason + "; " + would + " would match");
    c.fallback_reason = std::move(reason);
    c.would_match = std::move(would);
    return c;
  };
  const auto kernel_said = [&](const CalibrationEntry& e) {
    return e.kernel.empty() ? "measured with the " + measured_kernel(e) + " kernel (the study's, assumed: the entry states none)"
                            : "measured with the " + e.kernel + " kernel";
  };
  const std::string would = rotated ? "an entry for " + wanted + " measured rotated, or pcf.rotate false with a " + wanted + " entry"
                                    : "a " + wanted + " entry";
  const auto exact_kernel = [&](const CalibrationEntry& e) {
    return e.technique == technique && (measured_kernel(e) == kernel || (e.kernel.empty() && e.technique != "pcf"));
  };
  for (const CalibrationEntry& e : entries)
    if (e.technique == technique && e.kernel == kernel && exact_kernel(e)) {
      if (rotated) return fallback(e, "measured unrotated (the study draws one tap pattern for every pixel)", would);
      return from_entry(e, false, describe(e));
    }
  for (const CalibrationEntry& e : entries)
    if (exact_kernel(e)) {
      if (rotated) return fallback(e, "measured unrotated (the study draws one tap pattern for every pixel)", would);
      return from_entry(e, false, describe(e));
    }
  for (const CalibrationEntry& e : entries)
    if (e.technique == technique) return fallback(e, kernel_said(e) + (kernel.empty() ? "" : ", not with " + std::string(kernel)), would);
  for (const CalibrationEntry& e : entries)
    if (e.technique == "pcf") return fallback(e, "measured for pcf, not for " + std::string(technique), would);
  CalibrationChoice c{kPublishedC, kPublishedC, kPublishedC, false, std::nullopt, true,
                      "published PCF value, not measured for " + wanted_rotated + "; " + would + " would match"};
  c.fallback_reason = "no entry in the file for " + wanted + " or pcf";
  c.would_match = would;
  return c;
}

const json_input::ObjectSpec& calibration_fields() {
  static const ObjectSpec spec{{
      {.name = "schema_version", .type = Type::integer, .required = true, .constant = kCalibrationSchemaVersion,
       .constant_note = "or no field: a version-1 file with one c"},
      {.name = "created_utc", .type = Type::string},
      {.name = "source", .type = Type::string},
      {.name = "entries", .type = Type::array, .required = true, .min_items = 1, .max_items = kMaxEntries,
       .items = json_input::item({.type = Type::object, .object = entry_fields()})},
  }, false};
  return spec;
}

Calibration load_calibration(const std::filesystem::path& path) {
  nlohmann::json j;
  try {
    j = json_input::read_file(path, {.max_bytes = 1 << 20, .max_depth = 16});
  } catch (const json_input::JsonError& e) {
    throw CalibrationError(e.what());
  }
  const json_input::Reader r(path.string());
  try {
    Calibration cal;
    cal.source = path.string();
    // A study config given by mistake (its c is "missing"): say what it is and which file is wanted.
    if (j.is_object() && !j.contains("c") && !j.contains("entries") && (j.contains("rounds") || j.contains("quest")))
      throw CalibrationError(path.string() +
                             ": a study config (penumbra-study --config), not a calibration file; give the calibration.json "
                             "penumbra-fit writes, or the shipped calibration/default.json");
    if (!j.is_object() || !j.contains("schema_version")) {
      // Version 1: one c, measured with the study's own filter before entries per technique.
      r.object(j, "", version_1_fields());
      cal.schema_version = 1;
      CalibrationEntry e;
      e.technique = "pcf";
      read_c(r, j, "", version_1_fields(), e);
      e.condition = r.string(j, "", version_1_fields(), "condition");
      const std::string source = r.string(j, "", version_1_fields(), "source");
      e.obtained_by = source.rfind("penumbra-fit", 0) == 0 ? CalibrationMethod::study : CalibrationMethod::published;
      cal.entries.push_back(std::move(e));
      return cal;
    }
    const ObjectSpec& spec = calibration_fields();
    r.get(j, "", spec, "schema_version");
    if (j.contains("c")) fail(path, "c", "a version-2 file has its c in entries[], not at the top level");
    r.object(j, "", spec);
    r.get(j, "", spec, "created_utc");
    r.get(j, "", spec, "source");
    const auto& list = j["entries"];
    if (!list.is_array() || list.empty() || list.size() > kMaxEntries) r.get(j, "", spec, "entries");
    for (std::size_t i = 0; i < list.size(); ++i) {
      CalibrationEntry e = read_entry(r, list[i], i);
      for (const CalibrationEntry& other : cal.entries)
        if (other.technique == e.technique && other.kernel == e.kernel)
          fail(path, json_input::element("entries", i), "a second entry for " + e.label());
      cal.entries.push_back(std::move(e));
    }
    return cal;
  } catch (const json_input::FieldError& e) {
    throw CalibrationError(e.what());
  }
}

}  // namespace penumbra::adaptive
