#include "adaptive/resolution_rule.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>

#include <nlohmann/json.hpp>

#include "json/json_input.h"

namespace penumbra::adaptive {

double required_texels_uv(double c, double radius_uv) {
  if (!(radius_uv > 0) || !std::isfinite(c)) return std::numeric_limits<double>::infinity();
  return std::max(c, 0.0) / radius_uv;
}

double required_texels_ws(double c, double light_extent_ws, double radius_ws) {
  if (!(light_extent_ws > 0)) return 0;  // nothing to cover: the smallest map does
  if (!(radius_ws > 0)) return std::numeric_limits<double>::infinity();
  return required_texels_uv(c, radius_ws / light_extent_ws);
}

int clamp_resolution(double required, const ResolutionLimits& limits) {
  const int lo = std::max(1, limits.min_texels);
  const int hi = std::max(lo, limits.max_texels);
  const int q = std::max(1, limits.quantum_texels);
  if (std::isnan(required) || required >= hi) return hi;
  if (required <= lo) return lo;
  const double rounded = std::ceil(required / q) * q;
  return static_cast<int>(std::clamp(rounded, static_cast<double>(lo), static_cast<double>(hi)));
}

ResolutionController::ResolutionController(Params params) : params_(params) {}

int ResolutionController::update(double required) {
  const int target = clamp_resolution(required, params_.limits);
  if (current_ == 0 || target > current_) {  // first frame, or grow at once
    changes_ += current_ != 0 && target != current_;
    current_ = target;
    frames_below_ = 0;
    pending_max_ = 0;
    return current_;
  }
  if (target < current_ * params_.shrink_fraction) {
    pending_max_ = std::max(pending_max_, target);
    if (++frames_below_ >= params_.shrink_delay_frames) {
      current_ = pending_max_;
      ++changes_;
      frames_below_ = 0;
      pending_max_ = 0;
    }
  } else {
    frames_below_ = 0;
    pending_max_ = 0;
  }
  return current_;
}

namespace {
[[noreturn]] void fail(const std::filesystem::path& path, const std::string& field, const std::string& what) {
  throw CalibrationError(path.string() + ": " + field + ": " + what);
}
}  // namespace

namespace {
constexpr double kMinC = 0.01, kMaxC = 1000.0;
}  // namespace

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
  if (!j.contains("c")) fail(path, "c", "missing");
  if (!j["c"].is_number()) fail(path, "c", "expected a number");
  cal.c = j["c"].get<double>();
  // The renderer keeps c as a float: bounds that no texel count leaves keep 1e308 from becoming
  // inf and 1e-300 from becoming 0.
  if (!(cal.c >= kMinC && cal.c <= kMaxC))
    fail(path, "c", "expected a positive number in [0.01, 1000] texels, got " + json_input::printable(j["c"].dump()));
  cal.ci95_lo = cal.ci95_hi = cal.c;
  if (j.contains("ci95")) {
    const auto& ci = j["ci95"];
    if (!ci.is_array() || ci.size() != 2 || !ci[0].is_number() || !ci[1].is_number())
      fail(path, "ci95", "expected [lo, hi]");
    cal.ci95_lo = ci[0].get<double>();
    cal.ci95_hi = ci[1].get<double>();
    if (!(cal.ci95_lo > 0 && cal.ci95_lo <= cal.c && cal.c <= cal.ci95_hi && cal.ci95_hi <= kMaxC))
      fail(path, "ci95", "expected 0 < lo <= c <= hi, got " + ci.dump());
  }
  if (j.contains("condition")) {
    if (!j["condition"].is_string()) fail(path, "condition", "expected a string");
    cal.condition = j["condition"].get<std::string>();
  }
  return cal;
}

}  // namespace penumbra::adaptive
