#include "adaptive/calibration.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>

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

// A string field of `j`, at most kMaxText bytes; `at` prefixes its name in errors ("entries[2].").
std::string text(const std::filesystem::path& path, const nlohmann::json& j, const std::string& at, const char* field, bool required) {
  if (!j.contains(field)) {
    if (required) fail(path, at + field, "missing");
    return {};
  }
  if (!j[field].is_string()) fail(path, at + field, "expected a string");
  std::string s = j[field].get<std::string>();
  if (s.size() > kMaxText) fail(path, at + field, "longer than " + std::to_string(kMaxText) + " bytes");
  return s;
}

// c and ci95 of an entry (or of a version-1 file); `at` prefixes the field names.
void read_c(const std::filesystem::path& path, const nlohmann::json& j, const std::string& at, CalibrationEntry& e) {
  if (!j.contains("c")) fail(path, at + "c", "missing");
  if (!j["c"].is_number()) fail(path, at + "c", "expected a number");
  e.c = j["c"].get<double>();
  if (!(e.c >= kMinC && e.c <= kMaxC))
    fail(path, at + "c", "expected a positive number in [0.01, 1000] texels, got " + json_input::printable(j["c"].dump()));
  e.ci95_lo = e.ci95_hi = e.c;
  if (j.contains("ci95")) {
    const auto& ci = j["ci95"];
    if (!ci.is_array() || ci.size() != 2 || !ci[0].is_number() || !ci[1].is_number()) fail(path, at + "ci95", "expected [lo, hi]");
    e.ci95_lo = ci[0].get<double>();
    e.ci95_hi = ci[1].get<double>();
    if (!(e.ci95_lo > 0 && e.ci95_lo <= e.c && e.c <= e.ci95_hi && e.ci95_hi <= kMaxC))
      fail(path, at + "ci95", "expected 0 < lo <= c <= hi <= 1000, got " + json_input::printable(ci.dump()));
  }
}

long count(const std::filesystem::path& path, const nlohmann::json& j, const std::string& at, const char* field) {
  if (!j.contains(field) || j[field].is_null()) return 0;
  const auto& v = j[field];
  if (!v.is_number_integer() || v.get<long long>() < 0 || v.get<long long>() >= (1LL << 31))
    fail(path, at + field, "expected a whole number in [0, 2^31), got " + json_input::printable(v.dump()));
  return static_cast<long>(v.get<long long>());
}

// An entry's "threshold": what its c is a threshold of (penumbra-fit writes it; default.json states
// the published design's).
ThresholdDefinition read_threshold(const std::filesystem::path& path, const nlohmann::json& j, const std::string& at) {
  if (!j.is_object()) fail(path, at.substr(0, at.size() - 1), "expected an object");
  ThresholdDefinition t;
  auto real = [&](const char* key, double lo, double hi, double fallback) {
    if (!j.contains(key)) return fallback;
    if (!j[key].is_number() || !(j[key].get<double>() >= lo && j[key].get<double>() <= hi))
      fail(path, at + key, "expected a number in [" + json_input::printable(nlohmann::json(lo).dump()) + ", " +
                               json_input::printable(nlohmann::json(hi).dump()) + "]");
    return j[key].get<double>();
  };
  t.task = text(path, j, at, "task", false);
  if (t.task.empty()) t.task = "2afc";
  if (t.task != "2afc" && t.task != "yesno") fail(path, at + "task", "expected 2afc or yesno");
  t.guess = real("guess", 0, 0.99, 0.5);
  t.criterion_f = real("criterion_f", 1e-6, 1 - 1e-6, t.criterion_f);
  t.family = text(path, j, at, "family", false);
  if (t.family.empty()) t.family = "log-weibull";
  if (!psychometric::parse_model(t.family)) fail(path, at + "family", "expected log-weibull, weibull, normal or logistic");
  t.beta = real("beta", 0.01, 1000, 3.5);
  t.beta_assumed = !j.contains("beta_ci95");
  t.beta_lo = t.beta_hi = t.beta;
  if (j.contains("beta_ci95")) {
    const auto& ci = j["beta_ci95"];
    if (!ci.is_array() || ci.size() != 2 || !ci[0].is_number() || !ci[1].is_number() ||
        !(ci[0].get<double>() > 0 && ci[0].get<double>() <= t.beta && t.beta <= ci[1].get<double>() && ci[1].get<double>() <= 1000))
      fail(path, at + "beta_ci95", "expected [lo, hi] with 0 < lo <= beta <= hi <= 1000");
    t.beta_lo = ci[0].get<double>();
    t.beta_hi = ci[1].get<double>();
  }
  t.lapse = real("lapse", 0, 0.5, 0);
  return t;
}

CalibrationEntry read_entry(const std::filesystem::path& path, const nlohmann::json& j, std::size_t index) {
  const std::string at = "entries[" + std::to_string(index) + "].";
  if (!j.is_object()) fail(path, "entries[" + std::to_string(index) + "]", "expected an object");
  CalibrationEntry e;
  auto field = [&](const char* name, bool required) { return text(path, j, at, name, required); };
  e.technique = field("technique", true);
  if (e.technique.empty()) fail(path, at + "technique", "expected a technique name, got an empty string");
  e.kernel = field("kernel", false);
  read_c(path, j, at, e);
  e.condition = field("condition", false);
  const std::string method = field("obtained_by", true);
  const auto m = method_from_name(method);
  if (!m)
    fail(path, at + "obtained_by",
         "expected study, image-observer, simulated, mixed or published, got '" + json_input::printable(method) + "'");
  e.obtained_by = *m;
  e.participants = static_cast<int>(count(path, j, at, "participants"));
  e.trials = count(path, j, at, "trials");
  auto names = [&](const char* key) {
    std::vector<std::string> list;
    if (!j.contains(key)) return list;
    const auto& v = j[key];
    if (!v.is_array() || v.size() > 64) fail(path, at + key, "expected an array of at most 64 names");
    for (const auto& n : v) {
      if (!n.is_string() || n.get<std::string>().empty() || n.get<std::string>().size() > 128)
        fail(path, at + key, "expected names (strings of 1..128 bytes)");
      list.push_back(n.get<std::string>());
    }
    return list;
  };
  e.flags = names("flags");
  if (j.contains("usable")) {
    if (!j["usable"].is_boolean()) fail(path, at + "usable", "expected true or false");
    e.usable = j["usable"].get<bool>();
  }
  e.unusable_because = names("unusable_because");
  if (!e.usable && e.unusable_because.empty()) e.unusable_because.push_back("marked usable: false");
  if (j.contains("threshold")) e.threshold = read_threshold(path, j["threshold"], at + "threshold.");
  return e;
}

std::string describe(const CalibrationEntry& e) {
  std::string s = e.label() + " entry (" + std::string(method_description(e.obtained_by));
  if (e.participants > 0) s += ", " + std::to_string(e.participants) + (e.participants == 1 ? " participant" : " participants");
  return s + ")";
}

CalibrationChoice from_entry(const CalibrationEntry& e, bool fallback, std::string from) {
  return {e.c, e.ci95_lo, e.ci95_hi, e, fallback, std::move(from)};
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

CAtVisibility c_at_visibility(const CalibrationEntry& e, double visibility) {
  const ThresholdDefinition& t = e.definition();
  CAtVisibility out{c_at_visibility(e.c, t.criterion_f, visibility, t.beta, t.family), INFINITY, 0};
  for (const double c : {e.ci95_lo, e.ci95_hi})
    for (const double beta : {t.beta_lo, t.beta_hi}) {
      const double v = c_at_visibility(c, t.criterion_f, visibility, beta, t.family);
      out.lo = std::min(out.lo, v);
      out.hi = std::max(out.hi, v);
    }
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

CalibrationChoice Calibration::choose(std::string_view technique, std::string_view kernel) const {
  const std::string wanted = kernel.empty() ? std::string(technique) : std::string(technique) + " " + std::string(kernel);
  for (const CalibrationEntry& e : entries)
    if (e.technique == technique && e.kernel == kernel) return from_entry(e, false, describe(e));
  for (const CalibrationEntry& e : entries)
    if (e.technique == technique && e.kernel.empty()) return from_entry(e, false, describe(e));
  for (const CalibrationEntry& e : entries)
    if (e.technique == technique) return from_entry(e, true, describe(e) + ", not measured for " + wanted);
  for (const CalibrationEntry& e : entries)
    if (e.technique == "pcf") return from_entry(e, true, describe(e) + ", not measured for " + wanted);
  return {kPublishedC, kPublishedC, kPublishedC, std::nullopt, true, "published PCF value, not measured for " + wanted};
}

Calibration load_calibration(const std::filesystem::path& path) {
  nlohmann::json j;
  try {
    j = json_input::read_file(path, {.max_bytes = 1 << 20, .max_depth = 16});
  } catch (const json_input::JsonError& e) {
    throw CalibrationError(e.what());
  }
  if (!j.is_object()) fail(path, "(top level)", "expected an object");
  Calibration cal;
  cal.source = path.string();
  if (!j.contains("schema_version")) {
    // Version 1: one c, measured with the study's own filter before entries per technique.
    cal.schema_version = 1;
    CalibrationEntry e;
    e.technique = "pcf";
    read_c(path, j, "", e);
    e.condition = text(path, j, "", "condition", false);
    const std::string source = text(path, j, "", "source", false);
    e.obtained_by = source.rfind("penumbra-fit", 0) == 0 ? CalibrationMethod::study : CalibrationMethod::published;
    cal.entries.push_back(std::move(e));
    return cal;
  }
  const auto& v = j["schema_version"];
  if (!v.is_number_integer() || v.get<long long>() != kCalibrationSchemaVersion)
    fail(path, "schema_version",
         "expected " + std::to_string(kCalibrationSchemaVersion) + " (or no field: a version-1 file with one c), got " +
             json_input::printable(v.dump()));
  if (j.contains("c")) fail(path, "c", "a version-2 file has its c in entries[], not at the top level");
  if (!j.contains("entries")) fail(path, "entries", "missing");
  const auto& list = j["entries"];
  if (!list.is_array() || list.empty()) fail(path, "entries", "expected a non-empty array of entries");
  if (list.size() > kMaxEntries) fail(path, "entries", "more than " + std::to_string(kMaxEntries) + " entries");
  for (std::size_t i = 0; i < list.size(); ++i) {
    CalibrationEntry e = read_entry(path, list[i], i);
    for (const CalibrationEntry& other : cal.entries)
      if (other.technique == e.technique && other.kernel == e.kernel)
        fail(path, "entries[" + std::to_string(i) + "]", "a second entry for " + e.label());
    cal.entries.push_back(std::move(e));
  }
  return cal;
}

}  // namespace penumbra::adaptive
