#include "adaptive/cascades.h"

#include <algorithm>
#include <cmath>

namespace penumbra::adaptive {

std::vector<double> cascade_splits(double near_ws, double far_ws, int count, double lambda) {
  count = std::max(count, 1);
  if (!std::isfinite(lambda)) lambda = 1;
  lambda = std::clamp(lambda, 0.0, 1.0);
  if (!std::isfinite(far_ws) || far_ws <= 0) far_ws = 1;
  if (!std::isfinite(near_ws) || near_ws <= 0) near_ws = far_ws * 1e-4;
  if (far_ws <= near_ws) far_ws = near_ws * (1 + 1e-3);
  std::vector<double> z(static_cast<std::size_t>(count) + 1);
  for (int i = 0; i <= count; ++i) {
    const double t = static_cast<double>(i) / count;
    const double log_split = near_ws * std::pow(far_ws / near_ws, t);
    const double uniform_split = near_ws + (far_ws - near_ws) * t;
    z[static_cast<std::size_t>(i)] = lambda * log_split + (1 - lambda) * uniform_split;
  }
  z.front() = near_ws;  // exact ends, whatever the rounding of pow
  z.back() = far_ws;
  return z;
}

CascadeChoice choose_cascade_count(int max_count, double max_texels,
                                   const std::function<std::vector<double>(int)>& required) {
  max_count = std::max(max_count, 1);
  CascadeChoice choice;
  for (int n = 1; n <= max_count; ++n) {
    choice.count = n;
    choice.required_texels = required(n);
    choice.fits = std::all_of(choice.required_texels.begin(), choice.required_texels.end(),
                              [&](double r) { return r <= max_texels; });  // NaN compares false
    if (choice.fits) return choice;
  }
  return choice;
}

}  // namespace penumbra::adaptive
