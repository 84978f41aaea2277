#pragma once
// The image observer's 2afc psychometric curve read from its noise-free deviations, and its one
// decision parameter (`weber`) fitted to a threshold. GL-free: the deviations come from renders
// (penumbra-observer-curve, penumbra-observer-fit), the arithmetic here is shared by both.
//
// The deviations do not depend on `weber` (it only scales the decision noise), so a curve is
// rendered once and read at any weber: P(correct) = Phi(diff / (sqrt 2 weber)), and the implied
// c is the r / a beyond which P stays below p_threshold.
#include <cmath>
#include <vector>

namespace penumbra::observers {

// One radius of one artifact size: the observer's deviations per stimulus (seed: phase, orientation).
struct CurvePoint {
  double ratio = 0;  // r / a
  std::vector<double> jagged, straight;
};

struct ImpliedC {
  double c = NAN;        // r / a beyond which P stays below p_threshold; NAN: above it at the largest ratio
  bool at_most = false;  // P was below p_threshold from the first ratio on: c <= the first ratio
};

// 2afc P(correct) at one radius over the stimuli `pick` (indices into the seeds, repeats allowed).
double curve_p_correct(const CurvePoint& point, const std::vector<int>& pick, double weber);

// The r / a beyond which P stays below p_threshold, interpolated in log r / a at the last crossing.
ImpliedC implied_c(const std::vector<CurvePoint>& points, const std::vector<int>& pick, double weber, double p_threshold);

// A condition's c as penumbra-fit's one c per condition would see it: the geometric mean over
// artifact sizes (those that crossed); NAN when none did.
double condition_c(const std::vector<std::vector<CurvePoint>>& per_artifact, const std::vector<int>& pick, double weber,
                   double p_threshold);

// The log-Weibull beta of a condition's curve, pooled over the artifact sizes that crossed, each
// size's x = log10(a / r) taken from its own threshold (docs/study.md, "The observer's own slope").
// NAN with fewer than three points with F in [0.02, 0.98].
double condition_slope(const std::vector<std::vector<CurvePoint>>& per_artifact, const std::vector<int>& pick, double weber,
                       double p_threshold);

// One replicate of a condition (one radius grid with its own stimuli): artifact size -> radius.
using ConditionCurves = std::vector<std::vector<CurvePoint>>;

// A condition's c on one replicate for the fit: the geometric mean over its artifact sizes, every
// size counted (unlike condition_c): +infinity when a size is still above p_threshold at the
// largest ratio (c beyond the grid), an at-most size at its first ratio. All its seeds are used.
double replicate_c(const ConditionCurves& curves, double weber, double p_threshold);

// The geometric mean of replicate_c over the replicates: the condition's c with the radius grid
// and the stimuli averaged out. +infinity when any replicate's is.
double mean_c(const std::vector<ConditionCurves>& replicates, double weber, double p_threshold);

struct WeberFit {
  double weber = NAN;
  double c = NAN;  // mean_c at that weber: the target, unless the target falls into a jump of c
};

// The weber at which mean_c equals target_c: bisection in log weber over [1e-6, 1] (c falls as
// weber grows: a larger decision noise needs a larger deviation, which a smaller filter leaves).
// c is a step function where a curve is not monotone (the stair's nulls): a target inside a jump
// gives the jump's weber, and `c` says what it reaches. Throws std::invalid_argument when the
// target is outside what the grid can show (outside its radii, or above mean_c at 1e-6 or below
// it at 1).
WeberFit fit_weber(const std::vector<ConditionCurves>& replicates, double target_c, double p_threshold);

}  // namespace penumbra::observers
