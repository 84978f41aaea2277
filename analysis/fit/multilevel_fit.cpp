#include "fit/multilevel_fit.h"

#include <ceres/ceres.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <stdexcept>

#include "solver/solver_options.h"

namespace penumbra::analysis {

namespace psy = psychometric;

double student_t_quantile(double p, double dof) {
  const double z = std::sqrt(2.0) * psy::inverse_erf(2.0 * p - 1.0);
  if (!(dof > 0) || std::isinf(dof)) return z;
  const double z2 = z * z, z3 = z2 * z, z5 = z3 * z2, z7 = z5 * z2, z9 = z7 * z2;
  const double n = dof;
  return z + (z3 + z) / (4 * n) + (5 * z5 + 16 * z3 + 3 * z) / (96 * n * n) +
         (3 * z7 + 19 * z5 + 17 * z3 - 15 * z) / (384 * n * n * n) +
         (79 * z9 + 776 * z7 + 1482 * z5 - 1920 * z3 - 945 * z) / (92160 * n * n * n * n);
}

namespace {

constexpr int kNodes = 121;          // normal deviates in [-6, 6]
constexpr double kZMax = 6.0;
constexpr double kTableStep = 0.004;  // log10 units of the threshold tables
constexpr double kTableHalfWidth = 1.5;

// A participant's log-likelihood in one condition as a function of the threshold u, tabulated and
// read through a cubic (Catmull-Rom) so that numeric derivatives see a smooth function. Beyond the
// table the end value holds (the likelihood there is negligible beside the table's centre).
struct Table {
  double u0 = 0, step = kTableStep;
  std::vector<double> ll;
  double at(double u) const {
    const double f = (u - u0) / step;
    const int n = static_cast<int>(ll.size());
    if (f <= 1) return ll[1];
    if (f >= n - 2) return ll[static_cast<std::size_t>(n - 2)];
    const int i = static_cast<int>(std::floor(f));
    const double t = f - i;
    const double p0 = ll[static_cast<std::size_t>(i - 1)], p1 = ll[static_cast<std::size_t>(i)],
                 p2 = ll[static_cast<std::size_t>(i + 1)], p3 = ll[static_cast<std::size_t>(i + 2)];
    return p1 + 0.5 * t * (p2 - p0 + t * (2 * p0 - 5 * p1 + 4 * p2 - p3 + t * (3 * (p1 - p2) + p3 - p0)));
  }
  // The value and its derivative in u (0 beyond the table, where the value holds).
  double at(double u, double* slope) const {
    const double f = (u - u0) / step;
    const int n = static_cast<int>(ll.size());
    if (f <= 1 || f >= n - 2) {
      *slope = 0;
      return at(u);
    }
    const int i = static_cast<int>(std::floor(f));
    const double t = f - i;
    const double p0 = ll[static_cast<std::size_t>(i - 1)], p1 = ll[static_cast<std::size_t>(i)],
                 p2 = ll[static_cast<std::size_t>(i + 1)], p3 = ll[static_cast<std::size_t>(i + 2)];
    const double a = p2 - p0, b = 2 * p0 - 5 * p1 + 4 * p2 - p3, c = 3 * (p1 - p2) + p3 - p0;
    *slope = 0.5 * (a + 2 * t * b + 3 * t * t * c) / step;
    return p1 + 0.5 * t * (a + t * (b + t * c));
  }
};

struct Data {
  int conditions = 0;
  // tables[j][k]: participant j in condition k (empty ll where the participant lacks it).
  std::vector<std::vector<Table>> tables;
  std::vector<double> nodes, weights;  // standard normal deviates and trapezoid weights (sum 1)
};

// Which quantity a profile holds, and how the free parameters map to (u_1..u_K, sd).
struct Hold {
  enum Kind { none, mean, sd, percentile } kind = none;
  int condition = 0;
  double value = 0;  // mean, percentile: log10 c; sd: sd
  double z = 0;
};

int free_count(int conditions, const Hold& h) { return h.kind == Hold::none ? conditions + 1 : conditions; }

// Free parameters -> u (thresholds, -log10 c) and sd.
void unpack(const double* theta, int conditions, const Hold& h, std::vector<double>& u, double& sd) {
  u.assign(static_cast<std::size_t>(conditions), 0.0);
  int i = 0;
  for (int k = 0; k < conditions; ++k) {
    if ((h.kind == Hold::mean || h.kind == Hold::percentile) && k == h.condition) continue;
    u[static_cast<std::size_t>(k)] = theta[i++];
  }
  sd = h.kind == Hold::sd ? h.value : theta[i];
  if (h.kind == Hold::mean) u[static_cast<std::size_t>(h.condition)] = -h.value;
  if (h.kind == Hold::percentile) u[static_cast<std::size_t>(h.condition)] = -(h.value - h.z * sd);
}

// -log of participant j's marginal likelihood, and (when grad_u is given) its gradient in u (K)
// and in sd.
double participant_nll(const Data& d, std::size_t j, const std::vector<double>& u, double sd, double* grad_u = nullptr,
                       double* grad_sd = nullptr) {
  sd = std::max(0.0, sd);
  const std::size_t nodes = d.nodes.size(), K = static_cast<std::size_t>(d.conditions);
  double best = -INFINITY;
  static thread_local std::vector<double> ll, dll;  // per node: the sum over conditions; its slopes per condition
  ll.assign(nodes, 0.0);
  dll.assign(nodes * K, 0.0);
  for (std::size_t q = 0; q < nodes; ++q) {
    const double b = sd * d.nodes[q];  // log10 c offset: u - b
    double sum = 0;
    for (std::size_t k = 0; k < K; ++k) {
      const Table& t = d.tables[j][k];
      if (t.ll.empty()) continue;
      if (grad_u) sum += t.at(u[k] - b, &dll[q * K + k]);
      else sum += t.at(u[k] - b);
    }
    ll[q] = sum;
    best = std::max(best, sum);
  }
  double total = 0;
  for (std::size_t q = 0; q < nodes; ++q) {
    ll[q] = d.weights[q] * std::exp(ll[q] - best);  // now each node's share before normalising
    total += ll[q];
  }
  if (grad_u) {
    // d(-log L)/d u_k = -sum_q share_q ll'_k;  d/d sd = sum_q share_q z_q sum_k ll'_k.
    for (std::size_t k = 0; k < K; ++k) grad_u[k] = 0;
    *grad_sd = 0;
    for (std::size_t q = 0; q < nodes; ++q) {
      const double share = ll[q] / total;
      double slopes = 0;
      for (std::size_t k = 0; k < K; ++k) {
        grad_u[k] -= share * dll[q * K + k];
        slopes += dll[q * K + k];
      }
      *grad_sd += share * d.nodes[q] * slopes;
    }
  }
  return -(best + std::log(total));
}

// sqrt(2 NLL_j) with its analytic derivative in the free parameters (the map from them to u and sd
// is linear: Hold).
class ParticipantCost : public ceres::CostFunction {
 public:
  ParticipantCost(const Data* data, std::size_t j, Hold hold) : data_(data), j_(j), hold_(hold) {
    set_num_residuals(1);
    mutable_parameter_block_sizes()->push_back(free_count(data->conditions, hold));
  }
  bool Evaluate(double const* const* theta, double* residual, double** jacobians) const override {
    std::vector<double> u;
    double sd = 0;
    const int K = data_->conditions;
    unpack(theta[0], K, hold_, u, sd);
    std::vector<double> gu(static_cast<std::size_t>(K));
    double gsd = 0;
    const double nll = participant_nll(*data_, j_, u, sd, gu.data(), &gsd);
    const double r = std::sqrt(2.0 * std::max(nll, 1e-12));
    residual[0] = r;
    if (jacobians && jacobians[0]) {
      // The held percentile's threshold moves with sd: u_k = -(q - z sd).
      if (hold_.kind == Hold::percentile) gsd += hold_.z * gu[static_cast<std::size_t>(hold_.condition)];
      int i = 0;
      for (int k = 0; k < K; ++k) {
        if ((hold_.kind == Hold::mean || hold_.kind == Hold::percentile) && k == hold_.condition) continue;
        jacobians[0][i++] = gu[static_cast<std::size_t>(k)] / r;
      }
      if (hold_.kind != Hold::sd) jacobians[0][i] = gsd / r;
    }
    return true;
  }

 private:
  const Data* data_;
  std::size_t j_;
  Hold hold_;
};

double total_nll(const Data& d, const std::vector<double>& u, double sd) {
  double s = 0;
  for (std::size_t j = 0; j < d.tables.size(); ++j) s += participant_nll(d, j, u, sd);
  return s;
}

struct Solution {
  std::vector<double> u;
  double sd = 0, nll = NAN;
  bool converged = false;
};

Solution solve(const Data& d, const Hold& hold, const std::vector<double>& u_start, double sd_start) {
  const int n = free_count(d.conditions, hold);
  std::vector<double> theta;
  for (int k = 0; k < d.conditions; ++k)
    if (!((hold.kind == Hold::mean || hold.kind == Hold::percentile) && k == hold.condition)) theta.push_back(u_start[static_cast<std::size_t>(k)]);
  if (hold.kind != Hold::sd) theta.push_back(std::max(sd_start, 0.01));
  ceres::Problem problem;
  for (std::size_t j = 0; j < d.tables.size(); ++j) {
    problem.AddResidualBlock(new ParticipantCost(&d, j, hold), nullptr, theta.data());
  }
  if (hold.kind != Hold::sd) {
    problem.SetParameterLowerBound(theta.data(), n - 1, 0.0);
    problem.SetParameterUpperBound(theta.data(), n - 1, 1.0);
  }
  const ceres::Solver::Options options = solver::small_problem_options(1e-9);
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  Solution s;
  unpack(theta.data(), d.conditions, hold, s.u, s.sd);
  s.sd = std::max(0.0, s.sd);
  s.nll = total_nll(d, s.u, s.sd);
  s.converged = summary.termination_type == ceres::CONVERGENCE;
  return s;
}

// One end of a profile interval of a quantity at `estimate`: where 2 (NLL_profile - NLL_min) crosses
// `cutoff`, searched outward in steps that double, then bisected. `floor`: the quantity's least
// value (sd: 0), at which the end closes when the profile there is still within the cut-off.
struct End {
  double value = NAN;
  bool open = false;
};
End profile_end(const std::function<Solution(double)>& at, double estimate, double nll_min, double cutoff, double direction,
                double floor_value, double limit) {
  auto excess = [&](double v) { return 2.0 * (at(v).nll - nll_min) - cutoff; };
  double inside = estimate, step = 0.02, outside = NAN;
  for (int i = 0; i < 30; ++i) {
    double v = inside + direction * step;
    if (direction < 0 && v <= floor_value) {
      if (excess(floor_value) <= 0) return {floor_value, false};
      outside = floor_value;
      break;
    }
    if (std::abs(v - estimate) > limit) return {estimate + direction * limit, true};
    if (excess(v) > 0) {
      outside = v;
      break;
    }
    inside = v;
    step *= 2;
  }
  if (!std::isfinite(outside)) return {inside, true};
  // Illinois (regula falsi) between a point inside and one outside the cut-off.
  double f_in = excess(inside), f_out = excess(outside);
  int side = 0;
  for (int i = 0; i < 30 && std::abs(outside - inside) > 2e-4; ++i) {
    const double v = (f_out * inside - f_in * outside) / (f_out - f_in);
    const double fv = excess(v);
    if (std::abs(fv) < 1e-6) return {v, false};
    if (fv > 0) {
      outside = v, f_out = fv;
      if (side == -1) f_in *= 0.5;
      side = -1;
    } else {
      inside = v, f_in = fv;
      if (side == 1) f_out *= 0.5;
      side = 1;
    }
  }
  return {0.5 * (inside + outside), false};
}

MultilevelInterval c_of(const End& lo, const End& hi) {
  return {std::pow(10.0, lo.value), std::pow(10.0, hi.value), lo.open, hi.open};
}

}  // namespace

MultilevelFit fit_multilevel(const MultilevelInput& input, double percentile, double level) {
  if (!(percentile > 0 && percentile < 1)) throw std::invalid_argument("observer percentile must be in (0, 100)");
  if (!(level > 0 && level < 1)) throw std::invalid_argument("confidence level must be in (0, 1)");
  MultilevelFit out;
  out.percentile = percentile;
  out.level = level;
  out.z = std::sqrt(2.0) * psy::inverse_erf(2.0 * percentile - 1.0);
  const int K = static_cast<int>(input.condition_specs.size());
  out.participants = static_cast<int>(input.participants.size());
  if (out.participants < 3 || K < 1) return out;

  Data d;
  d.conditions = K;
  for (int q = 0; q < kNodes; ++q) {
    const double z = -kZMax + 2.0 * kZMax * q / (kNodes - 1);
    d.nodes.push_back(z);
    d.weights.push_back(std::exp(-0.5 * z * z) * ((q == 0 || q == kNodes - 1) ? 0.5 : 1.0));
  }
  double wsum = 0;
  for (double w : d.weights) wsum += w;
  for (double& w : d.weights) w /= wsum;
  const int table_points = static_cast<int>(2 * kTableHalfWidth / kTableStep) + 1;
  for (const MultilevelParticipant& p : input.participants) {
    std::vector<Table> per(static_cast<std::size_t>(K));
    for (int k = 0; k < K; ++k) {
      const auto& groups = p.conditions[static_cast<std::size_t>(k)];
      if (groups.empty()) continue;
      ModelSpec spec = input.condition_specs[static_cast<std::size_t>(k)];
      spec.groups = groups;
      for (Group& g : spec.groups) g.threshold_index = 0, g.offset = 0;
      spec.thresholds = 1;
      spec.power_law = false;
      Table& t = per[static_cast<std::size_t>(k)];
      t.u0 = input.u_start[static_cast<std::size_t>(k)] - kTableHalfWidth;
      Parameters params;
      params.log_beta = input.log_beta[static_cast<std::size_t>(k)];
      params.lambda = input.lambda[static_cast<std::size_t>(k)];
      for (int i = 0; i < table_points; ++i) {
        params.u = {t.u0 + i * t.step};
        t.ll.push_back(-negative_log_likelihood(spec, params));
      }
    }
    d.tables.push_back(std::move(per));
  }

  const Solution best = solve(d, {}, input.u_start, 0.05);
  out.fitted = true;
  out.converged = best.converged;
  if (!best.converged) out.flags.add("not_converged");
  out.nll = best.nll;
  out.sd_log10 = best.sd;
  const double dof = out.participants - 1;
  const double t = student_t_quantile(0.5 + 0.5 * level, dof);
  out.t_cutoff = t * t;
  const double t_sim = student_t_quantile(1.0 - 0.5 * (1.0 - level) / K, dof);
  const double cutoff_sim = t_sim * t_sim;
  const double chi2 = chi2_1_quantile(level);

  // sd: chi2(1) cut-off, closed at 0.
  const auto at_sd = [&](double v) { return solve(d, {Hold::sd, 0, v, 0}, best.u, v); };
  const End sd_lo = profile_end(at_sd, best.sd, best.nll, chi2, -1, 0.0, 1.0);
  const End sd_hi = profile_end(at_sd, best.sd, best.nll, chi2, +1, 0.0, 1.0);
  out.sd_ci = {sd_lo.value, sd_hi.value, sd_lo.open, sd_hi.open};
  if (best.sd < 1e-4) out.flags.add("sd_at_zero");

  for (int k = 0; k < K; ++k) {
    MultilevelFit::Condition c;
    c.log10_c = -best.u[static_cast<std::size_t>(k)];
    c.mean_c = std::pow(10.0, c.log10_c);
    const double q_hat = c.log10_c + out.z * best.sd;
    c.percentile_c = std::pow(10.0, q_hat);
    const auto at_mean = [&](double v) { return solve(d, {Hold::mean, k, v, 0}, best.u, best.sd); };
    const auto at_pct = [&](double v) { return solve(d, {Hold::percentile, k, v, out.z}, best.u, best.sd); };
    const double none = -INFINITY;
    c.mean_c_ci = c_of(profile_end(at_mean, c.log10_c, best.nll, out.t_cutoff, -1, none, 2.0),
                       profile_end(at_mean, c.log10_c, best.nll, out.t_cutoff, +1, none, 2.0));
    c.percentile_c_ci = c_of(profile_end(at_pct, q_hat, best.nll, out.t_cutoff, -1, none, 2.0),
                             profile_end(at_pct, q_hat, best.nll, out.t_cutoff, +1, none, 2.0));
    if (K == 1) {
      c.mean_c_ci_simultaneous = c.mean_c_ci;
      c.percentile_c_ci_simultaneous = c.percentile_c_ci;
    } else {
      c.mean_c_ci_simultaneous = c_of(profile_end(at_mean, c.log10_c, best.nll, cutoff_sim, -1, none, 2.0),
                                      profile_end(at_mean, c.log10_c, best.nll, cutoff_sim, +1, none, 2.0));
      c.percentile_c_ci_simultaneous = c_of(profile_end(at_pct, q_hat, best.nll, cutoff_sim, -1, none, 2.0),
                                            profile_end(at_pct, q_hat, best.nll, cutoff_sim, +1, none, 2.0));
    }
    out.conditions.push_back(c);
  }
  out.worst = 0;
  for (int k = 1; k < K; ++k)
    if (out.conditions[static_cast<std::size_t>(k)].log10_c > out.conditions[static_cast<std::size_t>(out.worst)].log10_c) out.worst = k;
  out.worst_mean_c_ci = out.conditions.front().mean_c_ci_simultaneous;
  out.worst_percentile_c_ci = out.conditions.front().percentile_c_ci_simultaneous;
  for (const auto& c : out.conditions) {
    auto& m = out.worst_mean_c_ci;
    m.lo = std::max(m.lo, c.mean_c_ci_simultaneous.lo);
    m.hi = std::max(m.hi, c.mean_c_ci_simultaneous.hi);
    m.lo_open = m.lo_open || c.mean_c_ci_simultaneous.lo_open;
    m.hi_open = m.hi_open || c.mean_c_ci_simultaneous.hi_open;
    auto& p = out.worst_percentile_c_ci;
    p.lo = std::max(p.lo, c.percentile_c_ci_simultaneous.lo);
    p.hi = std::max(p.hi, c.percentile_c_ci_simultaneous.hi);
    p.lo_open = p.lo_open || c.percentile_c_ci_simultaneous.lo_open;
    p.hi_open = p.hi_open || c.percentile_c_ci_simultaneous.hi_open;
  }
  return out;
}

}  // namespace penumbra::analysis
