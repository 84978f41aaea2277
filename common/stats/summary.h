#pragma once
// Percentiles, the median and a five-number spread: the one definition the timers, the fitter,
// the QUEST simulations and the demo's tables share (header only).
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace penumbra::stats {

// Linearly interpolated percentile (q in [0, 1], clamped) of unsorted values: between the two
// order statistics around q·(n - 1). NaN when empty; NaN values are not allowed (their order is
// undefined).
inline double percentile(std::vector<double> values, double q) {
  if (values.empty()) return NAN;
  std::sort(values.begin(), values.end());
  const double pos = std::clamp(q, 0.0, 1.0) * static_cast<double>(values.size() - 1);
  const auto i = static_cast<std::size_t>(std::floor(pos));
  const std::size_t j = std::min(i + 1, values.size() - 1);
  const double fraction = pos - static_cast<double>(i);
  if (fraction == 0) return values[i];  // an order statistic itself (also when a neighbour is infinite)
  return values[i] + fraction * (values[j] - values[i]);
}

// The middle value; the mean of the two middle values for an even count. NaN when empty.
inline double median(std::vector<double> values) { return percentile(std::move(values), 0.5); }

// Median, 10th and 90th percentiles (interpolated as percentile()), minimum and maximum; all 0
// when empty (a table row with nothing measured).
struct Spread {
  double median = 0, p10 = 0, p90 = 0, min = 0, max = 0;
};
inline Spread spread(std::vector<double> values) {
  Spread s;
  if (values.empty()) return s;
  std::sort(values.begin(), values.end());
  s.median = percentile(values, 0.5), s.p10 = percentile(values, 0.1), s.p90 = percentile(values, 0.9);
  s.min = values.front(), s.max = values.back();
  return s;
}

}  // namespace penumbra::stats
