#pragma once
// Maximum-likelihood fits of psychometric models with Ceres: one data set (a staircase, the
// `psychometric` subcommand) or many groups that share slope and lapse (the joint models).
//
//   psi(x) = gamma + (1 - gamma - lambda) F(x; alpha, beta)        (quest/psychometric.h)
//
// Parameters are fitted where the science works (docs/architecture.md, "Numerics"): the threshold
// location u (the x at which F reaches the criterion F*, ModelSpec; for the linear Weibull the log10 of that x, so u is
// always in log10 units of the stimulus ratio for study data), log beta, and lambda in
// [0, lapse_max] or fixed; alpha is derived from them (psychometric::alpha_for_threshold).
// A group's threshold is u[threshold_index] + s * offset: one u for all groups is the linear
// joint model r = c a (u = -log10 c), one u per artifact size the free per-size model, and a free
// s with offset log10(a / a_ref) the power law r = k a^p (p = 1 - s).
//
// The negative log-likelihood is minimized as a sum of squares: per row two residuals
// sqrt(-2 k log psi) and sqrt(-2 (n - k) log(1 - psi)), so cost = NLL exactly (no binomial
// coefficients). Standard errors come from ceres::Covariance on a second problem whose residuals
// sqrt(n / (psi^ (1 - psi^))) psi(x) have J^T J equal to the Fisher information at the optimum;
// parameters at a bound are held fixed there and reported as flags instead.
#include <optional>
#include <string>
#include <vector>

#include "psychometric/psychometric.h"

namespace penumbra::analysis {

// Binomial data at one stimulus level, x in the model's units (log10 ratio, or the ratio itself
// for the Weibull).
struct BinomialRow {
  double x = 0;
  double n_correct = 0;
  double n_total = 0;
};

struct Group {
  std::vector<BinomialRow> rows;
  int threshold_index = 0;
  double offset = 0;  // multiplies the power-law slope s
  // The lower asymptote of these rows when it is not ModelSpec::guess: a yes/no participant's own
  // false-alarm rate (from the catch trials). The threshold stays at ModelSpec::criterion_f() on F,
  // so groups with different guess rates share one meaning of a threshold.
  std::optional<double> guess;
};

struct LapseSpec {
  std::optional<double> fixed;  // lambda held at this value
  double max = 0.06;            // otherwise free in [0, max]
};

struct SlopeSpec {
  std::optional<double> fixed;  // beta held at this value
  double min = 0.1, max = 100;  // otherwise free in [min, max] (fitted as log beta)
};

struct ModelSpec {
  psychometric::Model family = psychometric::Model::log_weibull;
  double guess = 0.5;
  double p_threshold = 0.82;  // with criterion_lapse, the criterion F* that defines a threshold
  // A threshold is the x where F (lapse free) reaches the criterion
  //   F* = (p_threshold - guess) / (1 - guess - criterion_lapse),
  // QUEST's with criterion_lapse = delta (1 - guess) (psychometric::criterion_f). The fitted lapse
  // lowers psi's upper asymptote and does not move a threshold: defined on psi instead, c fell by
  // up to 6 % as the fitted lapse went from 0 to 0.06.
  double criterion_lapse = 0.0;
  double criterion_f() const { return psychometric::core_level(p_threshold, guess, criterion_lapse); }
  LapseSpec lapse;
  SlopeSpec slope;
  std::vector<Group> groups;
  int thresholds = 1;      // number of u parameters
  bool power_law = false;  // s free (else 0)
  // Bounds of every u (log10 units). Unset: the span of the data's x, widened by one log unit.
  std::optional<double> u_min, u_max;
};

// Starting point or result.
struct Parameters {
  std::vector<double> u;
  double s = 0;
  double log_beta = std::log(3.5);
  double lambda = 0.0;
};

struct Flags {
  std::vector<std::string> list;
  void add(const std::string& flag);
  bool has(const std::string& flag) const;
};

struct FitResult {
  Parameters params;
  double nll = 0;       // negative log-likelihood without binomial coefficients
  double deviance = 0;  // 2 (nll - nll of the saturated model over distinct x per group)
  int trials = 0;
  bool converged = false;
  int iterations = 0;
  // Covariance over [u_0 .. u_{K-1}, s, log_beta, lambda] (row-major, K + 3 square). Rows and
  // columns of parameters held fixed or at a bound are zero and `estimated` is false for them.
  std::vector<double> covariance;
  std::vector<bool> estimated;
  bool covariance_ok = false;
  Flags flags;
  double u_min = 0, u_max = 0;  // the u bounds used

  int index_s() const { return static_cast<int>(params.u.size()); }
  int index_log_beta() const { return index_s() + 1; }
  int index_lambda() const { return index_s() + 2; }
  // Standard error / correlation of parameters by index; NaN where not estimated.
  double se(int i) const;
  double correlation(int i, int j) const;
  double cov(int i, int j) const;
};

// Fits `spec`; starts from a grid search unless `start` is given. Throws std::invalid_argument for
// unusable input (no rows, non-finite or out-of-range numbers, x <= 0 for the Weibull, a guess or
// lapse outside [0, 1)). Never returns a non-finite estimate: degenerate data end at a bound,
// flagged. Flags: threshold_at_bound, slope_at_upper_bound (perfect separation: a step fits best),
// slope_at_lower_bound, lapse_at_bound, threshold_slope_correlated (|r| > 0.9), covariance_failed,
// not_converged, all_correct, none_above_chance, one_level.
// `covariance = false` skips the standard errors (bootstrap and profile fits need only the optimum).
FitResult fit(const ModelSpec& spec, const std::optional<Parameters>& start = std::nullopt, bool covariance = true);

// Same fit with u[threshold_index] held at `u_value` (profile likelihood; no covariance).
FitResult fit_with_threshold(const ModelSpec& spec, int threshold_index, double u_value, const Parameters& start);

// NLL of `spec` at `params` (double precision, the same expression the fit minimizes).
double negative_log_likelihood(const ModelSpec& spec, const Parameters& params);

struct ProfileInterval {
  double lo = NAN, hi = NAN;       // in u units
  bool lo_open = false, hi_open = false;  // the bound was reached before the likelihood fell enough
  int fits = 0;
};
// Profile-likelihood interval of u[threshold_index]: where 2 (NLL_profile - NLL_min) crosses the
// chi-square(1) quantile of `level`. With `threads` >= 2 the two ends are searched at once (the
// same fits either way).
ProfileInterval profile_interval(const ModelSpec& spec, const FitResult& best, int threshold_index,
                                 double level = 0.95, int threads = 1);

// alpha of the model at (u, beta, lambda), and its standard error by the delta method from the
// covariance of u[threshold_index], log beta and lambda (parameters held fixed or at a bound
// contribute nothing; NaN without a threshold variance).
double alpha_of(const ModelSpec& spec, double u, double beta);
double alpha_se(const ModelSpec& spec, const FitResult& fit, int threshold_index);

// Chi-square(1) quantile for a confidence level (0.95 -> 3.8415), for profile intervals.
double chi2_1_quantile(double level);

}  // namespace penumbra::analysis
