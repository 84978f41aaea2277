// The image observer's curve from its deviations and its decision noise fitted to a threshold
// (observer_curve.h).
#include "observers/observer_curve.h"

#include <algorithm>
#include <limits>
#include <stdexcept>
#include <string>

namespace penumbra::observers {

double curve_p_correct(const CurvePoint& point, const std::vector<int>& pick, double weber) {
  double jagged = 0, straight = 0;
  for (const int s : pick) {
    jagged += point.jagged[static_cast<std::size_t>(s)] / static_cast<double>(pick.size());
    straight += point.straight[static_cast<std::size_t>(s)] / static_cast<double>(pick.size());
  }
  return 0.5 * std::erfc(-(jagged - straight) / (2 * weber));  // Phi(d / (sqrt2 w))
}

ImpliedC implied_c(const std::vector<CurvePoint>& points, const std::vector<int>& pick, double weber, double p_threshold) {
  ImpliedC curve;
  double last_ratio = NAN, last_p = NAN;
  for (const CurvePoint& point : points) {
    const double p = curve_p_correct(point, pick, weber);
    if (p >= p_threshold) {
      curve.c = NAN;
      curve.at_most = false;
    } else if (std::isnan(curve.c)) {  // crossed down: interpolate in log r/a
      curve.at_most = std::isnan(last_p);
      curve.c = curve.at_most ? point.ratio
                              : last_ratio * std::pow(point.ratio / last_ratio, (last_p - p_threshold) / (last_p - p));
    }
    last_ratio = point.ratio;
    last_p = p;
  }
  return curve;
}

double condition_c(const std::vector<std::vector<CurvePoint>>& per_artifact, const std::vector<int>& pick, double weber,
                   double p_threshold) {
  double log_sum = 0;
  int count = 0;
  for (const auto& points : per_artifact) {
    const ImpliedC curve = implied_c(points, pick, weber, p_threshold);
    if (std::isnan(curve.c)) continue;
    log_sum += std::log(curve.c);
    ++count;
  }
  return count ? std::exp(log_sum / count) : NAN;
}

// The least-squares slope of log10(-ln(1 - F)) on x, F = (P - 0.5) / 0.5 (the observer has no
// lapse), over the points with F in [0.02, 0.98]: the curve is noise-free, and beyond those the
// transform only amplifies the rendering's rounding.
double condition_slope(const std::vector<std::vector<CurvePoint>>& per_artifact, const std::vector<int>& pick, double weber,
                       double p_threshold) {
  double n = 0, sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (const auto& points : per_artifact) {
    const ImpliedC curve = implied_c(points, pick, weber, p_threshold);
    if (std::isnan(curve.c) || curve.at_most) continue;
    for (const CurvePoint& point : points) {
      const double f = (curve_p_correct(point, pick, weber) - 0.5) / 0.5;
      if (!(f >= 0.02 && f <= 0.98)) continue;
      const double x = std::log10(curve.c / point.ratio), y = std::log10(-std::log(1 - f));
      n += 1;
      sx += x;
      sy += y;
      sxx += x * x;
      sxy += x * y;
    }
  }
  const double var = sxx - sx * sx / n;
  if (n < 3 || !(var > 0)) return NAN;
  return (sxy - sx * sy / n) / var;
}

double replicate_c(const ConditionCurves& curves, double weber, double p_threshold) {
  if (curves.empty()) throw std::invalid_argument("replicate_c: a condition without artifact sizes");
  double log_sum = 0;
  for (const auto& points : curves) {
    if (points.empty()) throw std::invalid_argument("replicate_c: an artifact size without radii");
    std::vector<int> pick(points.front().jagged.size());
    for (std::size_t s = 0; s < pick.size(); ++s) pick[s] = static_cast<int>(s);
    const ImpliedC curve = implied_c(points, pick, weber, p_threshold);
    if (std::isnan(curve.c)) return std::numeric_limits<double>::infinity();
    log_sum += std::log(curve.c);
  }
  return std::exp(log_sum / static_cast<double>(curves.size()));
}

double mean_c(const std::vector<ConditionCurves>& replicates, double weber, double p_threshold) {
  if (replicates.empty()) throw std::invalid_argument("mean_c: no replicates");
  double log_sum = 0;
  for (const ConditionCurves& curves : replicates) {
    const double c = replicate_c(curves, weber, p_threshold);
    if (std::isinf(c)) return c;
    log_sum += std::log(c);
  }
  return std::exp(log_sum / static_cast<double>(replicates.size()));
}

WeberFit fit_weber(const std::vector<ConditionCurves>& replicates, double target_c, double p_threshold) {
  // A c beyond a grid's radii is no threshold of it: the grid's largest ratio is a bound, not a c.
  double first = 0, last = std::numeric_limits<double>::infinity();
  for (const ConditionCurves& curves : replicates)
    for (const auto& points : curves)
      if (!points.empty()) {
        first = std::max(first, points.front().ratio);
        last = std::min(last, points.back().ratio);
      }
  if (!(target_c > first && target_c < last))
    throw std::invalid_argument("fit_weber: c " + std::to_string(target_c) + " is outside the radius grid (r/a " + std::to_string(first) +
                                " to " + std::to_string(last) + ")");
  double lo = std::log(1e-6), hi = std::log(1.0);  // c(lo) >= target >= c(hi)
  const double c_lo = mean_c(replicates, std::exp(lo), p_threshold), c_hi = mean_c(replicates, std::exp(hi), p_threshold);
  if (!(c_lo >= target_c) || !(c_hi <= target_c))
    throw std::invalid_argument("fit_weber: c " + std::to_string(target_c) + " is outside what the radius grid shows (" +
                                std::to_string(c_hi) + " to " + std::to_string(c_lo) + " over weber 1 to 1e-6)");
  for (int i = 0; i < 100 && hi - lo > 1e-12; ++i) {
    const double mid = 0.5 * (lo + hi);
    if (mean_c(replicates, std::exp(mid), p_threshold) > target_c) {
      lo = mid;
    } else {
      hi = mid;
    }
  }
  WeberFit fit;
  // Of the two ends the one whose c is nearer the target (they differ only across a jump).
  const double c_at_lo = mean_c(replicates, std::exp(lo), p_threshold), c_at_hi = mean_c(replicates, std::exp(hi), p_threshold);
  const bool take_lo = std::abs(std::log(c_at_lo / target_c)) < std::abs(std::log(c_at_hi / target_c));
  fit.weber = std::exp(take_lo ? lo : hi);
  fit.c = take_lo ? c_at_lo : c_at_hi;
  return fit;
}

}  // namespace penumbra::observers
