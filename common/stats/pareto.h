#pragma once
// The Pareto front of configurations measured by an error (lower is better) and a cost (frame
// time, memory; lower is better), the cost the front implies at a given error, and the paired
// per-frame ratio against it with a bootstrap interval: how penumbra-demo states "adaptive
// against the engine's best at equal error".
//
// Reading the front at an error between two of its points interpolates the cost geometrically
// (log-linear in the error: costs come in powers of two, and a straight line on a log axis is
// what the plot draws); for a front that bends toward the origin this is the lower, more
// conservative of the two readings. Outside the front's error range there is no engine configuration of that error: the
// reading says on which side it fell and takes the nearest end, so a ratio there is a bound, not
// an estimate (more accurate than the front's best: the engine would pay at least that end's cost;
// less accurate than its cheapest: at most).
#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

namespace penumbra::stats {

struct Candidate {
  double error = 0;  // e.g. RMSE against the reference
  double cost = 0;   // e.g. median frame ms, or texels allocated
};

// Indices of the candidates no other candidate dominates (error <= and cost <=, one of them
// strictly), ordered by error ascending, hence cost descending. Of candidates equal in both, the
// first is kept. Candidates with a NaN error or cost are never on the front.
std::vector<std::size_t> pareto_front(std::span<const Candidate> candidates);

struct FrontReading {
  enum class Position {
    on_front,        // error within the front's range: cost interpolated between lo and hi
    more_accurate,   // error below the front's smallest: lo = hi = its most accurate point
    less_accurate,   // error above the front's largest: lo = hi = its cheapest point
  };
  Position position = Position::on_front;
  std::size_t lo = 0, hi = 0;  // candidate indices: lo the more accurate (costlier) neighbour
  double weight = 0;           // cost = interpolate_cost(cost[lo], cost[hi], weight)
  double cost = 0;
};
std::string_view to_string(FrontReading::Position p);

// lo^(1 - weight) · hi^weight for positive costs (linear where one is not positive); lo at
// weight <= 0, hi at weight >= 1.
double interpolate_cost(double lo, double hi, double weight);

// The front's cost at `error` (front: from pareto_front over the same candidates). Throws
// std::invalid_argument for an empty front or a NaN error.
FrontReading read_front(std::span<const Candidate> candidates, std::span<const std::size_t> front, double error);

// Paired per-frame ratios r_i = interpolate_cost(lo_i, hi_i, weight) / cost_i, e.g. the engine's
// frame time at equal error over the adaptive frame time, frame by frame along one path. `median`
// is the median of r_i; [lo, hi] its 95 % percentile bootstrap interval (frames resampled with
// replacement `resamples` times from a fixed seed: the same numbers every run). Frames where a
// cost is not finite or cost_i <= 0 are left out; none left: NaNs and n = 0. Throws
// std::invalid_argument when the three series differ in length.
struct RatioInterval {
  double median = 0, lo = 0, hi = 0;
  std::size_t n = 0;  // frames used
};
RatioInterval paired_ratio(std::span<const double> lo_cost, std::span<const double> hi_cost, double weight,
                           std::span<const double> cost, int resamples = 2000, std::uint64_t seed = 1);

}  // namespace penumbra::stats
