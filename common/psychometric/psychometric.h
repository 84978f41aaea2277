#pragma once
// The one place psychometric model math lives. QUEST, QUEST+, the simulated observers, the fitter
// (analysis/) and the tests all call these functions, so a model is defined exactly once.
//
// Every function is templated on the scalar so that Ceres autodiff Jets can differentiate through
// it: math calls are unqualified (`using std::exp; exp(x)`) and resolve by argument-dependent lookup.
// Nothing here throws; invalid inputs give NaN, and callers that take user input validate first.
//
// A model is  psi(x) = gamma + (1 - gamma - lambda) * F(x; alpha, beta)
//   gamma  guess rate (0.5 in 2AFC), lambda lapse rate, F a sigmoid from 0 to 1 with location alpha
//   and slope beta. The units of x, alpha and beta per model are listed on `Model`.

#include <cmath>
#include <numbers>
#include <optional>
#include <string_view>

namespace penumbra::psychometric {

enum class Model {
  // F = 1 - exp(-(x / alpha)^beta); x and alpha linear, x > 0.
  weibull,
  // F = 1 - exp(-10^(beta (x - alpha))); x and alpha in log10 units (QUEST's form, a Gumbel in x).
  log_weibull,
  // F = Phi(beta (x - alpha)); beta = 1 / sigma.
  normal,
  // F = 1 / (1 + exp(-beta (x - alpha))).
  logistic,
};

// Parses "weibull", "log-weibull" (or "log_weibull", "gumbel"), "normal", "logistic".
inline std::optional<Model> parse_model(std::string_view name) {
  if (name == "weibull") return Model::weibull;
  if (name == "log-weibull" || name == "log_weibull" || name == "gumbel") return Model::log_weibull;
  if (name == "normal") return Model::normal;
  if (name == "logistic") return Model::logistic;
  return std::nullopt;
}

inline std::string_view model_name(Model model) {
  switch (model) {
    case Model::weibull: return "weibull";
    case Model::log_weibull: return "log-weibull";
    case Model::normal: return "normal";
    case Model::logistic: return "logistic";
  }
  return "unknown";
}

template <typename T>
struct Params {
  T alpha;   // location (model units, see Model)
  T beta;    // slope
  T gamma;   // guess rate
  T lambda;  // lapse rate
};

// The plain value of a scalar or of a Ceres Jet (its `.a`), for starting iterations.
inline double scalar_value(double v) { return v; }
template <typename J>
auto scalar_value(const J& jet) -> decltype(scalar_value(jet.a)) {
  return scalar_value(jet.a);
}

// erf^-1 for double: a single-precision start (Giles 2010) polished by Newton steps on erf.
inline double inverse_erf(double y) {
  if (!(y > -1.0 && y < 1.0)) return y == 1.0 ? INFINITY : (y == -1.0 ? -INFINITY : NAN);
  // Initial guess (Giles 2010 single-precision approximation), then Newton steps on erf.
  double w = -std::log((1.0 - y) * (1.0 + y));
  double x;
  if (w < 5.0) {
    w -= 2.5;
    double p = 2.81022636e-08;
    p = 3.43273939e-07 + p * w;
    p = -3.5233877e-06 + p * w;
    p = -4.39150654e-06 + p * w;
    p = 0.00021858087 + p * w;
    p = -0.00125372503 + p * w;
    p = -0.00417768164 + p * w;
    p = 0.246640727 + p * w;
    p = 1.50140941 + p * w;
    x = p * y;
  } else {
    w = std::sqrt(w) - 3.0;
    double p = -0.000200214257;
    p = 0.000100950558 + p * w;
    p = 0.00134934322 + p * w;
    p = -0.00367342844 + p * w;
    p = 0.00573950773 + p * w;
    p = -0.0076224613 + p * w;
    p = 0.00943887047 + p * w;
    p = 1.00167406 + p * w;
    p = 2.83297682 + p * w;
    x = p * y;
  }
  const double two_over_sqrt_pi = 2.0 / std::sqrt(std::numbers::pi);
  for (int i = 0; i < 3; ++i) {
    const double err = std::erf(x) - y;
    x -= err / (two_over_sqrt_pi * std::exp(-x * x));
  }
  return x;
}

template <typename T>
T pow10(const T& y) {
  using std::pow;
  return pow(10.0, y);
}

// F(x): the sigmoid core, rising from 0 to 1.
template <typename T>
T core(Model model, const T& x, const T& alpha, const T& beta) {
  using std::erfc;
  using std::exp;
  using std::pow;
  switch (model) {
    case Model::weibull:
      return T(1.0) - exp(-pow(x / alpha, beta));
    case Model::log_weibull:
      return T(1.0) - exp(-pow10(T(beta * (x - alpha))));
    case Model::normal:
      return T(0.5) * erfc(-beta * (x - alpha) / T(std::numbers::sqrt2));
    case Model::logistic:
      return T(1.0) / (T(1.0) + exp(-beta * (x - alpha)));
  }
  return T(NAN);
}

// F(x) and 1 - F(x) together, each with its own relative precision (1 - F where F is close to 1,
// F where it is close to 0): what a likelihood needs for log(psi) and log(1 - psi).
template <typename T>
void core_and_complement(Model model, const T& x, const T& alpha, const T& beta, T* f, T* f_complement) {
  using std::erfc;
  using std::exp;
  using std::expm1;
  using std::pow;
  switch (model) {
    case Model::weibull:
    case Model::log_weibull: {
      const T z = model == Model::weibull ? T(pow(x / alpha, beta)) : pow10(T(beta * (x - alpha)));
      *f = -expm1(-z);
      *f_complement = exp(-z);
      return;
    }
    case Model::normal:
      *f = T(0.5) * erfc(-beta * (x - alpha) / T(std::numbers::sqrt2));
      *f_complement = T(0.5) * erfc(beta * (x - alpha) / T(std::numbers::sqrt2));
      return;
    case Model::logistic:
      *f = T(1.0) / (T(1.0) + exp(-beta * (x - alpha)));
      *f_complement = T(1.0) / (T(1.0) + exp(beta * (x - alpha)));
      return;
  }
  *f = *f_complement = T(NAN);
}

// Inverse of the core: the x at which F(x) = f, for 0 < f < 1.
template <typename T>
T core_inverse(Model model, const T& f, const T& alpha, const T& beta) {
  using std::log;
  using std::log10;
  using std::pow;
  switch (model) {
    case Model::weibull:
      return alpha * pow(-log(T(1.0) - f), T(1.0) / beta);
    case Model::log_weibull:
      return alpha + log10(-log(T(1.0) - f)) / beta;
    case Model::normal: {
      // One Newton step in T on top of the double solve carries the derivative for Jets.
      using std::erf;
      using std::exp;
      const T y = T(2.0) * f - T(1.0);
      T z = T(inverse_erf(scalar_value(y)));
      z = z - (erf(z) - y) / (T(2.0 / std::sqrt(std::numbers::pi)) * exp(-z * z));
      return alpha + T(std::numbers::sqrt2) * z / beta;
    }
    case Model::logistic:
      return alpha + log(f / (T(1.0) - f)) / beta;
  }
  return T(NAN);
}

// psi(x): probability of a correct (or "yes") response.
template <typename T>
T probability(Model model, const T& x, const Params<T>& params) {
  return params.gamma +
         (T(1.0) - params.gamma - params.lambda) * core(model, x, params.alpha, params.beta);
}

// The core value f = F(x) at which psi(x) = p_correct; outside (0, 1) when psi never reaches it.
template <typename T>
T core_level(const T& p_correct, const T& gamma, const T& lambda) {
  return (p_correct - gamma) / (T(1.0) - gamma - lambda);
}

// The threshold: the x at which psi(x) = p_correct. NaN when psi never reaches p_correct.
template <typename T>
T threshold(Model model, const T& p_correct, const Params<T>& params) {
  const T f = core_level(p_correct, params.gamma, params.lambda);
  if (!(f > T(0.0) && f < T(1.0))) return T(NAN);
  return core_inverse(model, f, params.alpha, params.beta);
}

// The location alpha that puts the threshold (psi = p_correct) at `threshold_x`: lets a planted
// observer or a fitter be parameterised by its threshold, the quantity the study reports.
template <typename T>
T alpha_for_threshold(Model model, const T& threshold_x, const T& p_correct, const T& beta,
                      const T& gamma, const T& lambda) {
  using std::pow;
  const T f = core_level(p_correct, gamma, lambda);
  if (!(f > T(0.0) && f < T(1.0))) return T(NAN);
  if (model == Model::weibull) return threshold_x / core_inverse(model, f, T(1.0), beta);
  return threshold_x - core_inverse(model, f, T(0.0), beta);
}

// Psychtoolbox's QUEST table entry, written exactly as QuestRecompute.m evaluates it so that the
// table is bit-identical: delta*gamma + (1-delta)*(1-(1-gamma)*exp(-10^(beta*x))).
// It is the log_weibull model with lapse lambda = delta * (1 - gamma) and alpha = 0.
template <typename T>
T quest_weibull(const T& x, const T& beta, const T& delta, const T& gamma) {
  using std::exp;
  return delta * gamma + (T(1.0) - delta) * (T(1.0) - (T(1.0) - gamma) * exp(-pow10(T(beta * x))));
}

template <typename T>
T quest_lapse(const T& delta, const T& gamma) {
  return delta * (T(1.0) - gamma);
}

// The detection probability F* that defines a study's threshold, as QUEST defines it: QUEST's
// model reaches p_correct where F = F*, its fixed lapse being delta (1 - gamma), so
//   F* = (p_correct - gamma) / ((1 - gamma) (1 - delta)),
// 0.6465 for 2AFC at 0.82 with delta 0.01. A threshold on F does not move with an observer's (or a
// fit's) own lapse, which only lowers the upper asymptote of psi.
inline double criterion_f(double p_correct, double gamma, double quest_delta) {
  return core_level(p_correct, gamma, quest_lapse(quest_delta, gamma));
}

// The x at which F reaches `f`, for a model whose F reaches `criterion` at `threshold_x`: the
// threshold at another detection probability on the same psychometric function. NaN outside (0, 1).
inline double threshold_at(Model model, double threshold_x, double criterion, double f, double beta) {
  if (!(criterion > 0.0 && criterion < 1.0 && f > 0.0 && f < 1.0 && beta > 0.0)) return NAN;
  if (model == Model::weibull) {
    const double alpha = threshold_x / core_inverse(model, criterion, 1.0, beta);
    return core_inverse(model, f, alpha, beta);
  }
  const double alpha = threshold_x - core_inverse(model, criterion, 0.0, beta);
  return core_inverse(model, f, alpha, beta);
}

}  // namespace penumbra::psychometric
