#include "display/display_calibration.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>
#include <stdexcept>

#include "io/atomic_file.h"
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

DisplayCalibration parse_calibration(const nlohmann::json& j, const std::string& file) {
  auto fail = [&](const std::string& field, const std::string& what) -> void {
    throw std::runtime_error(file + ": " + field + ": " + what);
  };
  if (!j.is_object()) fail("(top level)", "expected an object");
  static const std::set<std::string> known = {"schema_version", "created_utc", "model", "method", "gamma", "black_cd_m2",
                                              "white_cd_m2", "points", "residual_rms_cd_m2", "matched_level", "source", "monitor"};
  for (auto it = j.begin(); it != j.end(); ++it)
    if (!known.count(it.key())) fail(json_input::printable(it.key()), "unknown field");
  for (const char* key : {"schema_version", "model", "method", "gamma", "points"})
    if (!j.contains(key)) fail(key, "missing");
  if (!j["schema_version"].is_number_integer() || j["schema_version"].get<long long>() != kSchemaVersion)
    fail("schema_version", "expected " + std::to_string(kSchemaVersion) + " (a display-calibration.json of this version)");
  auto text = [&](const char* key, std::size_t max) {
    if (!j.contains(key)) return std::string();
    if (!j[key].is_string() || j[key].get<std::string>().size() > max)
      fail(key, "expected a string of at most " + std::to_string(max) + " bytes");
    return j[key].get<std::string>();
  };
  auto number = [&](const char* key, double lo, double hi) -> std::optional<double> {
    if (!j.contains(key) || j[key].is_null()) return std::nullopt;
    if (!j[key].is_number() || !(j[key].get<double>() >= lo && j[key].get<double>() <= hi))
      fail(key, "expected a number in [" + fmt(lo) + ", " + fmt(hi) + "] or null");
    return j[key].get<double>();
  };
  DisplayCalibration c;
  c.created_utc = text("created_utc", 64);
  c.source = text("source", 4096);
  try {
    c.model = parse_model(text("model", 16));
  } catch (const std::invalid_argument& e) {
    fail("model", e.what());
  }
  c.method = text("method", 32);
  if (c.method != "photometer" && c.method != "checkerboard-match") fail("method", "expected photometer or checkerboard-match");
  if (!j["gamma"].is_number() || !(j["gamma"].get<double>() >= 0.5 && j["gamma"].get<double>() <= 5))
    fail("gamma", "expected a number in [0.5, 5]");
  c.gamma = j["gamma"].get<double>();
  c.black_cd_m2 = number("black_cd_m2", 0, kMaxLuminanceCdM2);
  c.white_cd_m2 = number("white_cd_m2", 0, kMaxLuminanceCdM2);
  c.residual_rms_cd_m2 = number("residual_rms_cd_m2", 0, kMaxLuminanceCdM2);
  if (j.contains("monitor")) {
    if (!j["monitor"].is_object() && !j["monitor"].is_null()) fail("monitor", "expected an object or null");
    if (json_input::dump(j["monitor"]).size() > 4096) fail("monitor", "longer than 4096 bytes");
    c.monitor = j["monitor"];
  }
  const auto& points = j["points"];
  if (!points.is_array() || points.size() > 256) fail("points", "expected an array of at most 256 readings");
  for (std::size_t i = 0; i < points.size(); ++i) {
    const std::string at = json_input::element("points", i);
    const auto& p = points[i];
    if (!p.is_object() || p.size() != 2 || !p.contains("level") || !p.contains("luminance_cd_m2") ||
        !p["level"].is_number_integer() || !p["luminance_cd_m2"].is_number())
      fail(at, "expected {\"level\": 0..255, \"luminance_cd_m2\": number}");
    if (p["level"].get<long long>() < 0 || p["level"].get<long long>() > 255) fail(at + ".level", "expected 0..255");
    c.points.push_back({p["level"].get<int>(), p["luminance_cd_m2"].get<double>()});
  }
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
    for (const Reading& r : c.points) {
      const double predicted = *c.black_cd_m2 + range * std::pow(r.level / 255.0, c.gamma);
      sum += (predicted - r.luminance_cd_m2) * (predicted - r.luminance_cd_m2);
    }
    const double rms = std::sqrt(sum / static_cast<double>(c.points.size()));
    const double allowed = std::max(2.0 * c.residual_rms_cd_m2.value_or(0.0), 0.02 * range);
    if (c.model == Model::gamma && !(rms <= allowed))
      fail("gamma", fmt(c.gamma) + " (black " + fmt(*c.black_cd_m2) + ", white " + fmt(*c.white_cd_m2) +
                        ") contradicts the points: the model misses them by " + fmt(rms) + " cd/m2 RMS, more than " +
                        fmt(allowed) + " (twice residual_rms_cd_m2, at least 2 % of the range)");

    if (j.contains("matched_level")) fail("matched_level", "only for method checkerboard-match");
  } else {
    if (c.model != Model::gamma) fail("model", "a checkerboard match gives a gamma, not a table");
    if (!c.points.empty()) fail("points", "expected [] for a checkerboard match (no photometer readings)");
    if (!j.contains("matched_level") || !j["matched_level"].is_number_integer() || j["matched_level"].get<long long>() < 1 ||
        j["matched_level"].get<long long>() > 254)
      fail("matched_level", "expected the matched grey level, 1..254");
    c.matched_level = j["matched_level"].get<int>();
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
