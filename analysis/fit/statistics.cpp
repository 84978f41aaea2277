#include "fit/statistics.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace penumbra::analysis {

namespace {

// Regularized lower incomplete gamma P(a, x) by its power series (converges well for x < a + 1).
double gamma_p_series(double a, double x) {
  double term = 1.0 / a, sum = term;
  for (int n = 1; n < 1000; ++n) {
    term *= x / (a + n);
    sum += term;
    if (std::abs(term) < std::abs(sum) * 1e-16) break;
  }
  return sum * std::exp(-x + a * std::log(x) - std::lgamma(a));
}

// Regularized upper incomplete gamma Q(a, x) by its continued fraction (modified Lentz; x >= a + 1).
double gamma_q_fraction(double a, double x) {
  constexpr double tiny = 1e-300;
  double b = x + 1.0 - a, c = 1.0 / tiny, d = 1.0 / b, h = d;
  for (int i = 1; i < 1000; ++i) {
    const double an = -i * (i - a);
    b += 2.0;
    d = an * d + b;
    if (std::abs(d) < tiny) d = tiny;
    c = b + an / c;
    if (std::abs(c) < tiny) c = tiny;
    d = 1.0 / d;
    const double delta = d * c;
    h *= delta;
    if (std::abs(delta - 1.0) < 1e-16) break;
  }
  return std::exp(-x + a * std::log(x) - std::lgamma(a)) * h;
}

}  // namespace

double chi2_survival(double x, double dof) {
  if (!(dof > 0)) throw std::invalid_argument("chi2_survival: degrees of freedom must be positive");
  if (std::isnan(x)) return NAN;
  if (x <= 0) return 1.0;
  const double a = 0.5 * dof, z = 0.5 * x;
  return z < a + 1.0 ? 1.0 - gamma_p_series(a, z) : gamma_q_fraction(a, z);
}

double mad_sd(const std::vector<double>& values) {
  const double m = median(values);
  std::vector<double> deviations;
  for (double v : values) deviations.push_back(std::abs(v - m));
  return 1.4826 * median(deviations);
}

}  // namespace penumbra::analysis
