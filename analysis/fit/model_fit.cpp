#include "fit/model_fit.h"

#include <ceres/ceres.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <cstdint>
#include <cstring>
#include <map>
#include <memory>
#include <exception>
#include <stdexcept>
#include <thread>
#include <unordered_map>

#include "solver/solver_options.h"

namespace penumbra::analysis {

namespace psy = psychometric;

void Flags::add(const std::string& flag) {
  if (!has(flag)) list.push_back(flag);
}
bool Flags::has(const std::string& flag) const { return std::find(list.begin(), list.end(), flag) != list.end(); }

double FitResult::cov(int i, int j) const {
  const int n = index_lambda() + 1;
  if (!covariance_ok || i < 0 || j < 0 || i >= n || j >= n || !estimated[i] || !estimated[j]) return NAN;
  return covariance[static_cast<std::size_t>(i * n + j)];
}
double FitResult::se(int i) const { return std::sqrt(cov(i, i)); }
double FitResult::correlation(int i, int j) const { return cov(i, j) / (se(i) * se(j)); }

double chi2_1_quantile(double level) {
  const double z = psy::inverse_erf(level);
  return 2.0 * z * z;
}

namespace {

constexpr double kTiny = 1e-300;

// alpha that puts F at the criterion F* at threshold u. A group with its own guess rate takes F*
// directly (F* on F needs no guess rate); the others go through ModelSpec's p_threshold, guess and
// criterion lapse, which give the same F*.
template <typename T>
T threshold_alpha(const ModelSpec& spec, const std::optional<double>& group_guess, const T& u, const T& beta) {
  using std::pow;
  const T threshold_x = spec.family == psy::Model::weibull ? T(pow(T(10.0), u)) : u;
  if (group_guess) return psy::alpha_for_threshold(spec.family, threshold_x, T(spec.criterion_f()), beta, T(0.0), T(0.0));
  return psy::alpha_for_threshold(spec.family, threshold_x, T(spec.p_threshold), beta, T(spec.guess), T(spec.criterion_lapse));
}

// The model at one group threshold u, with what does not depend on x computed once.
template <typename T>
struct GroupModel {
  T alpha, beta, gamma, lambda, scale;
  GroupModel(const ModelSpec& spec, const std::optional<double>& group_guess, const T& u, const T& log_beta,
             const T& lambda_in) {
    using std::exp;
    using std::pow;
    beta = exp(log_beta);
    gamma = T(group_guess.value_or(spec.guess));
    lambda = lambda_in;
    alpha = threshold_alpha(spec, group_guess, u, beta);
    scale = T(1.0) - gamma - lambda;
  }
  // log psi and log(1 - psi) at x; 1 - psi is built from 1 - F so that it keeps its precision far
  // above threshold, and both stay away from log(0). A null pointer skips that logarithm: a row of
  // one trial needs only one of them.
  void log_probabilities(psy::Model family, double x, T* log_p, T* log_q) const {
    using std::exp;
    using std::expm1;
    using std::log;
    using std::log1p;
    using std::pow;
    if (family == psy::Model::weibull || family == psy::Model::log_weibull) {
      // psy::core_and_complement's expressions, with F computed only where it is used: log psi is
      // taken from psi itself only for a correct answer where 1 - psi >= 0.5, so most rows skip
      // F's expm1 (and, for a Jet, the exp of its derivative). The numbers are the same.
      const T z = family == psy::Model::weibull ? T(pow(T(x) / alpha, beta)) : psy::pow10(T(beta * (T(x) - alpha)));
      T q = lambda + scale * T(exp(-z));
      if (q < T(kTiny)) q = T(kTiny);
      if (log_q) *log_q = log(q);
      if (!log_p) return;
      if (q < T(0.5)) {
        *log_p = T(log1p(-q));
        return;
      }
      T p = gamma + scale * T(-expm1(-z));
      if (p < T(kTiny)) p = T(kTiny);
      *log_p = T(log(p));
      return;
    }
    T f, f_complement;
    psy::core_and_complement(family, T(x), alpha, beta, &f, &f_complement);
    T p = gamma + scale * f;
    T q = lambda + scale * f_complement;
    if (p < T(kTiny)) p = T(kTiny);
    if (q < T(kTiny)) q = T(kTiny);
    if (log_p) *log_p = q < T(0.5) ? T(log1p(-q)) : T(log(p));
    if (log_q) *log_q = log(q);
  }
};

template <typename T>
T probability(const ModelSpec& spec, const std::optional<double>& group_guess, double x, const T& u, const T& log_beta,
              const T& lambda) {
  using std::exp;
  const T beta = exp(log_beta);
  const T alpha = threshold_alpha(spec, group_guess, u, beta);
  return psy::probability(spec.family, T(x), psy::Params<T>{alpha, beta, T(group_guess.value_or(spec.guess)), lambda});
}

// NLL of one group as residuals: sqrt(-2 k log psi), sqrt(-2 (n - k) log(1 - psi)) per row.
struct GroupNllCost {
  const ModelSpec* spec;
  const Group* group;
  template <typename T>
  bool operator()(const T* u, const T* s, const T* log_beta, const T* lambda, T* residuals) const {
    using std::sqrt;
    const GroupModel<T> model(*spec, group->guess, u[0] + s[0] * group->offset, log_beta[0], lambda[0]);
    for (std::size_t i = 0; i < group->rows.size(); ++i) {
      const BinomialRow& row = group->rows[i];
      const double k = row.n_correct, m = row.n_total - row.n_correct;
      T log_p, log_q;
      model.log_probabilities(spec->family, row.x, k > 0 ? &log_p : nullptr, m > 0 ? &log_q : nullptr);
      residuals[2 * i] = k > 0 ? T(sqrt(T(-2.0 * k) * log_p)) : T(0.0);
      residuals[2 * i + 1] = m > 0 ? T(sqrt(T(-2.0 * m) * log_q)) : T(0.0);
    }
    return true;
  }
};

// The cost of a group that appears more than once in a problem (a participant the bootstrap drew
// twice or more): every copy's residual block shares this one cost, which evaluates the group once
// per evaluation of the problem and hands the copies the stored residuals and derivatives. The
// copies get the very numbers they would have computed (same data, same parameters, same call),
// so the fit does not change; a resample of n participants holds about n (1 - 1/e) distinct ones,
// so about a third of its evaluations were repeats. The store is not locked: a problem is
// evaluated by one thread (solver::small_problem_options).
class RepeatedGroupCost final : public ceres::CostFunction {
 public:
  explicit RepeatedGroupCost(std::unique_ptr<ceres::CostFunction> inner) : inner_(std::move(inner)) {
    set_num_residuals(inner_->num_residuals());
    *mutable_parameter_block_sizes() = inner_->parameter_block_sizes();
    const std::size_t blocks = parameter_block_sizes().size();
    parameters_.resize(blocks);
    residuals_.resize(static_cast<std::size_t>(num_residuals()));
    jacobians_.resize(blocks);
    for (std::size_t i = 0; i < blocks; ++i)
      jacobians_[i].resize(static_cast<std::size_t>(num_residuals() * parameter_block_sizes()[i]));
  }

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    const std::vector<std::int32_t>& sizes = parameter_block_sizes();
    // What was asked decides how the inner cost computes (with or without derivatives): a stored
    // evaluation serves only the same question.
    std::vector<bool> wanted(sizes.size() + 1);
    wanted.back() = jacobians != nullptr;
    for (std::size_t i = 0; i < sizes.size(); ++i) wanted[i] = jacobians && jacobians[i];
    bool stored = ok_ && wanted == wanted_;
    for (std::size_t i = 0; i < sizes.size() && stored; ++i)
      stored = parameters_[i].size() == static_cast<std::size_t>(sizes[i]) &&
               std::memcmp(parameters_[i].data(), parameters[i], sizeof(double) * static_cast<std::size_t>(sizes[i])) == 0;
    if (!stored) {
      std::vector<double*> into(sizes.size(), nullptr);
      for (std::size_t i = 0; i < sizes.size(); ++i)
        if (wanted[i]) into[i] = jacobians_[i].data();
      ok_ = inner_->Evaluate(parameters, residuals_.data(), jacobians ? into.data() : nullptr);
      wanted_ = wanted;
      for (std::size_t i = 0; i < sizes.size(); ++i) parameters_[i].assign(parameters[i], parameters[i] + sizes[i]);
      if (!ok_) return false;
    }
    std::copy(residuals_.begin(), residuals_.end(), residuals);
    for (std::size_t i = 0; i < sizes.size(); ++i)
      if (wanted[i]) std::copy(jacobians_[i].begin(), jacobians_[i].end(), jacobians[i]);
    return true;
  }

 private:
  std::unique_ptr<ceres::CostFunction> inner_;
  mutable bool ok_ = false;
  mutable std::vector<bool> wanted_;
  mutable std::vector<std::vector<double>> parameters_, jacobians_;
  mutable std::vector<double> residuals_;
};

// Residuals w_i psi_i(theta) with w_i = sqrt(n_i / (psi^_i (1 - psi^_i))) fixed at the optimum:
// J^T J = sum n (d psi)^2 / (psi (1 - psi)), the Fisher information.
struct GroupFisherCost {
  const ModelSpec* spec;
  const Group* group;
  std::vector<double> weights;
  template <typename T>
  bool operator()(const T* u, const T* s, const T* log_beta, const T* lambda, T* residuals) const {
    const T threshold = u[0] + s[0] * group->offset;
    for (std::size_t i = 0; i < group->rows.size(); ++i)
      residuals[i] = T(weights[i]) * probability(*spec, group->guess, group->rows[i].x, threshold, log_beta[0], lambda[0]);
    return true;
  }
};

double log10_x(const ModelSpec& spec, double x) { return spec.family == psy::Model::weibull ? std::log10(x) : x; }

void validate(const ModelSpec& spec) {
  if (spec.groups.empty()) throw std::invalid_argument("no data to fit");
  if (!(spec.guess >= 0.0 && spec.guess < 1.0)) throw std::invalid_argument("guess rate must be in [0, 1)");
  const double lapse_hi = spec.lapse.fixed ? *spec.lapse.fixed : spec.lapse.max;
  if (!(lapse_hi >= 0.0 && spec.guess + lapse_hi < 1.0))
    throw std::invalid_argument("lapse must be in [0, 1 - guess)");
  if (!(spec.criterion_lapse >= 0.0 && spec.guess + spec.criterion_lapse < 1.0))
    throw std::invalid_argument("the criterion's lapse must be in [0, 1 - guess)");
  if (!(spec.p_threshold > spec.guess && spec.p_threshold < 1.0 - spec.criterion_lapse))
    throw std::invalid_argument("threshold percent correct must lie between the guess rate and 1 - the criterion's lapse");
  if (spec.slope.fixed && !(*spec.slope.fixed > 0 && std::isfinite(*spec.slope.fixed)))
    throw std::invalid_argument("a fixed slope must be positive");
  if (!(spec.slope.min > 0 && spec.slope.min < spec.slope.max && std::isfinite(spec.slope.max)))
    throw std::invalid_argument("slope bounds must satisfy 0 < min < max");
  if (spec.thresholds < 1) throw std::invalid_argument("at least one threshold");
  double trials = 0;
  for (const Group& g : spec.groups) {
    if (g.threshold_index < 0 || g.threshold_index >= spec.thresholds)
      throw std::invalid_argument("group threshold index out of range");
    if (!std::isfinite(g.offset)) throw std::invalid_argument("group offset must be finite");
    if (g.guess && !(*g.guess >= 0.0 && *g.guess + lapse_hi < 1.0))
      throw std::invalid_argument("a group's guess rate must be in [0, 1 - lapse)");
    for (const BinomialRow& r : g.rows) {
      if (!std::isfinite(r.x)) throw std::invalid_argument("stimulus level must be finite");
      if (spec.family == psy::Model::weibull && !(r.x > 0))
        throw std::invalid_argument("the Weibull needs stimulus levels > 0 (use log-weibull for log units)");
      if (!(r.n_total >= 1 && r.n_correct >= 0 && r.n_correct <= r.n_total && std::isfinite(r.n_total)))
        throw std::invalid_argument("counts must satisfy 0 <= n_correct <= n_total, n_total >= 1");
      trials += r.n_total;
    }
  }
  if (trials == 0) throw std::invalid_argument("no trials to fit");
  if (trials > std::numeric_limits<int>::max()) throw std::invalid_argument("more than 2147483647 trials in all");
}

struct Bounds {
  double u_min, u_max, log_beta_min, log_beta_max, s_min = -3.0, s_max = 3.0;
};

Bounds bounds_of(const ModelSpec& spec) {
  double lo = INFINITY, hi = -INFINITY;
  for (const Group& g : spec.groups) {
    for (const BinomialRow& r : g.rows) {
      lo = std::min(lo, log10_x(spec, r.x));
      hi = std::max(hi, log10_x(spec, r.x));
    }
  }
  Bounds b;
  b.u_min = spec.u_min.value_or(lo - 1.0);
  b.u_max = spec.u_max.value_or(hi + 1.0);
  if (!(b.u_min < b.u_max)) throw std::invalid_argument("threshold bounds must satisfy min < max");
  // Levels such as 1e308 and -1e308 are finite but their span is not: the start grid would hold
  // no finite point.
  if (!std::isfinite(b.u_max - b.u_min)) {
    char span[96];
    std::snprintf(span, sizeof span, "from %g to %g", lo, hi);
    throw std::invalid_argument(std::string("stimulus levels span more than a double can hold (") + span + ")");
  }
  b.log_beta_min = std::log(spec.slope.min);
  b.log_beta_max = std::log(spec.slope.max);
  return b;
}

double lambda_start(const ModelSpec& spec) {
  return spec.lapse.fixed ? *spec.lapse.fixed : std::min(0.01, 0.5 * spec.lapse.max);
}

// The best (u, log beta) on a grid, every u equal, s = 0, lambda at its start.
Parameters grid_start(const ModelSpec& spec, const Bounds& b) {
  Parameters p;
  p.lambda = lambda_start(spec);
  double best = INFINITY;
  Parameters trial = p;
  trial.u.assign(static_cast<std::size_t>(spec.thresholds), 0.0);
  constexpr int kU = 41, kBeta = 9;
  for (int j = 0; j < (spec.slope.fixed ? 1 : kBeta); ++j) {
    trial.log_beta = spec.slope.fixed ? std::log(*spec.slope.fixed)
                                      : b.log_beta_min + (b.log_beta_max - b.log_beta_min) * (j + 0.5) / kBeta;
    for (int i = 0; i < kU; ++i) {
      std::fill(trial.u.begin(), trial.u.end(), b.u_min + (b.u_max - b.u_min) * (i + 0.5) / kU);
      const double nll = negative_log_likelihood(spec, trial);
      if (nll < best) {
        best = nll;
        p = trial;
      }
    }
  }
  if (p.u.empty()) throw std::invalid_argument("the likelihood is not finite anywhere on the start grid");
  return p;
}

double saturated_nll(const ModelSpec& spec) {
  double nll = 0;
  for (const Group& g : spec.groups) {
    std::map<double, std::pair<double, double>> by_x;
    for (const BinomialRow& r : g.rows) {
      by_x[r.x].first += r.n_correct;
      by_x[r.x].second += r.n_total;
    }
    for (const auto& [x, kn] : by_x) {
      const double k = kn.first, n = kn.second;
      if (k > 0) nll -= k * std::log(k / n);
      if (n - k > 0) nll -= (n - k) * std::log((n - k) / n);
    }
  }
  return nll;
}

// The values Ceres moves, in one array in the parameters' index order: thresholds, s, log beta,
// lambda. ceres::Covariance orders its columns by the blocks' addresses; with the thresholds on the
// heap and the other three on the stack, that order depended on the thread a fit ran on (a worker's
// stack lies above or below its heap arena), and so did the covariance's last bit.
class Blocks {
 public:
  explicit Blocks(const Parameters& p) : k_(p.u.size()), values_(p.u) {
    values_.insert(values_.end(), {p.s, p.log_beta, p.lambda});
  }
  std::size_t thresholds() const { return k_; }
  double* u(std::size_t i) { return &values_[i]; }
  double* s() { return &values_[k_]; }
  double* log_beta() { return &values_[k_ + 1]; }
  double* lambda() { return &values_[k_ + 2]; }
  Parameters parameters() const {
    return {std::vector<double>(values_.begin(), values_.begin() + static_cast<std::ptrdiff_t>(k_)), values_[k_],
            values_[k_ + 1], values_[k_ + 2]};
  }

 private:
  std::size_t k_;
  std::vector<double> values_;
};

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// Groups equal bit for bit: the same rows, threshold, offset and guess rate.
bool same_group(const Group& a, const Group& b) {
  if (a.threshold_index != b.threshold_index || !same_bits(a.offset, b.offset) || a.guess.has_value() != b.guess.has_value() ||
      (a.guess && !same_bits(*a.guess, *b.guess)) || a.rows.size() != b.rows.size())
    return false;
  for (std::size_t i = 0; i < a.rows.size(); ++i)
    if (!same_bits(a.rows[i].x, b.rows[i].x) || !same_bits(a.rows[i].n_correct, b.rows[i].n_correct) ||
        !same_bits(a.rows[i].n_total, b.rows[i].n_total))
      return false;
  return true;
}

std::uint64_t group_hash(const Group& g) {
  std::uint64_t h = 0xcbf29ce484222325ull;  // FNV-1a over the words
  const auto mix = [&h](std::uint64_t word) { h = (h ^ word) * 0x100000001b3ull; };
  const auto bits = [](double v) {
    std::uint64_t w;
    std::memcpy(&w, &v, sizeof w);
    return w;
  };
  mix(static_cast<std::uint64_t>(g.threshold_index));
  mix(bits(g.offset));
  mix(g.guess ? bits(*g.guess) : 1);
  for (const BinomialRow& r : g.rows) {
    mix(bits(r.x));
    mix(bits(r.n_correct));
    mix(bits(r.n_total));
  }
  return h;
}

// For each group, the index of the first group equal to it (its own index when none before it is).
std::vector<std::size_t> first_copies(const ModelSpec& spec) {
  std::vector<std::size_t> first(spec.groups.size());
  std::unordered_map<std::uint64_t, std::vector<std::size_t>> by_hash;
  for (std::size_t i = 0; i < spec.groups.size(); ++i) {
    first[i] = i;
    std::vector<std::size_t>& candidates = by_hash[group_hash(spec.groups[i])];
    for (std::size_t j : candidates)
      if (same_group(spec.groups[j], spec.groups[i])) {
        first[i] = j;
        break;
      }
    if (first[i] == i) candidates.push_back(i);
  }
  return first;
}

void add_nll_blocks(ceres::Problem& problem, const ModelSpec& spec, Blocks& blocks) {
  const std::vector<std::size_t> first = first_copies(spec);
  std::vector<int> copies(spec.groups.size(), 0);
  for (std::size_t f : first) ++copies[f];
  std::vector<ceres::CostFunction*> costs(spec.groups.size(), nullptr);
  for (std::size_t i = 0; i < spec.groups.size(); ++i) {
    const Group& group = spec.groups[i];
    if (group.rows.empty()) continue;
    ceres::CostFunction*& cost = costs[first[i]];
    if (!cost) {
      auto nll = std::make_unique<ceres::AutoDiffCostFunction<GroupNllCost, ceres::DYNAMIC, 1, 1, 1, 1>>(
          new GroupNllCost{&spec, &group}, static_cast<int>(2 * group.rows.size()));
      cost = copies[i] > 1 ? new RepeatedGroupCost(std::move(nll)) : static_cast<ceres::CostFunction*>(nll.release());
    }
    // The problem owns each cost once, however many blocks share it.
    problem.AddResidualBlock(cost, nullptr, blocks.u(static_cast<std::size_t>(group.threshold_index)), blocks.s(),
                             blocks.log_beta(), blocks.lambda());
  }
}

bool near(double v, double bound, double span) { return std::abs(v - bound) <= 1e-6 * std::max(1.0, span); }

void data_flags(const ModelSpec& spec, FitResult& out) {
  double k = 0, n = 0, chance = 0;  // chance: correct answers expected from guessing alone
  std::vector<double> levels;
  for (const Group& g : spec.groups) {
    for (const BinomialRow& r : g.rows) {
      k += r.n_correct;
      n += r.n_total;
      chance += g.guess.value_or(spec.guess) * r.n_total;
      levels.push_back(r.x);
    }
  }
  out.trials = static_cast<int>(n);
  // Perfect separation (one data set): every level above some split all correct, every level
  // below it at or under the guess rate. A step then fits best and a free slope runs to its bound
  // (with the slope held, the threshold is still found: nothing to flag).
  if (spec.groups.size() == 1 && !spec.slope.fixed) {
    std::vector<BinomialRow> rows = spec.groups[0].rows;
    std::sort(rows.begin(), rows.end(), [](const BinomialRow& a, const BinomialRow& b) { return a.x < b.x; });
    for (std::size_t split = 1; split < rows.size(); ++split) {
      if (rows[split - 1].x == rows[split].x) continue;
      bool separated = true;
      for (std::size_t i = 0; i < rows.size() && separated; ++i)
        separated = i < split ? rows[i].n_correct <= spec.groups[0].guess.value_or(spec.guess) * rows[i].n_total
                              : rows[i].n_correct == rows[i].n_total;
      if (separated) out.flags.add("perfect_separation");
    }
  }
  std::sort(levels.begin(), levels.end());
  if (std::unique(levels.begin(), levels.end()) - levels.begin() < 2) out.flags.add("one_level");
  if (k == n) out.flags.add("all_correct");
  if (k <= chance) out.flags.add("none_above_chance");
}

// Covariance from the Fisher information at `out.params`; parameters held fixed or at a bound are
// excluded. Fills covariance, estimated, covariance_ok and the correlation flag.
void compute_covariance(const ModelSpec& spec, const Bounds& b, const std::optional<int>& fixed_threshold,
                        FitResult& out) {
  const int k = spec.thresholds;
  const int n = k + 3;
  out.covariance.assign(static_cast<std::size_t>(n * n), 0.0);
  out.estimated.assign(static_cast<std::size_t>(n), false);
  Blocks blocks(out.params);
  ceres::Problem::Options problem_options;
  ceres::Problem problem(problem_options);
  for (const Group& group : spec.groups) {
    if (group.rows.empty()) continue;
    std::vector<double> weights;
    const double u = out.params.u[static_cast<std::size_t>(group.threshold_index)] + out.params.s * group.offset;
    for (const BinomialRow& r : group.rows) {
      const double p =
          std::clamp(probability(spec, group.guess, r.x, u, out.params.log_beta, out.params.lambda), 1e-12, 1 - 1e-12);
      weights.push_back(std::sqrt(r.n_total / (p * (1 - p))));
    }
    auto* cost = new ceres::AutoDiffCostFunction<GroupFisherCost, ceres::DYNAMIC, 1, 1, 1, 1>(
        new GroupFisherCost{&spec, &group, weights}, static_cast<int>(group.rows.size()));
    problem.AddResidualBlock(cost, nullptr, blocks.u(static_cast<std::size_t>(group.threshold_index)), blocks.s(),
                             blocks.log_beta(), blocks.lambda());
  }
  std::vector<const double*> free_blocks;
  std::vector<int> free_index;
  auto consider = [&](double* block, int index, bool is_free) {
    if (!problem.HasParameterBlock(block)) return;
    if (is_free) {
      free_blocks.push_back(block);
      free_index.push_back(index);
    } else {
      problem.SetParameterBlockConstant(block);
    }
  };
  for (int i = 0; i < k; ++i) {
    const double u = out.params.u[static_cast<std::size_t>(i)];
    const bool at_bound = near(u, b.u_min, b.u_max - b.u_min) || near(u, b.u_max, b.u_max - b.u_min);
    consider(blocks.u(static_cast<std::size_t>(i)), i, !at_bound && fixed_threshold != i);
  }
  consider(blocks.s(), k, spec.power_law && !near(out.params.s, b.s_min, 1) && !near(out.params.s, b.s_max, 1));
  consider(blocks.log_beta(), k + 1,
           !spec.slope.fixed && !near(out.params.log_beta, b.log_beta_min, 1) &&
               !near(out.params.log_beta, b.log_beta_max, 1));
  consider(blocks.lambda(), k + 2,
           !spec.lapse.fixed && !near(out.params.lambda, 0.0, 0.01) && !near(out.params.lambda, spec.lapse.max, 0.01));
  if (free_blocks.empty()) return;
  ceres::Covariance::Options options;
  options.algorithm_type = ceres::DENSE_SVD;
  options.null_space_rank = 0;  // fail (and flag) rather than return a pseudo-inverse
  options.num_threads = 1;
  ceres::Covariance covariance(options);
  std::vector<std::pair<const double*, const double*>> pairs;
  for (std::size_t i = 0; i < free_blocks.size(); ++i)
    for (std::size_t j = i; j < free_blocks.size(); ++j) pairs.emplace_back(free_blocks[i], free_blocks[j]);
  if (!covariance.Compute(pairs, &problem)) {
    out.flags.add("covariance_failed");
    return;
  }
  const std::size_t m = free_blocks.size();
  std::vector<double> sub(m * m);
  if (!covariance.GetCovarianceMatrix(free_blocks, sub.data())) {
    out.flags.add("covariance_failed");
    return;
  }
  for (std::size_t i = 0; i < m; ++i) {
    if (!(std::isfinite(sub[i * m + i]) && sub[i * m + i] >= 0)) {
      out.flags.add("covariance_failed");
      return;
    }
  }
  for (std::size_t i = 0; i < m; ++i) {
    out.estimated[static_cast<std::size_t>(free_index[i])] = true;
    for (std::size_t j = 0; j < m; ++j)
      out.covariance[static_cast<std::size_t>(free_index[i] * n + free_index[j])] = sub[i * m + j];
  }
  out.covariance_ok = true;
  for (int i = 0; i < k; ++i) {
    const double r = out.correlation(i, out.index_log_beta());
    if (std::isfinite(r) && std::abs(r) > 0.9) out.flags.add("threshold_slope_correlated");
  }
}

FitResult solve(const ModelSpec& spec, const Bounds& b, Parameters start, const std::optional<int>& fixed_threshold,
                bool covariance) {
  FitResult out;
  out.u_min = b.u_min;
  out.u_max = b.u_max;
  data_flags(spec, out);
  start.u.resize(static_cast<std::size_t>(spec.thresholds), start.u.empty() ? 0.5 * (b.u_min + b.u_max) : start.u[0]);
  for (std::size_t i = 0; i < start.u.size(); ++i)
    if (!(fixed_threshold && static_cast<int>(i) == *fixed_threshold))
      start.u[i] = std::clamp(start.u[i], b.u_min, b.u_max);
  if (!spec.power_law) start.s = 0;
  start.s = std::clamp(start.s, b.s_min, b.s_max);
  start.log_beta = spec.slope.fixed ? std::log(*spec.slope.fixed)
                                    : std::clamp(start.log_beta, b.log_beta_min, b.log_beta_max);
  start.lambda = spec.lapse.fixed ? *spec.lapse.fixed : std::clamp(start.lambda, 0.0, spec.lapse.max);

  Blocks blocks(start);
  ceres::Problem problem;
  add_nll_blocks(problem, spec, blocks);
  for (std::size_t i = 0; i < blocks.thresholds(); ++i) {
    double* block = blocks.u(i);
    if (!problem.HasParameterBlock(block)) continue;
    if (fixed_threshold && static_cast<int>(i) == *fixed_threshold) {
      problem.SetParameterBlockConstant(block);
    } else {
      problem.SetParameterLowerBound(block, 0, b.u_min);
      problem.SetParameterUpperBound(block, 0, b.u_max);
    }
  }
  if (spec.power_law) {
    problem.SetParameterLowerBound(blocks.s(), 0, b.s_min);
    problem.SetParameterUpperBound(blocks.s(), 0, b.s_max);
  } else {
    problem.SetParameterBlockConstant(blocks.s());
  }
  if (spec.slope.fixed) {
    problem.SetParameterBlockConstant(blocks.log_beta());
  } else {
    problem.SetParameterLowerBound(blocks.log_beta(), 0, b.log_beta_min);
    problem.SetParameterUpperBound(blocks.log_beta(), 0, b.log_beta_max);
  }
  if (spec.lapse.fixed) {
    problem.SetParameterBlockConstant(blocks.lambda());
  } else {
    problem.SetParameterLowerBound(blocks.lambda(), 0, 0.0);
    problem.SetParameterUpperBound(blocks.lambda(), 0, spec.lapse.max);
  }
  const ceres::Solver::Options options = solver::small_problem_options(1e-12);
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  out.iterations = static_cast<int>(summary.iterations.size());
  out.params = blocks.parameters();
  bool finite = std::isfinite(out.params.s) && std::isfinite(out.params.log_beta) && std::isfinite(out.params.lambda);
  for (double u : out.params.u) finite = finite && std::isfinite(u);
  out.nll = finite ? negative_log_likelihood(spec, out.params) : NAN;
  const double start_nll = negative_log_likelihood(spec, start);
  if (!std::isfinite(out.nll) || out.nll > start_nll) {
    // A failed solve never leaves a NaN: fall back to the (finite) start, flagged.
    out.params = start;
    out.nll = start_nll;
    out.flags.add("not_converged");
  } else {
    out.converged = summary.termination_type == ceres::CONVERGENCE;
    if (!out.converged) out.flags.add("not_converged");
  }
  out.deviance = std::max(0.0, 2.0 * (out.nll - saturated_nll(spec)));
  for (std::size_t i = 0; i < out.params.u.size(); ++i) {
    if (fixed_threshold && static_cast<int>(i) == *fixed_threshold) continue;
    if (near(out.params.u[i], b.u_min, b.u_max - b.u_min) || near(out.params.u[i], b.u_max, b.u_max - b.u_min))
      out.flags.add("threshold_at_bound");
  }
  if (!spec.slope.fixed) {
    if (near(out.params.log_beta, b.log_beta_max, 1)) out.flags.add("slope_at_upper_bound");
    if (near(out.params.log_beta, b.log_beta_min, 1)) out.flags.add("slope_at_lower_bound");
  }
  if (!spec.lapse.fixed && (near(out.params.lambda, 0.0, 0.01) || near(out.params.lambda, spec.lapse.max, 0.01)))
    out.flags.add("lapse_at_bound");
  if (spec.power_law && (near(out.params.s, b.s_min, 1) || near(out.params.s, b.s_max, 1)))
    out.flags.add("exponent_at_bound");
  if (covariance) compute_covariance(spec, b, fixed_threshold, out);
  return out;
}

}  // namespace

double negative_log_likelihood(const ModelSpec& spec, const Parameters& params) {
  double nll = 0;
  for (const Group& g : spec.groups) {
    const GroupModel<double> model(spec, g.guess, params.u.at(static_cast<std::size_t>(g.threshold_index)) + params.s * g.offset,
                                   params.log_beta, params.lambda);
    for (const BinomialRow& r : g.rows) {
      double log_p = 0, log_q = 0;
      model.log_probabilities(spec.family, r.x, r.n_correct > 0 ? &log_p : nullptr,
                              r.n_total - r.n_correct > 0 ? &log_q : nullptr);
      if (r.n_correct > 0) nll -= r.n_correct * log_p;
      if (r.n_total - r.n_correct > 0) nll -= (r.n_total - r.n_correct) * log_q;
    }
  }
  return nll;
}

FitResult fit(const ModelSpec& spec, const std::optional<Parameters>& start, bool covariance) {
  validate(spec);
  const Bounds b = bounds_of(spec);
  return solve(spec, b, start ? *start : grid_start(spec, b), std::nullopt, covariance);
}

FitResult fit_with_threshold(const ModelSpec& spec, int threshold_index, double u_value, const Parameters& start) {
  validate(spec);
  if (threshold_index < 0 || threshold_index >= spec.thresholds)
    throw std::invalid_argument("threshold index out of range");
  const Bounds b = bounds_of(spec);
  Parameters p = start;
  p.u.resize(static_cast<std::size_t>(spec.thresholds), u_value);
  p.u[static_cast<std::size_t>(threshold_index)] = u_value;
  return solve(spec, b, p, threshold_index, false);
}

ProfileInterval profile_interval(const ModelSpec& spec, const FitResult& best, int threshold_index, double level,
                                 int threads) {
  ProfileInterval out;
  const double target = best.nll + 0.5 * chi2_1_quantile(level);
  const double u_hat = best.params.u.at(static_cast<std::size_t>(threshold_index));
  const double se = best.se(threshold_index);
  const double step0 = std::isfinite(se) && se > 0 ? std::clamp(2.0 * se, 1e-3, 0.25) : 0.05;
  int fits[2] = {0, 0};
  // The two ends are searched apart from each other, each its own sequence of fits.
  auto search = [&](int side) {
    auto profile = [&](double u) {
      ++fits[side > 0];
      return fit_with_threshold(spec, threshold_index, u, best.params).nll;
    };
    const double bound = side < 0 ? best.u_min : best.u_max;
    double inside = u_hat, outside = u_hat, step = step0;
    bool crossed = false;
    while (true) {
      outside = u_hat + side * step;
      if (side * (outside - bound) >= 0) {
        outside = bound;
        crossed = profile(bound) > target;
        break;
      }
      if (profile(outside) > target) {
        crossed = true;
        break;
      }
      inside = outside;
      step *= 2;
    }
    double edge = bound;
    if (crossed) {
      for (int i = 0; i < 40 && std::abs(outside - inside) > 1e-5; ++i) {
        const double mid = 0.5 * (inside + outside);
        (profile(mid) > target ? outside : inside) = mid;
      }
      edge = 0.5 * (inside + outside);
    }
    (side < 0 ? out.lo : out.hi) = edge;
    (side < 0 ? out.lo_open : out.hi_open) = !crossed;
  };
  if (threads < 2) {
    search(-1);
    search(+1);
  } else {
    std::exception_ptr failed[2];
    std::thread lower([&] {
      try {
        search(-1);
      } catch (...) {
        failed[0] = std::current_exception();
      }
    });
    try {
      search(+1);
    } catch (...) {
      failed[1] = std::current_exception();
    }
    lower.join();
    for (const std::exception_ptr& e : failed)
      if (e) std::rethrow_exception(e);
  }
  out.fits = fits[0] + fits[1];
  return out;
}

double alpha_of(const ModelSpec& spec, double u, double beta) {
  const double threshold_x = spec.family == psy::Model::weibull ? std::pow(10.0, u) : u;
  return psy::alpha_for_threshold(spec.family, threshold_x, spec.p_threshold, beta, spec.guess, spec.criterion_lapse);
}

double alpha_se(const ModelSpec& spec, const FitResult& fit, int threshold_index) {
  using Jet = ceres::Jet<double, 3>;
  const Jet u(fit.params.u.at(static_cast<std::size_t>(threshold_index)), 0);
  const Jet log_beta(fit.params.log_beta, 1);  // alpha does not depend on the fitted lapse (a threshold is on F)
  const Jet threshold_x = spec.family == psy::Model::weibull ? Jet(pow(Jet(10.0), u)) : u;
  const Jet alpha =
      psy::alpha_for_threshold(spec.family, threshold_x, Jet(spec.p_threshold), Jet(exp(log_beta)), Jet(spec.guess),
                               Jet(spec.criterion_lapse));
  const int index[3] = {threshold_index, fit.index_log_beta(), fit.index_lambda()};
  // Parameters held fixed or at a bound carry no uncertainty; without a threshold variance there is no answer.
  if (!fit.covariance_ok || !fit.estimated[static_cast<std::size_t>(threshold_index)]) return NAN;
  const bool held[3] = {false, !fit.estimated[static_cast<std::size_t>(index[1])],
                        !fit.estimated[static_cast<std::size_t>(index[2])]};
  double variance = 0;
  for (int i = 0; i < 3; ++i) {
    if (held[i]) continue;
    for (int j = 0; j < 3; ++j) {
      if (held[j]) continue;
      variance += alpha.v[i] * alpha.v[j] * fit.cov(index[i], index[j]);
    }
  }
  return std::sqrt(variance);
}

}  // namespace penumbra::analysis
