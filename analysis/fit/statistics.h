#pragma once
// Small statistics the fitter reports: chi-square tail probabilities for likelihood-ratio tests,
// percentiles for the bootstrap, robust location and spread for outlying participants.
#include <vector>

namespace penumbra::analysis {

// P(X > x) for X ~ chi-square with `dof` degrees of freedom (regularized upper incomplete gamma
// Q(dof / 2, x / 2)). 1 for x <= 0; throws std::invalid_argument for dof <= 0.
double chi2_survival(double x, double dof);

// Linearly interpolated percentile (q in [0, 1]) of unsorted values; NaN when empty.
double percentile(std::vector<double> values, double q);
double median(std::vector<double> values);
// Median absolute deviation scaled by 1.4826 (the sd for normal data).
double mad_sd(const std::vector<double>& values);

}  // namespace penumbra::analysis
