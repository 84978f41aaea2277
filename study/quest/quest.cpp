#include "quest/quest.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "psychometric/psychometric.h"

namespace penumbra::quest {
namespace {

// The largest table QuestCreate is allowed to build here (Psychtoolbox has no limit and simply
// runs out of memory); 10^7 points is 80 MB per vector.
constexpr double kMaxDim = 1e7;

std::string format(const char* fmt, double a, double b = 0.0, double c = 0.0) {
  char buffer[256];
  std::snprintf(buffer, sizeof buffer, fmt, a, b, c);
  return buffer;
}

void require(bool ok, const std::string& message) {
  if (!ok) throw std::invalid_argument(message);
}

// MATLAB/Octave interp1(xs, ys, xi, 'linear') for strictly increasing xs: NaN outside
// [xs.front(), xs.back()], and the same arithmetic as Octave's ppval (slope * dx + y_k).
double interp1(const std::vector<double>& xs, const std::vector<double>& ys, double xi) {
  const std::size_t n = xs.size();
  if (n < 2 || !(xi >= xs.front() && xi <= xs.back())) return NAN;
  std::size_t k = static_cast<std::size_t>(std::upper_bound(xs.begin(), xs.end(), xi) - xs.begin());
  k = std::min(k == 0 ? 0 : k - 1, n - 2);
  const double slope = (ys[k + 1] - ys[k]) / (xs[k + 1] - xs[k]);
  return slope * (xi - xs[k]) + ys[k];
}

double sum(const std::vector<double>& v) {
  double total = 0.0;
  for (double value : v) total += value;
  return total;
}

}  // namespace

int quest_dim(const QuestParams& params) {
  require(std::isfinite(params.grain) && params.grain > 0.0,
          format("grain must be positive and finite (got %g)", params.grain));
  if (!params.range) return 500;
  const double range = *params.range;
  require(range > 0.0, format("\"range\" must be greater than zero (got %g)", range));
  require(std::isfinite(range), "\"range\" must be finite");
  const double dim = 2.0 * std::ceil(range / params.grain / 2.0);
  require(dim <= kMaxDim, format("range / grain = %g gives a table larger than %g points", range / params.grain,
                                 kMaxDim));
  return static_cast<int>(dim);
}

Quest::Quest(const QuestParams& params) : Quest(params, quest_dim(params)) {}

Quest::Quest(const QuestParams& params, int dim) : params_(params), dim_(dim) {
  require(std::isfinite(params.t_guess), "\"tGuess\" must be real and finite");
  require(params.t_guess_sd > 0.0, format("tGuessSd must be positive (got %g); use inf for a flat prior",
                                          params.t_guess_sd));
  require(std::isfinite(params.grain) && params.grain > 0.0,
          format("grain must be positive and finite (got %g)", params.grain));
  require(dim >= 2 && dim % 2 == 0 && dim <= kMaxDim, format("dim must be an even number in [2, 1e7] (got %g)", dim));
  require(std::isfinite(params.beta) && params.beta > 0.0,
          format("beta must be positive and finite (got %g)", params.beta));
  require(params.delta >= 0.0 && params.delta <= 1.0, format("delta must be in [0, 1] (got %g)", params.delta));
  require(std::isfinite(params.gamma) && params.gamma >= 0.0, format("gamma must be >= 0 (got %g)", params.gamma));
  require(params.p_threshold > 0.0 && params.p_threshold < 1.0,
          format("pThreshold must be in (0, 1) (got %g)", params.p_threshold));
  if (params_.gamma > params_.p_threshold) {
    warnings_.push_back(format("reducing gamma from %.2f to 0.5", params_.gamma));
    params_.gamma = 0.5;
  }
  build_table();
}

void Quest::build_table() {
  const QuestParams& q = params_;
  const int half = dim_ / 2;
  x_.resize(static_cast<std::size_t>(dim_) + 1);
  pdf_.resize(x_.size());
  for (int i = -half; i <= half; ++i) {
    const double x = i * q.grain;
    const double z = x / q.t_guess_sd;
    x_[static_cast<std::size_t>(i + half)] = x;
    pdf_[static_cast<std::size_t>(i + half)] = std::exp(-0.5 * (z * z));
  }
  normalize();

  x2_.resize(2 * static_cast<std::size_t>(dim_) + 1);
  p2_.resize(x2_.size());
  for (int i = -dim_; i <= dim_; ++i) {
    const std::size_t k = static_cast<std::size_t>(i + dim_);
    x2_[k] = i * q.grain;
    p2_[k] = psychometric::quest_weibull(x2_[k], q.beta, q.delta, q.gamma);
  }
  const double p_low = std::min(p2_.front(), p2_.back());
  const double p_high = std::max(p2_.front(), p2_.back());
  require(!(p_low > q.p_threshold || p_high < q.p_threshold),
          format("psychometric function range [%.4g %.4g] omits the %.4g threshold", p_low, p_high, q.p_threshold));

  // Threshold shift: interpolate x2 at pThreshold over the strictly monotonic part of p2.
  std::vector<double> p_mono, x_mono;
  for (std::size_t k = 0; k + 1 < p2_.size(); ++k) {
    if (p2_[k + 1] != p2_[k]) {
      p_mono.push_back(p2_[k]);
      x_mono.push_back(x2_[k]);
    }
  }
  require(p_mono.size() >= 2, format("psychometric function has only %g strictly monotonic point(s)",
                                     static_cast<double>(p_mono.size())));
  x_threshold_ = interp1(p_mono, x_mono, q.p_threshold);
  require(std::isfinite(x_threshold_), format("psychometric function has no %.4g threshold", q.p_threshold));

  for (std::size_t k = 0; k < x2_.size(); ++k) {
    p2_[k] = psychometric::quest_weibull(x2_[k] + x_threshold_, q.beta, q.delta, q.gamma);
    require(std::isfinite(p2_[k]), "psychometric function p2 is not finite");
  }
  s2_[0].assign(p2_.size(), 0.0);
  s2_[1].assign(p2_.size(), 0.0);
  for (std::size_t k = 0; k < p2_.size(); ++k) {
    s2_[0][p2_.size() - 1 - k] = 1.0 - p2_[k];
    s2_[1][p2_.size() - 1 - k] = p2_[k];
  }

  // Pelli (1987) best quantile order; eps is MATLAB's eps = 2^-52.
  const double eps = DBL_EPSILON;
  const double pL = p2_.front();
  const double pH = p2_.back();
  double pE = pH * std::log(pH + eps) - pL * std::log(pL + eps) + (1 - pH + eps) * std::log(1 - pH + eps) -
              (1 - pL + eps) * std::log(1 - pL + eps);
  pE = 1 / (1 + std::exp(pE / (pL - pH)));
  quantile_order_ = (pE - pL) / (pH - pL);

  for (double value : pdf_) require(std::isfinite(value), "prior pdf is not finite");
}

bool Quest::multiply_likelihood(double intensity, int response) {
  const double clamped = std::max(-1e10, std::min(1e10, intensity));
  // Psychtoolbox's ii(1) (1-based) is dim/2 + 1 - shift; `start` is the 0-based column of s2.
  const double shift = std::round((clamped - params_.t_guess) / params_.grain);
  const double start_unclamped = dim_ / 2 - shift;
  const double last_column = 2.0 * dim_;
  bool outside = false;
  double start = start_unclamped;
  if (start < 0.0 || start + dim_ > last_column) {
    outside = true;
    start = start < 0.0 ? 0.0 : last_column - dim_;
  }
  const double* likelihood = s2_[response].data() + static_cast<std::size_t>(start);
  for (std::size_t j = 0; j < pdf_.size(); ++j) pdf_[j] *= likelihood[j];
  return outside;
}

void Quest::normalize() {
  const double total = sum(pdf_);
  for (double& value : pdf_) value /= total;
}

void Quest::update(double intensity, int response) {
  require(!std::isnan(intensity), "QuestUpdate: intensity is NaN");
  require(response == 0 || response == 1, format("response %g out of range 0 to 1", response));
  if (multiply_likelihood(intensity, response)) {
    const double low = -(dim_ / 2) * params_.grain + params_.t_guess;
    const double high = (dim_ / 2) * params_.grain + params_.t_guess;
    warnings_.push_back(format("QuestUpdate: intensity %.3f out of range %.2f to %.2f. Pdf will be inexact. "
                               "Suggest that you increase \"range\" in call to QuestCreate.",
                               intensity, low, high));
  }
  normalize();
  intensities_.push_back(intensity);
  responses_.push_back(response);
}

void Quest::recompute() {
  build_table();
  for (std::size_t k = 0; k < responses_.size(); ++k) {
    multiply_likelihood(intensities_[k], responses_[k]);
    if ((k + 1) % 100 == 0) normalize();
  }
  normalize();
  for (double value : pdf_) require(std::isfinite(value), "pdf is not finite");
}

double Quest::mean() const {
  double weighted = 0.0;
  for (std::size_t j = 0; j < pdf_.size(); ++j) weighted += pdf_[j] * x_[j];
  return params_.t_guess + weighted / sum(pdf_);
}

double Quest::sd() const {
  const double p = sum(pdf_);
  double first = 0.0, second = 0.0;
  for (std::size_t j = 0; j < pdf_.size(); ++j) {
    first += pdf_[j] * x_[j];
    second += pdf_[j] * (x_[j] * x_[j]);
  }
  const double m = first / p;
  // A pdf concentrated on one grid point can round the variance to a tiny negative number, which
  // MATLAB turns into an imaginary sd; report 0.
  return std::sqrt(std::max(0.0, second / p - m * m));
}

double Quest::mode() const {
  const auto it = std::max_element(pdf_.begin(), pdf_.end());  // first maximum, as MATLAB's max
  return x_[static_cast<std::size_t>(it - pdf_.begin())] + params_.t_guess;
}

double Quest::quantile() const { return quantile(quantile_order_); }

double Quest::quantile(double order) const {
  require(order >= 0.0 && order <= 1.0, format("quantileOrder %f is outside range 0 to 1.", order));
  // The running sum reproduces cumsum(pdf) bit for bit; its last value is p(end).
  double total = 0.0;
  for (double value : pdf_) total += value;
  require(std::isfinite(total), "pdf is not finite");
  require(total != 0.0, "pdf is all zero");
  if (order < pdf_.front()) return params_.t_guess + x_.front();
  if (order > total) return params_.t_guess + x_.back();
  // interp1(p(index), x(index), order * p(end)) over the points where the cumulative sum strictly
  // rises (the first point always counts), without building those vectors: find the first rising
  // point above the target and interpolate from the rising point before it.
  const double target = order * total;
  double running = 0.0, previous = -1.0;
  double below_p = NAN, below_x = NAN;  // last rising point <= target
  double before_p = NAN, before_x = NAN;  // the rising point before that one
  std::size_t rising = 0;
  for (std::size_t j = 0; j < pdf_.size(); ++j) {
    running += pdf_[j];
    if (running - previous > 0.0) {
      ++rising;
      if (running > target) {
        if (std::isnan(below_p)) return NAN;  // below the first point: interp1 gives NaN
        const double slope = (x_[j] - below_x) / (running - below_p);
        return params_.t_guess + (slope * (target - below_p) + below_x);
      }
      before_p = below_p;
      before_x = below_x;
      below_p = running;
      below_x = x_[j];
    }
    previous = running;
  }
  require(rising >= 2, format("pdf has only %g nonzero point(s)", static_cast<double>(rising)));
  // target equals the last rising point: interp1 uses the last interval.
  if (target != below_p) return NAN;
  const double slope = (below_x - before_x) / (below_p - before_p);
  return params_.t_guess + (slope * (target - before_p) + before_x);
}

double Quest::p(double x) const {
  require(!std::isnan(x), "QuestP: x is NaN");
  if (x < x2_.front()) return p2_.front();
  if (x > x2_.back()) return p2_.back();
  return interp1(x2_, p2_, x);
}

double Quest::pdf_at(double t) const {
  require(!std::isnan(t), "QuestPdf: t is NaN");
  const double i = std::round((t - params_.t_guess) / params_.grain) + 1 + dim_ / 2;  // 1-based
  const double clamped = std::min(static_cast<double>(pdf_.size()), std::max(1.0, i));
  return pdf_[static_cast<std::size_t>(clamped) - 1];
}

bool Quest::simulate(double t_test, double t_actual, double uniform01) const {
  const double t = std::min(std::max(t_test - t_actual, x2_.front()), x2_.back());
  return interp1(x2_, p2_, t) > uniform01;
}

Quest replay(const QuestParams& params, const std::vector<double>& intensities, const std::vector<int>& responses) {
  require(intensities.size() == responses.size(),
          format("replay needs one intensity per response (%g intensities, %g responses)",
                 static_cast<double>(intensities.size()), static_cast<double>(responses.size())));
  Quest quest(params);
  for (std::size_t k = 0; k < responses.size(); ++k) quest.update(intensities[k], responses[k]);
  return quest;
}

BetaAnalysis beta_analysis(const Quest& quest) {
  // Psychtoolbox recomputes the 16 tables as one joint pdf, without per-table normalisation, so
  // the tables' sums are the slopes' relative likelihoods. It lets them underflow (after roughly a
  // thousand trials every slope has zero probability and the answer is NaN); here all tables are
  // rescaled by one common factor when the largest sum gets small, which changes no ratio.
  constexpr int kSlopes = 16;
  std::vector<Quest> tables;
  tables.reserve(kSlopes);
  for (int i = 1; i <= kSlopes; ++i) {
    QuestParams params = quest.params();
    params.beta = std::pow(2.0, i / 4.0);
    params.grain = 0.02;
    tables.emplace_back(params, 250);
  }
  const auto& intensities = quest.intensities();
  const auto& responses = quest.responses();
  for (std::size_t k = 0; k < responses.size(); ++k) {
    double largest = 0.0;
    for (Quest& table : tables) {
      table.multiply_likelihood(intensities[k], responses[k]);
      largest = std::max(largest, sum(table.pdf_));
    }
    if (largest < 1e-200 && largest > 0.0) {
      for (Quest& table : tables)
        for (double& value : table.pdf_) value /= largest;
    }
  }

  std::vector<double> t2, p2, beta2;
  std::vector<std::size_t> kept;
  for (std::size_t i = 0; i < tables.size(); ++i) {
    if (sum(tables[i].pdf_) == 0.0) continue;  // zero probability: omitted, as Psychtoolbox does
    kept.push_back(i);
    t2.push_back(tables[i].mean());
    p2.push_back(tables[i].pdf_at(t2.back()));
    beta2.push_back(tables[i].params_.beta);
  }
  require(!kept.empty(), "QuestBetaAnalysis: every slope has zero probability");
  const std::size_t best = static_cast<std::size_t>(std::max_element(p2.begin(), p2.end()) - p2.begin());
  BetaAnalysis result{};
  result.t = t2[best];
  result.sd = tables[kept[best]].sd();
  double p = 0.0, beta_sum = 0.0, beta_sq = 0.0, inverse_sum = 0.0;
  for (std::size_t i = 0; i < p2.size(); ++i) {
    p += p2[i];
    beta_sum += p2[i] * beta2[i];
    beta_sq += p2[i] * (beta2[i] * beta2[i]);
    inverse_sum += p2[i] / beta2[i];
  }
  const double beta_mean = beta_sum / p;
  result.beta_sd = std::sqrt(std::max(0.0, beta_sq / p - beta_mean * beta_mean));
  result.beta = 1.0 / (inverse_sum / p);
  return result;
}

}  // namespace penumbra::quest
