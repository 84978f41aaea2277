#include "adaptive/resolution_rule.h"

#include <algorithm>
#include <cmath>
#include <limits>

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

}  // namespace penumbra::adaptive
