#include "stats/pareto.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

#include "sampling/random.h"
#include "stats/summary.h"

namespace penumbra::stats {

double interpolate_cost(double lo, double hi, double weight) {
  if (weight <= 0) return lo;
  if (weight >= 1) return hi;
  if (lo > 0 && hi > 0) return std::exp((1 - weight) * std::log(lo) + weight * std::log(hi));
  return (1 - weight) * lo + weight * hi;
}

std::vector<std::size_t> pareto_front(std::span<const Candidate> candidates) {
  std::vector<std::size_t> order;
  for (std::size_t i = 0; i < candidates.size(); ++i)
    if (!std::isnan(candidates[i].error) && !std::isnan(candidates[i].cost)) order.push_back(i);
  // By error, then cost, then index: a sweep keeps each candidate cheaper than every one before it.
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    if (candidates[a].error != candidates[b].error) return candidates[a].error < candidates[b].error;
    return candidates[a].cost < candidates[b].cost;
  });
  std::vector<std::size_t> front;
  for (const std::size_t i : order)
    if (front.empty() || candidates[i].cost < candidates[front.back()].cost) front.push_back(i);
  return front;
}

std::string_view to_string(FrontReading::Position p) {
  switch (p) {
    case FrontReading::Position::on_front: return "on_front";
    case FrontReading::Position::more_accurate: return "more_accurate_than_front";
    case FrontReading::Position::less_accurate: return "less_accurate_than_front";
  }
  return "?";
}

FrontReading read_front(std::span<const Candidate> candidates, std::span<const std::size_t> front, double error) {
  if (front.empty()) throw std::invalid_argument("read_front: the front is empty");
  if (std::isnan(error)) throw std::invalid_argument("read_front: the error is NaN");
  FrontReading r;
  const Candidate& best = candidates[front.front()];
  const Candidate& cheapest = candidates[front.back()];
  if (error < best.error) {
    r.position = FrontReading::Position::more_accurate;
    r.lo = r.hi = front.front();
    r.cost = best.cost;
    return r;
  }
  if (error > cheapest.error) {
    r.position = FrontReading::Position::less_accurate;
    r.lo = r.hi = front.back();
    r.cost = cheapest.cost;
    return r;
  }
  for (std::size_t k = 0; k + 1 < front.size(); ++k) {
    const Candidate& a = candidates[front[k]];
    const Candidate& b = candidates[front[k + 1]];
    if (error > b.error) continue;
    r.lo = front[k], r.hi = front[k + 1];
    r.weight = b.error > a.error ? (error - a.error) / (b.error - a.error) : 0.0;
    r.cost = interpolate_cost(a.cost, b.cost, r.weight);
    return r;
  }
  r.lo = r.hi = front.back();  // a one-point front, error equal to its own
  r.cost = cheapest.cost;
  return r;
}

RatioInterval paired_ratio(std::span<const double> lo_cost, std::span<const double> hi_cost, double weight,
                           std::span<const double> cost, int resamples, std::uint64_t seed) {
  if (lo_cost.size() != cost.size() || hi_cost.size() != cost.size())
    throw std::invalid_argument("paired_ratio: the series differ in length");
  std::vector<double> ratios;
  for (std::size_t i = 0; i < cost.size(); ++i) {
    const double front = interpolate_cost(lo_cost[i], hi_cost[i], weight);
    if (std::isfinite(front) && std::isfinite(cost[i]) && cost[i] > 0) ratios.push_back(front / cost[i]);
  }
  RatioInterval out;
  out.n = ratios.size();
  if (ratios.empty()) {
    out.median = out.lo = out.hi = NAN;
    return out;
  }
  out.median = median(ratios);
  std::vector<double> medians;
  medians.reserve(static_cast<std::size_t>(std::max(resamples, 1)));
  sampling::Random random(seed);
  std::vector<double> sample(ratios.size());
  const int last = static_cast<int>(ratios.size()) - 1;
  for (int b = 0; b < std::max(resamples, 1); ++b) {
    for (double& x : sample) x = ratios[static_cast<std::size_t>(random.integer(0, last))];
    medians.push_back(median(sample));
  }
  out.lo = percentile(medians, 0.025);
  out.hi = percentile(medians, 0.975);
  return out;
}

}  // namespace penumbra::stats
