#pragma once
// The multilevel (hierarchical) fit of a study (issue 48): c for a population of observers, not for
// the sample that was measured.
//
//   log10 c_jk = m_k + b_j,   b_j ~ N(0, sd^2)
//
// m_k: condition k's population mean of log10 c (a fixed effect; 10^m_k is the population's
// geometric-mean c, the median observer's); b_j: participant j's offset, the same in every
// condition (a random effect on log c, integrated out). The observer at percentile p of the
// population has log10 c = m_k + z_p sd (z_0.9 = 1.2816).
//
// The likelihood integrates b_j numerically: each participant's likelihood in condition k as a
// function of its threshold u = -log10 c is tabulated once (slope and lapse held at the condition's
// joint fit, ConditionFit::linear; a cubic through the table), and the product over conditions is
// integrated against the normal density on a fixed grid of 121 normal deviates in [-6, 6]
// (trapezoid rule: spacing sd / 10, fine beside the width of a participant's likelihood at the
// spreads people show). Ceres minimizes the marginal negative log-likelihood as a sum of squares,
// one residual sqrt(2 NLL_j) per participant, with its analytic gradient through the tables.
//
// Intervals are profile likelihood: the quantity held, the rest refitted. For the population mean
// and a percentile the cut-off is the squared Student t quantile with participants - 1 degrees of
// freedom in place of chi2(1) (with 6-10 participants the between-participant spread is estimated
// from few values and the chi2 cut-off under-covers, as a z interval for a mean with estimated
// variance does); for sd the chi2(1) cut-off, closed at 0 when sd 0 is within it.
#include <string>
#include <vector>

#include "fit/model_fit.h"

namespace penumbra::analysis {

// One participant's data: per condition (index into the conditions) its groups (any artifact size:
// the linear model's threshold does not depend on it).
struct MultilevelParticipant {
  std::string name;
  std::vector<std::vector<Group>> conditions;  // empty where the participant lacks a condition
};

struct MultilevelInput {
  // Each condition's model (family, guess, criterion) and its joint fit's slope and lapse, held.
  std::vector<ModelSpec> condition_specs;
  std::vector<double> log_beta, lambda;
  std::vector<double> u_start;  // each condition's joint-fit threshold (a start and the table's centre)
  std::vector<MultilevelParticipant> participants;
};

struct MultilevelInterval {
  double lo = NAN, hi = NAN;
  bool lo_open = false, hi_open = false;
};

struct MultilevelFit {
  bool fitted = false;       // false: fewer than 2 participants (no spread to estimate)
  bool converged = false;
  int participants = 0;
  double nll = NAN;
  double percentile = 0.9;   // the observer percentile asked for
  double z = NAN;            // its normal deviate
  double level = 0.95;
  double t_cutoff = NAN;     // the profile cut-off of means and percentiles (t_{N-1} squared)
  double sd_log10 = NAN;     // between-participant sd of log10 c
  MultilevelInterval sd_ci;
  struct Condition {
    double log10_c = NAN;                 // m_k
    double mean_c = NAN;                  // 10^m_k: the population's median observer
    MultilevelInterval mean_c_ci;         // at `level`
    MultilevelInterval mean_c_ci_simultaneous;  // at 1 - (1 - level) / K (Bonferroni over the K conditions)
    double percentile_c = NAN;            // 10^(m_k + z sd)
    MultilevelInterval percentile_c_ci;
    MultilevelInterval percentile_c_ci_simultaneous;
  };
  std::vector<Condition> conditions;
  // The worst condition of the population: the largest m_k, and an interval for the largest true
  // m_k that needs no test of whether the conditions differ: [max_k lo_k, max_k hi_k] of the
  // simultaneous intervals covers max_k m_k whenever all K cover their own, so its coverage is at
  // least `level` whatever the differences (0, 5, 10 % or clear); likewise for the percentile.
  int worst = 0;
  MultilevelInterval worst_mean_c_ci, worst_percentile_c_ci;
  Flags flags;  // sd_at_zero (the data show no spread), not_converged
};

// Throws std::invalid_argument for a percentile outside (0, 1) or a level outside (0, 1).
MultilevelFit fit_multilevel(const MultilevelInput& input, double percentile, double level);

// Student t quantile with `dof` degrees of freedom (Cornish-Fisher expansion about the normal;
// within 0.01 of the exact value for dof >= 3 at 0.975, exact normal as dof grows).
double student_t_quantile(double p, double dof);

}  // namespace penumbra::analysis
