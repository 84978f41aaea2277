#include "adaptive/resolution_rule.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>

namespace penumbra::adaptive {

namespace {

// The rule's inputs are lengths and a constant of the calibration: positive and finite, or the
// call is refused with the parameter's name (a swapped or unset value would otherwise be clamped
// into a plausible resolution).
double positive_finite(const char* function, const char* parameter, double value) {
  if (!(value > 0) || !std::isfinite(value)) {
    char text[64];
    std::snprintf(text, sizeof text, "%.17g", value);
    throw std::invalid_argument(std::string(function) + ": " + parameter + " must be positive and finite, got " + text);
  }
  return value;
}

}  // namespace

double required_texels_uv(double c, FilterRadiusUv radius) {
  const double c_texels = positive_finite("required_texels_uv", "c", c);
  return c_texels / positive_finite("required_texels_uv", "radius_uv", radius.value);
}

double required_texels_ws(double c, LightExtentWs light_extent, FilterRadiusWs radius) {
  const double c_texels = positive_finite("required_texels_ws", "c", c);
  const double extent_ws = positive_finite("required_texels_ws", "light_extent_ws", light_extent.value);
  const double radius_ws = positive_finite("required_texels_ws", "radius_ws", radius.value);
  return c_texels / (radius_ws / extent_ws);  // c / r_uv; r_uv underflowing to 0 gives +inf
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

}  // namespace penumbra::adaptive
