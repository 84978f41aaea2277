#pragma once
// Small statistics the fitter reports: chi-square tail probabilities for likelihood-ratio tests,
// percentiles for the bootstrap, robust location and spread for outlying participants.
#include <vector>

#include "stats/summary.h"

namespace penumbra::analysis {

// P(X > x) for X ~ chi-square with `dof` degrees of freedom (regularized upper incomplete gamma
// Q(dof / 2, x / 2)). 1 for x <= 0; throws std::invalid_argument for dof <= 0.
double chi2_survival(double x, double dof);

// Linearly interpolated percentile and median (common/stats/summary.h).
using stats::median;
using stats::percentile;
// Median absolute deviation scaled by 1.4826 (the sd for normal data).
double mad_sd(const std::vector<double>& values);

}  // namespace penumbra::analysis
