#include "display/display_calibration.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>
#include <stdexcept>

#include "io/atomic_file.h"
#include "json/json_fields.h"
#include "json/json_input.h"
#include "text/fingerprint.h"

namespace penumbra::display {

std::string to_string(Model m) { return m == Model::gamma ? "gamma" : "table"; }

Model parse_model(const std::string& s) {
  if (s == "gamma") return Model::gamma;
  if (s == "table") return Model::table;
  throw std::invalid_argument("model '" + json_input::printable(s) + "': expected gamma or table");
}

namespace {

std::string fmt(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%g", v);
  return b;
}

// Fritsch–Carlson: the monotone cubic Hermite interpolant of (x, y), y non-decreasing, at `at`.
double monotone_cubic(const std::vector<double>& x, const std::vector<double>& y, double at) {
  const std::size_t n = x.size();
  if (at <= x.front()) return y.front();
  if (at >= x.back()) return y.back();
  std::vector<double> slope(n - 1), tangent(n);
  for (std::size_t i = 0; i + 1 < n; ++i) slope[i] = (y[i + 1] - y[i]) / (x[i + 1] - x[i]);
  tangent[0] = slope[0];
  tangent[n - 1] = slope[n - 2];
  for (std::size_t i = 1; i + 1 < n; ++i)
    tangent[i] = slope[i - 1] * slope[i] <= 0 ? 0 : (slope[i - 1] + slope[i]) / 2;
  for (std::size_t i = 0; i + 1 < n; ++i) {
    if (slope[i] == 0) {
      tangent[i] = tangent[i + 1] = 0;
      continue;
    }
    const double a = tangent[i] / slope[i], b = tangent[i + 1] / slope[i], h = std::hypot(a, b);
    if (h > 3) {  // outside the circle of radius 3 the cubic could overshoot
      tangent[i] = 3 * a / h * slope[i];
      tangent[i + 1] = 3 * b / h * slope[i];
    }
  }
  const std::size_t i = static_cast<std::size_t>(std::upper_bound(x.begin(), x.end(), at) - x.begin()) - 1;
  const double h = x[i + 1] - x[i], t = (at - x[i]) / h, t2 = t * t, t3 = t2 * t;
  return (2 * t3 - 3 * t2 + 1) * y[i] + (t3 - 2 * t2 + t) * h * tangent[i] + (-2 * t3 + 3 * t2) * y[i + 1] +
         (t3 - t2) * h * tangent[i + 1];
}

}  // namespace

double DisplayCalibration::relative_luminance(double level) const {
  const double v = std::clamp(level, 0.0, 255.0);
  if (model == Model::gamma) return std::pow(v / 255.0, gamma);
  std::vector<double> x, y;
  const double black = points.front().luminance_cd_m2, range = points.back().luminance_cd_m2 - black;
  for (const Reading& p : points) {
    x.push_back(p.level);
    y.push_back((p.luminance_cd_m2 - black) / range);
  }
  return monotone_cubic(x, y, v);
}

std::uint8_t DisplayCalibration::encode(double linear) const {
  const double target = std::clamp(linear, 0.0, 1.0);
  double level = 0;
  if (model == Model::gamma) {
    level = 255.0 * std::pow(target, 1.0 / gamma);
  } else {  // relative_luminance rises with the level: bisection to well below a level
    double lo = 0, hi = 255;
    for (int i = 0; i < 40; ++i) {
      const double mid = (lo + hi) / 2;
      (relative_luminance(mid) < target ? lo : hi) = mid;
    }
    level = (lo + hi) / 2;
  }
  // Of the two levels around it, the one whose luminance is nearer.
  const double below = std::clamp(std::floor(level), 0.0, 255.0), above = std::min(below + 1, 255.0);
  const bool up = std::abs(relative_luminance(above) - target) < std::abs(relative_luminance(below) - target);
  return static_cast<std::uint8_t>(up ? above : below);
}

void check_readings(const std::vector<Reading>& r) {
  if (r.size() < static_cast<std::size_t>(kMinReadings))
    throw std::invalid_argument(std::to_string(r.size()) + " reading(s): expected at least " + std::to_string(kMinReadings) +
                                " levels, including 0 and 255");
  for (const Reading& p : r) {
    if (p.level < 0 || p.level > 255) throw std::invalid_argument("level " + std::to_string(p.level) + ": expected 0..255");
    if (!(std::isfinite(p.luminance_cd_m2) && p.luminance_cd_m2 >= 0 && p.luminance_cd_m2 <= kMaxLuminanceCdM2))
      throw std::invalid_argument("level " + std::to_string(p.level) + ": " + fmt(p.luminance_cd_m2) +
                                  " is not a luminance in [0, 100000] cd/m2");
  }
  if (r.front().level != 0 || r.back().level != 255)
    throw std::invalid_argument("expected readings of level 0 (black) and 255 (white); the lowest is " +
                                std::to_string(r.front().level) + ", the highest " + std::to_string(r.back().level));
  for (std::size_t i = 1; i < r.size(); ++i) {
    if (r[i].level == r[i - 1].level) throw std::invalid_argument("level " + std::to_string(r[i].level) + ": read twice");
    if (!(r[i].luminance_cd_m2 > r[i - 1].luminance_cd_m2))
      throw std::invalid_argument("level " + std::to_string(r[i].level) + ": " + fmt(r[i].luminance_cd_m2) +
                                  " cd/m2, not above level " + std::to_string(r[i - 1].level) + "'s " +
                                  fmt(r[i - 1].luminance_cd_m2) + " (luminance must rise with the level: remeasure)");
  }
}

// Hand-written: schema_version added, the model as its name, optionals as null, matched_level only when set.
nlohmann::json to_json(const DisplayCalibration& c) {
  auto optional = [](const std::optional<double>& v) { return v ? nlohmann::json(*v) : nlohmann::json(nullptr); };
  nlohmann::json points = nlohmann::json::array();
  for (const Reading& p : c.points) points.push_back({{"level", p.level}, {"luminance_cd_m2", p.luminance_cd_m2}});
  nlohmann::json j = {{"schema_version", kSchemaVersion},
                      {"created_utc", c.created_utc},
                      {"model", to_string(c.model)},
                      {"method", c.method},
                      {"gamma", c.gamma},
                      {"black_cd_m2", optional(c.black_cd_m2)},
                      {"white_cd_m2", optional(c.white_cd_m2)},
                      {"points", points},
                      {"residual_rms_cd_m2", optional(c.residual_rms_cd_m2)},
                      {"source", c.source},
                      {"monitor", c.monitor}};
  if (c.matched_level) j["matched_level"] = *c.matched_level;
  return j;
}

const json_input::ObjectSpec& calibration_fields() {
  using json_input::Type;
  static const json_input::ObjectSpec spec{{
      {.name = "schema_version", .type = Type::integer, .required = true, .constant = kSchemaVersion,
       .constant_note = "a display-calibration.json of this version"},
      {.name = "created_utc", .type = Type::string, .max_length = 64},
      {.name = "model", .type = Type::string, .required = true, .choices = {"gamma", "table"}, .noun = "model"},
      {.name = "method", .type = Type::string, .required = true, .choices = {"photometer", "checkerboard-match"}, .noun = "method"},
      {.name = "gamma", .type = Type::number, .required = true, .min = 0.5, .max = 5},
      {.name = "black_cd_m2", .type = Type::number, .nullable = true, .min = 0, .max = kMaxLuminanceCdM2},
      {.name = "white_cd_m2", .type = Type::number, .nullable = true, .min = 0, .max = kMaxLuminanceCdM2},
      {.name = "points", .type = Type::array, .required = true, .max_items = 256,
       .items = json_input::item({.type = Type::object, .object = json_input::spec({{
           {.name = "level", .type = Type::integer, .required = true, .min = 0, .max = 255},
           {.name = "luminance_cd_m2", .type = Type::number, .required = true, .min = 0, .max = kMaxLuminanceCdM2}}})})},
      {.name = "residual_rms_cd_m2", .type = Type::number, .nullable = true, .min = 0, .max = kMaxLuminanceCdM2},
      {.name = "matched_level", .type = Type::integer, .min = 1, .max = 254},
      {.name = "source", .type = Type::string, .max_length = 4096},
      {.name = "monitor", .type = Type::object, .nullable = true},
  }};
  return spec;
}

DisplayCalibration parse_calibration(const nlohmann::json& j, const std::string& file) {
  const json_input::Reader r(file);
  auto fail = [&](const std::string& field, const std::string& what) -> void { r.fail(field, what); };
  const json_input::ObjectSpec& spec = calibration_fields();
  r.object(j, "", spec);
  auto optional = [&](const char* key) -> std::optional<double> {
    if (const auto* v = r.get(j, "", spec, key)) return v->get<double>();
    return std::nullopt;
  };
  r.get(j, "", spec, "schema_version");
  DisplayCalibration c;
  c.created_utc = r.string(j, "", spec, "created_utc");
  c.source = r.string(j, "", spec, "source");
  c.model = parse_model(r.string(j, "", spec, "model"));
  c.method = r.string(j, "", spec, "method");
  c.gamma = r.number(j, "", spec, "gamma");
  c.black_cd_m2 = optional("black_cd_m2");
  c.white_cd_m2 = optional("white_cd_m2");
  c.residual_rms_cd_m2 = optional("residual_rms_cd_m2");
  if (const auto* monitor = r.get(j, "", spec, "monitor")) {
    if (json_input::dump(*monitor).size() > 4096) fail("monitor", "longer than 4096 bytes");
    c.monitor = *monitor;
  }
  for (const auto& p : *r.get(j, "", spec, "points"))
    c.points.push_back({p["level"].get<int>(), p["luminance_cd_m2"].get<double>()});
  const auto* matched = r.get(j, "", spec, "matched_level");
  if (c.method == "photometer") {
    try {
      check_readings(c.points);  // in order, as written
    } catch (const std::invalid_argument& e) {
      fail("points", e.what());
    }
    if (!c.black_cd_m2 || !c.white_cd_m2 || !(*c.white_cd_m2 > *c.black_cd_m2))
      fail("white_cd_m2", "expected black_cd_m2 and white_cd_m2 with white above black");
    // The model's numbers must describe the readings they came from (an edited gamma, black or
    // white would encode every stimulus with a transfer nobody measured). The gamma model through
    // black, white and gamma is held to the readings within twice its recorded RMS residual, and
    // at least 2 % of the range (a table encodes with its readings alone).
    const double range = *c.white_cd_m2 - *c.black_cd_m2;
    double sum = 0;
    for (const Reading& p : c.points) {
      const double predicted = *c.black_cd_m2 + range * std::pow(p.level / 255.0, c.gamma);
      sum += (predicted - p.luminance_cd_m2) * (predicted - p.luminance_cd_m2);
    }
    const double rms = std::sqrt(sum / static_cast<double>(c.points.size()));
    const double allowed = std::max(2.0 * c.residual_rms_cd_m2.value_or(0.0), 0.02 * range);
    if (c.model == Model::gamma && !(rms <= allowed))
      fail("gamma", fmt(c.gamma) + " (black " + fmt(*c.black_cd_m2) + ", white " + fmt(*c.white_cd_m2) +
                        ") contradicts the points: the model misses them by " + fmt(rms) + " cd/m2 RMS, more than " +
                        fmt(allowed) + " (twice residual_rms_cd_m2, at least 2 % of the range)");

    if (matched) fail("matched_level", "only for method checkerboard-match");
  } else {
    if (c.model != Model::gamma) fail("model", "a checkerboard match gives a gamma, not a table");
    if (!c.points.empty()) fail("points", "expected [] for a checkerboard match (no photometer readings)");
    if (!matched) fail("matched_level", "missing (a checkerboard match records the grey level matched)");
    c.matched_level = matched->get<int>();
    const double implied = std::log(0.5) / std::log(*c.matched_level / 255.0);
    if (std::abs(implied - c.gamma) > 1e-6 * implied)
      fail("gamma", "expected " + fmt(implied) + ", the gamma of matched_level " + std::to_string(*c.matched_level));
  }
  return c;
}

DisplayCalibration load_calibration(const std::filesystem::path& path) {
  return parse_calibration(json_input::read_file(path, {.max_bytes = 1 << 20, .max_depth = 8}), path.string());
}

void write_calibration(const std::filesystem::path& path, const DisplayCalibration& c) {
  io::write_file_atomic(path, json_input::dump(to_json(c), 2) + "\n");
}

std::string fingerprint(const nlohmann::json& calibration_json) { return text::fnv1a64_hex(json_input::dump(calibration_json)); }

}  // namespace penumbra::display
