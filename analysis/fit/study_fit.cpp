#include "fit/study_fit.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <map>
#include <mutex>
#include <set>
#include <stdexcept>
#include <thread>

#include "fit/statistics.h"
#include "procedure/config.h"
#include "procedure/procedure.h"
#include "sampling/random.h"

namespace penumbra::analysis {

namespace psy = psychometric;

double model_x(psy::Model family, double intensity) {
  return family == psy::Model::weibull ? std::pow(10.0, intensity) : intensity;
}

namespace {

double z_of(double level) { return std::sqrt(chi2_1_quantile(level)); }

// Rows at one stimulus level merged (the likelihood is the same; the fit has fewer residuals).
std::vector<BinomialRow> merge_rows(std::vector<BinomialRow> rows) {
  std::sort(rows.begin(), rows.end(), [](const BinomialRow& a, const BinomialRow& b) { return a.x < b.x; });
  std::vector<BinomialRow> out;
  for (const BinomialRow& r : rows) {
    if (!out.empty() && out.back().x == r.x) {
      out.back().n_correct += r.n_correct;
      out.back().n_total += r.n_total;
    } else {
      out.push_back(r);
    }
  }
  return out;
}

// c = 10^-u: a lower u bound is an upper c bound.
Interval c_interval(double u_lo, double u_hi, bool lo_open, bool hi_open) {
  return {std::pow(10.0, -u_hi), std::pow(10.0, -u_lo), hi_open, lo_open};
}

Interval wald_c(const FitResult& f, int index, double level) {
  const double u = f.params.u[static_cast<std::size_t>(index)], se = f.se(index), z = z_of(level);
  if (!std::isfinite(se)) return {};
  return c_interval(u - z * se, u + z * se, false, false);
}

ModelSpec base_spec(const StudyFitOptions& o, double p_threshold, double guess, double quest_delta) {
  ModelSpec s;
  s.family = o.family;
  s.guess = guess;
  s.p_threshold = p_threshold;
  s.criterion_lapse = psychometric::quest_lapse(quest_delta, guess);  // thresholds on F, as QUEST's
  s.lapse = o.lapse;
  return s;
}

void fit_participants(ConditionFit& cf, const std::map<std::string, std::vector<Group>>& by_participant,
                      const StudyFitOptions& o) {
  std::vector<double> log_c;
  for (const auto& [name, groups] : by_participant) {
    ParticipantFit pf;
    pf.participant = name;
    ModelSpec spec = cf.spec;
    spec.groups = groups;
    spec.u_min = cf.linear.u_min;
    spec.u_max = cf.linear.u_max;
    pf.fit = fit(spec);
    pf.c = std::pow(10.0, -pf.fit.params.u[0]);
    const Interval w = wald_c(pf.fit, 0, o.level);
    pf.c_lo = w.lo;
    pf.c_hi = w.hi;
    pf.flags = pf.fit.flags;
    log_c.push_back(std::log10(pf.c));
    cf.participants.push_back(pf);
  }
  if (cf.participants.size() < 4) return;  // too few for a robust spread
  const double m = median(log_c), spread = mad_sd(log_c);
  for (ParticipantFit& pf : cf.participants) {
    // The participant's own uncertainty widens the yardstick, so a tight group does not flag noise.
    const double se = pf.fit.se(0);
    const double scale = std::sqrt(spread * spread + (std::isfinite(se) ? se * se : 0.0));
    if (!(scale > 0)) continue;
    pf.robust_z = (std::log10(pf.c) - m) / scale;
    if (std::abs(pf.robust_z) > o.outlier_z) {
      pf.flags.add("far_from_rest");
      cf.flags.add("participant_far_from_rest");
    }
  }
}

void fit_linearity(ConditionFit& cf, const std::vector<std::pair<std::size_t, Group>>& sized_groups,
                   const StudyFitOptions& o) {
  const int k = static_cast<int>(cf.artifact_px.size());
  if (k < 2) {
    cf.flags.add("one_artifact_size");
    return;
  }
  // Free per-size thresholds.
  ModelSpec per_size = cf.spec;
  per_size.groups.clear();
  per_size.thresholds = k;
  for (const auto& [size_index, group] : sized_groups) {
    Group g = group;
    g.threshold_index = static_cast<int>(size_index);
    per_size.groups.push_back(g);
  }
  Parameters start = cf.linear.params;
  start.u.assign(static_cast<std::size_t>(k), cf.linear.params.u[0]);
  cf.per_size = fit(per_size, start);
  cf.linearity_tested = true;
  cf.lr_linear_stat = std::max(0.0, 2.0 * (cf.linear.nll - cf.per_size.nll));
  cf.lr_linear_dof = k - 1;
  cf.lr_linear_p = chi2_survival(cf.lr_linear_stat, cf.lr_linear_dof);
  for (int i = 0; i < k; ++i) {
    SizeThreshold st;
    st.artifact_px = cf.artifact_px[static_cast<std::size_t>(i)];
    for (const auto& [size_index, group] : sized_groups)
      if (static_cast<int>(size_index) == i)
        for (const BinomialRow& r : group.rows) st.trials += static_cast<int>(r.n_total);
    st.u = cf.per_size.params.u[static_cast<std::size_t>(i)];
    st.se_u = cf.per_size.se(i);
    st.c = std::pow(10.0, -st.u);
    const Interval w = wald_c(cf.per_size, i, o.level);
    st.c_lo = w.lo;
    st.c_hi = w.hi;
    cf.sizes.push_back(st);
  }
  // Power law r = k a^p around a_ref = geometric mean of the sizes.
  double log_sum = 0;
  for (double a : cf.artifact_px) log_sum += std::log10(a);
  cf.a_ref_px = std::pow(10.0, log_sum / k);
  ModelSpec power = cf.spec;
  power.groups.clear();
  power.power_law = true;
  for (const auto& [size_index, group] : sized_groups) {
    Group g = group;
    g.threshold_index = 0;
    g.offset = std::log10(cf.artifact_px[size_index] / cf.a_ref_px);
    power.groups.push_back(g);
  }
  cf.power = fit(power, cf.linear.params);
  cf.power_law_tested = true;
  const double s = cf.power.params.s;
  cf.exponent = 1.0 - s;
  cf.exponent_se = cf.power.se(cf.power.index_s());
  if (std::isfinite(cf.exponent_se)) {
    const double z = z_of(o.level);
    cf.exponent_wald = {cf.exponent - z * cf.exponent_se, cf.exponent + z * cf.exponent_se, false, false};
  }
  cf.k_px = std::pow(10.0, -cf.power.params.u[0] + s * std::log10(cf.a_ref_px));
  cf.lr_power_stat = std::max(0.0, 2.0 * (cf.linear.nll - cf.power.nll));
  cf.lr_power_p = chi2_survival(cf.lr_power_stat, 1);
}

// Runs body(i) for i in [0, n) on `threads` threads. A body that throws stops the others taking
// more; the exception of the lowest i is rethrown (the one a loop in order would have thrown, since
// every lower i was taken, and finished, before it).
void parallel_for(int n, int threads, const std::function<void(int)>& body) {
  std::atomic<int> next{0};
  std::mutex failure_mutex;
  int failed_at = n;
  std::exception_ptr failure;
  auto worker = [&] {
    for (int i = next++; i < n; i = next++) {
      try {
        body(i);
      } catch (...) {
        std::lock_guard<std::mutex> lock(failure_mutex);
        if (i < failed_at) failed_at = i, failure = std::current_exception();
        next = n;
      }
    }
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < std::max(1, std::min(threads, n)); ++t) pool.emplace_back(worker);
  worker();
  for (std::thread& t : pool) t.join();
  if (failure) std::rethrow_exception(failure);
}

// One phase of StudyFitOptions::progress: done counted over the threads, the callback called one at
// a time with done rising to total.
class Phase {
 public:
  Phase(const StudyFitOptions& options, std::string name, int total)
      : progress_(options.progress), name_(std::move(name)), total_(total) {
    if (progress_ && total_ > 0) progress_(name_, 0, total_);
  }
  void one_done() {
    if (!progress_ || total_ <= 0) return;
    std::lock_guard<std::mutex> lock(mutex_);
    progress_(name_, ++done_, total_);
  }

 private:
  const std::function<void(const std::string&, int, int)>& progress_;
  std::string name_;
  int total_ = 0, done_ = 0;
  std::mutex mutex_;
};

// `catches`: the staircase's yes/no catch trials, which its QUEST saw when the session was scored
// balanced (empty otherwise); merged with `trials` in trial order.
void recompute_quest(StaircaseFit& sf, const SessionInfo& session, const std::vector<const Trial*>& trials,
                     const std::vector<const Trial*>& catches) {
  std::vector<const Trial*> seen = trials;
  seen.insert(seen.end(), catches.begin(), catches.end());
  std::sort(seen.begin(), seen.end(), [](const Trial* a, const Trial* b) { return a->row.trial < b->row.trial; });
  sf.logged_quest_mean = seen.back()->row.quest_mean;
  sf.logged_quest_sd = seen.back()->row.quest_sd;
  if (!session.quest) return;
  quest::QuestParams params = *session.quest;
  if (procedure::is_tail_staircase(sf.staircase, session.tail_p_threshold)) params.p_threshold = session.tail_p_threshold;
  quest::Quest q(params, session.quest_dim);
  for (const Trial* t : seen) q.update(t->row.intensity, t->row.correct);
  sf.quest_recomputed = true;
  sf.quest_mean = q.mean();
  sf.quest_sd = q.sd();
  auto same = [](double a, double b) { return std::abs(a - b) <= 1e-9 * std::max(1.0, std::abs(b)); };
  sf.quest_matches_log = same(sf.quest_mean, sf.logged_quest_mean) && same(sf.quest_sd, sf.logged_quest_sd);
  if (!sf.quest_matches_log) sf.flags.add("quest_replay_differs");
}

}  // namespace

BootstrapSummary bootstrap_participants(const ModelSpec& base, const std::vector<std::vector<Group>>& participants,
                                        const Parameters& start, int resamples, std::uint64_t seed, int threads,
                                        double level, const std::function<void()>& one_done) {
  BootstrapSummary out;
  if (participants.size() < 2 || resamples < 1) return out;
  out.resamples = resamples;
  std::vector<double> log_c(static_cast<std::size_t>(resamples), NAN);
  std::vector<char> flagged(static_cast<std::size_t>(resamples), 0);
  parallel_for(resamples, threads, [&](int i) {
    sampling::Random random(sampling::derive_seed(seed, static_cast<std::uint64_t>(i)));
    ModelSpec spec = base;
    spec.groups.clear();
    for (std::size_t j = 0; j < participants.size(); ++j) {
      const auto& pick = participants[random.bits() % participants.size()];
      spec.groups.insert(spec.groups.end(), pick.begin(), pick.end());
    }
    const FitResult f = fit(spec, start, false);
    log_c[static_cast<std::size_t>(i)] = -f.params.u[0];
    flagged[static_cast<std::size_t>(i)] =
        f.flags.has("threshold_at_bound") || f.flags.has("not_converged") ? 1 : 0;
    if (one_done) one_done();
  });
  for (char f : flagged) out.flagged += f;
  const double tail = 0.5 * (1.0 - level);
  out.c = {std::pow(10.0, percentile(log_c, tail)), std::pow(10.0, percentile(log_c, 1.0 - tail)), false, false};
  double mean = 0;
  for (double v : log_c) mean += v;
  mean /= static_cast<double>(log_c.size());
  double ss = 0;
  for (double v : log_c) ss += (v - mean) * (v - mean);
  out.sd_log10_c = log_c.size() > 1 ? std::sqrt(ss / static_cast<double>(log_c.size() - 1)) : NAN;
  for (double v : log_c) out.c_values.push_back(std::pow(10.0, v));
  return out;
}

namespace {

Interval hull(const Interval& a, const Interval& b) {
  if (!std::isfinite(a.lo) || !std::isfinite(a.hi)) return b;
  if (!std::isfinite(b.lo) || !std::isfinite(b.hi)) return a;
  return {std::min(a.lo, b.lo), std::max(a.hi, b.hi), a.lo_open || b.lo_open, a.hi_open || b.hi_open};
}

// One model over every condition: thresholds per condition (or one for all), slope and lapse shared.
ModelSpec joint_spec(const StudyFit& fit, const std::vector<std::map<std::string, std::vector<Group>>>& groups, bool one_threshold) {
  ModelSpec spec = fit.conditions.front().spec;
  spec.groups.clear();
  spec.thresholds = one_threshold ? 1 : static_cast<int>(groups.size());
  spec.u_min = std::nullopt;
  spec.u_max = std::nullopt;
  for (std::size_t k = 0; k < groups.size(); ++k)
    for (const auto& [participant, list] : groups[k])
      for (Group g : list) {
        g.threshold_index = one_threshold ? 0 : static_cast<int>(k);
        spec.groups.push_back(std::move(g));
      }
  return spec;
}

}  // namespace

namespace {

// The population's worst-case interval into the entry's ci95; an interval the profile never closed
// (too few participants or trials to bound the spread) is kept beside it and flagged, not hulled:
// it would say nothing but "unbounded".
void add_population(WorstCase& w, const MultilevelFit& m) {
  if (!m.fitted) return;
  const MultilevelInterval& i = m.worst_mean_c_ci;
  w.population = {i.lo, i.hi, i.lo_open, i.hi_open};
  if (i.lo_open || i.hi_open || !(i.lo > 0.01 && i.hi < 1000)) {
    w.flags.add("population_interval_open");
    return;
  }
  w.ci95 = hull(w.ci95, w.population);
}

}  // namespace

WorstCase worst_case(const StudyFit& fit, const std::vector<std::map<std::string, std::vector<Group>>>& groups,
                     const StudyFitOptions& options, int threads, const std::function<void()>& one_done) {
  WorstCase w;
  if (fit.conditions.empty()) return w;
  const double tail = 0.5 * (1.0 - options.level);
  if (fit.conditions.size() == 1) {
    const ConditionFit& only = fit.conditions.front();
    w.method = "single condition";
    w.condition = only.condition;
    w.c = only.c;
    w.profile = only.c_profile;
    w.bootstrap = only.bootstrap.c;
    w.resamples = only.bootstrap.resamples;
    w.ci95 = hull(w.profile, w.bootstrap);
    w.beta = only.beta;
    w.beta_wald = only.beta_wald;
    w.lapse = only.linear.params.lambda;
    w.flags = only.flags;
    add_population(w, fit.population);
    return w;
  }
  // Do the conditions differ? One threshold for all against one per condition.
  const ModelSpec one = joint_spec(fit, groups, true), each = joint_spec(fit, groups, false);
  FitResult f_one, f_each;
  parallel_for(2, threads, [&](int i) { (i == 0 ? f_one : f_each) = analysis::fit(i == 0 ? one : each); });
  w.lr_dof = static_cast<int>(fit.conditions.size()) - 1;
  w.lr_stat = std::max(0.0, 2.0 * (f_one.nll - f_each.nll));
  w.lr_p = chi2_survival(w.lr_stat, w.lr_dof);
  const ConditionFit* largest = &fit.conditions.front();
  for (const ConditionFit& c : fit.conditions)
    if (c.c > largest->c) largest = &c;
  w.max_c = largest->c;
  // The worst case without a significance gate (issue 48): each condition's log10 c shrunk toward
  // their precision-weighted mean by the between-condition variance the data show
  // (DerSimonian-Laird: tau^2 = max(0, (Q - (K - 1)) / (sum w - sum w^2 / sum w)), weights 1 / se^2
  // of each condition's joint fit), theta_k* = mean + tau^2 / (tau^2 + se_k^2) (theta_k - mean),
  // and the largest of them. Equal conditions give tau^2 = 0 most of the time: the conditions' one
  // c (the pooled fit), which no maximum biased; clearly different ones are barely shrunk: the
  // largest. In between the estimate moves smoothly, with no test deciding. Its interval (below)
  // holds the population's worst-case interval, which covers whatever the differences.
  std::vector<double> theta, se2;
  for (const ConditionFit& c : fit.conditions) {
    theta.push_back(std::log10(c.c));
    double se = c.linear.se(0);
    if (!std::isfinite(se) && std::isfinite(c.c_profile.lo) && std::isfinite(c.c_profile.hi))
      se = std::log10(c.c_profile.hi / c.c_profile.lo) / (2 * z_of(options.level));
    se2.push_back(std::isfinite(se) && se > 0 ? se * se : 1.0);
  }
  double sw = 0, sw2 = 0, weighted_mean = 0;
  for (std::size_t k = 0; k < theta.size(); ++k) sw += 1 / se2[k], sw2 += 1 / (se2[k] * se2[k]), weighted_mean += theta[k] / se2[k];
  weighted_mean /= sw;
  double q = 0;
  for (std::size_t k = 0; k < theta.size(); ++k) q += (theta[k] - weighted_mean) * (theta[k] - weighted_mean) / se2[k];
  const double tau2 = std::max(0.0, (q - static_cast<double>(theta.size() - 1)) / (sw - sw2 / sw));
  w.tau_log10 = std::sqrt(tau2);
  const bool pooled = tau2 <= 0;
  std::size_t chosen = 0;
  double largest_log10 = -INFINITY;
  for (std::size_t k = 0; k < theta.size(); ++k) {
    const double shrunk = weighted_mean + tau2 / (tau2 + se2[k]) * (theta[k] - weighted_mean);
    if (shrunk > largest_log10) largest_log10 = shrunk, chosen = k;
  }
  const ConditionFit* largest_shrunk = &fit.conditions[chosen];
  // The participants, and each one's groups per condition (empty where a participant lacks one).
  std::vector<std::string> people;
  for (const auto& per_condition : groups)
    for (const auto& [participant, list] : per_condition)
      if (std::find(people.begin(), people.end(), participant) == people.end()) people.push_back(participant);
  if (pooled) {
    w.method = "pooled";
    w.condition = "all conditions";
    w.c = std::pow(10.0, -f_one.params.u[0]);
    ModelSpec bounded = one;
    bounded.u_min = f_one.u_min;
    bounded.u_max = f_one.u_max;
    const ProfileInterval p = profile_interval(bounded, f_one, 0, options.level, threads);
    w.profile = c_interval(p.lo, p.hi, p.lo_open, p.hi_open);
    w.beta = std::exp(f_one.params.log_beta);
    w.lapse = f_one.params.lambda;
    w.flags = f_one.flags;
    if (p.lo_open || p.hi_open) w.flags.add("interval_open");
    if (const double se = f_one.se(f_one.index_log_beta()); std::isfinite(se)) {
      const double z = z_of(options.level);
      w.beta_wald = {std::exp(f_one.params.log_beta - z * se), std::exp(f_one.params.log_beta + z * se), false, false};
    }
  } else {
    w.method = "shrunken maximum";
    w.condition = largest_shrunk->condition;
    w.c = std::pow(10.0, largest_log10);
    w.profile = largest_shrunk->c_profile;
    w.beta = largest_shrunk->beta;
    w.beta_wald = largest_shrunk->beta_wald;
    w.lapse = largest_shrunk->linear.params.lambda;
    w.flags = largest_shrunk->flags;
  }
  if (options.bootstrap > 0 && people.size() >= 2) {
    // Participants resampled with replacement, the same draw for every condition (paired).
    std::vector<double> values(static_cast<std::size_t>(options.bootstrap), NAN);
    parallel_for(options.bootstrap, threads, [&](int i) {
      sampling::Random random(sampling::derive_seed(options.seed, 0x776f727374ull + static_cast<std::uint64_t>(i)));  // "worst"
      std::vector<std::string> draw;
      for (std::size_t j = 0; j < people.size(); ++j) draw.push_back(people[random.bits() % people.size()]);
      std::vector<std::map<std::string, std::vector<Group>>> resampled(groups.size());
      for (std::size_t k = 0; k < groups.size(); ++k)
        for (std::size_t j = 0; j < draw.size(); ++j)
          if (const auto it = groups[k].find(draw[j]); it != groups[k].end())
            resampled[k][draw[j] + "#" + std::to_string(j)] = it->second;  // a participant drawn twice counts twice
      double value = NAN;
      {
        double best = -INFINITY;
        for (std::size_t k = 0; k < groups.size(); ++k) {
          if (resampled[k].empty()) continue;
          ModelSpec spec = fit.conditions[k].spec;
          spec.groups.clear();
          for (const auto& [name, list] : resampled[k]) spec.groups.insert(spec.groups.end(), list.begin(), list.end());
          best = std::max(best, -analysis::fit(spec, fit.conditions[k].linear.params, false).params.u[0]);
        }
        value = std::isfinite(best) ? best : NAN;
      }
      values[static_cast<std::size_t>(i)] = value;
      if (one_done) one_done();
    });
    values.erase(std::remove_if(values.begin(), values.end(), [](double v) { return !std::isfinite(v); }), values.end());
    if (!values.empty()) {
      w.resamples = static_cast<int>(values.size());
      double shift = 0;
      {
        double mean = 0;
        for (double v : values) mean += v;
        mean /= static_cast<double>(values.size());
        w.bias_log10 = mean - std::log10(w.max_c);
        shift = w.bias_log10;
      }
      w.bootstrap = {std::pow(10.0, percentile(values, tail) - shift), std::pow(10.0, percentile(values, 1.0 - tail) - shift), false,
                     false};
    }
  }
  w.ci95 = hull(w.profile, w.bootstrap);
  // The population's worst case (fit/multilevel_fit.h): participants as random effects, the largest
  // of the conditions' simultaneous intervals.
  add_population(w, fit.population);
  return w;
}

MultilevelFit population_fit(const StudyFit& fit, const std::vector<std::map<std::string, std::vector<Group>>>& groups,
                             const StudyFitOptions& options) {
  MultilevelInput input;
  std::map<std::string, std::size_t> index;
  for (std::size_t k = 0; k < fit.conditions.size(); ++k) {
    const ConditionFit& cf = fit.conditions[k];
    input.condition_specs.push_back(cf.spec);
    input.log_beta.push_back(cf.linear.params.log_beta);
    input.lambda.push_back(cf.linear.params.lambda);
    input.u_start.push_back(cf.linear.params.u[0]);
    for (const auto& [participant, list] : groups[k]) {
      if (!index.count(participant)) {
        index[participant] = input.participants.size();
        input.participants.push_back({participant, std::vector<std::vector<Group>>(fit.conditions.size())});
      }
      input.participants[index[participant]].conditions[k] = list;
    }
  }
  return fit_multilevel(input, options.observer_percentile, options.level);
}

CAtVisibilityFit condition_c_at_visibility(const StudyFit& fit, std::size_t condition, double visibility) {
  if (!(visibility > 0 && visibility < 1)) throw std::invalid_argument("visibility: expected a detection probability in (0, 1)");
  if (condition >= fit.conditions.size()) throw std::invalid_argument("condition " + std::to_string(condition) + ": no such condition");
  const FitResult& f = fit.conditions[condition].linear;
  const psy::Model family = fit.options.family;
  // log10 c(F) from u (c = 10^-u) and log beta; the Weibull's x is the ratio a / r, the others' its log10.
  const auto log10_c_at = [&](double u, double log_beta) {
    const bool linear = family == psy::Model::weibull;
    const double x = psy::threshold_at(family, linear ? std::pow(10.0, u) : u, fit.criterion_f, visibility, std::exp(log_beta));
    return linear ? -std::log10(x) : -x;
  };
  const double u = f.params.u[0], log_beta = f.params.log_beta;
  CAtVisibilityFit out;
  out.c = std::pow(10.0, log10_c_at(u, log_beta));
  if (!f.covariance_ok) return out;
  const int iu = 0, ib = f.index_log_beta();
  constexpr double h = 1e-6;
  const double du = (log10_c_at(u + h, log_beta) - log10_c_at(u - h, log_beta)) / (2 * h);
  double db = 0, var_b = 0, cov_ub = 0;
  if (std::isfinite(f.se(ib))) {  // a slope held fixed has no variance
    db = (log10_c_at(u, log_beta + h) - log10_c_at(u, log_beta - h)) / (2 * h);
    var_b = f.cov(ib, ib);
    cov_ub = f.cov(iu, ib);
  }
  const double var = du * du * f.cov(iu, iu) + db * db * var_b + 2 * du * db * cov_ub;
  if (!(var >= 0) || !std::isfinite(var)) return out;
  const double half = z_of(fit.options.level) * std::sqrt(var), log_c = std::log10(out.c);
  out.ci = {std::pow(10.0, log_c - half), std::pow(10.0, log_c + half), false, false};
  return out;
}

std::vector<ThesisEstimate> thesis_estimates(const StudyFit& fit) {
  std::vector<ThesisEstimate> out;
  for (const ConditionFit& c : fit.conditions) {
    ThesisEstimate t;
    t.condition = c.condition;
    // Per participant and size one staircase: its radius r = a 10^-(QUEST's final mean).
    std::map<double, std::vector<double>> radii;
    for (const StaircaseFit& s : fit.staircases) {
      // The thesis ran one target; a tail staircase's QUEST mean is another point of the function.
      if (s.condition != c.condition || s.tail) continue;
      const double mean = s.quest_recomputed ? s.quest_mean : s.logged_quest_mean;
      if (!std::isfinite(mean)) continue;
      radii[s.artifact_px].push_back(s.artifact_px * std::pow(10.0, -mean));
      ++t.staircases;
    }
    double num = 0, den = 0;
    for (const auto& [a, r] : radii) {
      double sum = 0;
      for (double v : r) sum += v;
      const double mean_r = sum / static_cast<double>(r.size());
      t.artifact_px.push_back(a);
      t.mean_radius_px.push_back(mean_r);
      num += a * mean_r;
      den += a * a;
    }
    t.c = den > 0 ? num / den : NAN;  // least squares through the origin: r = c a
    out.push_back(std::move(t));
  }
  return out;
}

StudyFit fit_study(const Dataset& data, const StudyFitOptions& options) {
  if (!(options.level > 0 && options.level < 1)) throw std::invalid_argument("confidence level must be in (0, 1)");
  if (options.bootstrap < 0) throw std::invalid_argument("bootstrap resamples must be >= 0");
  StudyFit out;
  out.options = options;
  out.sessions = static_cast<int>(data.sessions.size());
  for (const SessionInfo& s : data.sessions) {
    if (s.browser_pixels_per_degree) {  // measured in the participant's browser, not the config's monitor
      out.pixels_per_degree[s.participant] = *s.browser_pixels_per_degree;
      continue;
    }
    const auto field = [&](const char* key) {
      const auto it = s.setup.find(std::string("display.") + key);
      return it == s.setup.end() ? NAN : std::strtod(it->second.c_str(), nullptr);
    };
    const double width_px = field("width_px");  // NaN when session.json records no display
    procedure::Display d;
    d.width_mm = field("width_mm");
    d.viewing_distance_mm = field("viewing_distance_mm");
    if (!(width_px >= 1 && width_px <= 1e6 && d.width_mm > 0 && d.viewing_distance_mm > 0)) continue;
    d.width_px = static_cast<int>(width_px);
    out.pixels_per_degree[s.participant] = d.pixels_per_degree();
  }
  out.trials = static_cast<int>(data.trials.size());
  out.practice_rows_excluded = data.practice_rows;
  out.inconsistencies = data.inconsistencies;
  out.pooled_differences = data.pooled_differences;
  // pThreshold: the option, else the sessions' QUEST value when they agree, else QUEST's default.
  std::set<double> p_thresholds, gammas, deltas;
  for (const SessionInfo& s : data.sessions) {
    if (s.quest) {
      p_thresholds.insert(s.quest->p_threshold);
      gammas.insert(s.quest->gamma);
      deltas.insert(s.quest->delta);
    }
    else out.notes.push_back(s.log_file + ": no session.json with QUEST parameters; QUEST posterior not recomputed");
    if (s.torn_tail) out.notes.push_back(s.log_file + ": last line torn (an unanswered trial); ignored");
  }
  out.p_threshold = options.p_threshold ? *options.p_threshold
                                        : (p_thresholds.size() == 1 ? *p_thresholds.begin() : 0.82);
  if (!options.p_threshold && p_thresholds.size() > 1)
    out.notes.push_back("sessions use different QUEST pThreshold values; thresholds are at 0.82");
  out.guess = options.guess ? *options.guess : (gammas.size() == 1 ? *gammas.begin() : 0.5);
  if (!options.guess && gammas.size() > 1)
    out.notes.push_back("sessions use different QUEST gamma values; the guess rate is 0.5");
  // The criterion F* of a threshold is QUEST's (its delta), so c means what QUEST converged to.
  out.quest_delta = deltas.size() == 1 ? *deltas.begin() : 0.01;
  if (deltas.size() > 1) out.notes.push_back("sessions use different QUEST delta values; the criterion uses delta 0.01");
  out.criterion_f = psychometric::criterion_f(out.p_threshold, out.guess, out.quest_delta);
  // A --p-threshold the curves never reach is the option's fault, not the sessions' (it was
  // refused by the fit, naming no option, exit 1).
  if (options.p_threshold && !(out.criterion_f > 0 && out.criterion_f < 1)) {
    char line[200];
    std::snprintf(line, sizeof line,
                  "--p-threshold %g: expected a proportion correct between the guess rate %g and %g (1 - QUEST's delta lapse)",
                  out.p_threshold, out.guess, 1 - out.quest_delta * (1 - out.guess));
    throw std::invalid_argument(line);
  }
  if (!data.trials.empty()) out.task = data.trials.front().row.task;
  // yes/no: the fits model detections on the jagged trials, P = fa + (1 - fa - lambda) F, with
  // each participant's own false-alarm rate as the guess rate. QUEST's gamma is what the session
  // assumed (0.5 in the published design, where it misreads a participant who rarely says "not
  // straight"); the data say what the participant did.
  std::optional<double> forced_guess = options.guess;
  if (out.task == "yesno" && !options.guess) {
    for (const Trial& t : data.trials) out.false_alarms[t.row.participant];
    for (const Trial& t : data.catch_trials) {
      StudyFit::FalseAlarms& fa = out.false_alarms[t.row.participant];
      ++fa.catch_trials;
      fa.false_alarms += t.row.response == "no" ? 1 : 0;
    }
    for (auto& [participant, fa] : out.false_alarms) {
      if (fa.catch_trials == 0) {
        fa.rate = out.guess;
        out.notes.push_back("yesno: participant " + participant + " has no catch trials; their guess rate is QUEST's " +
                            format_number(out.guess));
      } else {
        fa.rate = (fa.false_alarms + 0.5) / (fa.catch_trials + 1.0);
      }
    }
  }
  auto participant_guess = [&](const std::string& participant) -> std::optional<double> {
    if (forced_guess || out.task != "yesno") return std::nullopt;
    return out.false_alarms.at(participant).rate;
  };
  if (data.catch_rows > 0)
    out.notes.push_back("yesno: " + std::to_string(data.catch_rows) +
                        " straight (catch) trials give each participant's false-alarm rate (all: " +
                        format_number(double(data.catch_false_alarms) / data.catch_rows) +
                        "), the guess rate of their detections; the fits use the jagged trials");
  const int threads = options.threads > 0 ? options.threads
                                          : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));

  // Conditions in order of first appearance.
  std::vector<std::string> order;
  std::map<std::string, std::vector<const Trial*>> by_condition;
  for (const Trial& t : data.trials) {
    const std::string name = condition_name(t.row.pattern, t.row.contrast);
    if (!by_condition.count(name)) order.push_back(name);
    by_condition[name].push_back(&t);
  }

  // Each condition's fits but the bootstrap, the conditions side by side (a study of one
  // condition searches its profile interval's two ends at once instead).
  const int condition_count = static_cast<int>(order.size());
  std::vector<ConditionFit> conditions(order.size());
  std::vector<std::map<std::string, std::vector<Group>>> condition_groups(order.size());  // per condition: participant -> groups
  {
    // Four steps each: the joint fit, its profile interval, the linearity fits, the participants'.
    Phase phase(options, "conditions", 4 * condition_count);
    parallel_for(condition_count, threads, [&](int k) {
      const std::string& name = order[static_cast<std::size_t>(k)];
      ConditionFit& cf = conditions[static_cast<std::size_t>(k)];
      std::map<std::string, std::vector<Group>>& by_participant = condition_groups[static_cast<std::size_t>(k)];
      const auto& trials = by_condition.at(name);
      cf.condition = name;
      cf.pattern = trials.front()->row.pattern;
      cf.contrast = trials.front()->row.contrast;
      cf.trials = static_cast<int>(trials.size());
      std::set<double> sizes;
      for (const Trial* t : trials) sizes.insert(t->row.artifact_px);
      cf.artifact_px.assign(sizes.begin(), sizes.end());
      // Groups per (participant, size).
      std::map<std::pair<std::string, std::size_t>, std::vector<BinomialRow>> rows;
      for (const Trial* t : trials) {
        const std::size_t size_index = static_cast<std::size_t>(
            std::lower_bound(cf.artifact_px.begin(), cf.artifact_px.end(), t->row.artifact_px) - cf.artifact_px.begin());
        rows[{t->row.participant, size_index}].push_back(
            {model_x(options.family, t->row.intensity), static_cast<double>(t->row.correct), 1.0});
      }
      std::vector<std::pair<std::size_t, Group>> sized_groups;
      cf.spec = base_spec(options, out.p_threshold, out.guess, out.quest_delta);
      for (auto& [key, r] : rows) {
        Group g{merge_rows(std::move(r)), 0, 0.0, participant_guess(key.first)};
        sized_groups.emplace_back(key.second, g);
        by_participant[key.first].push_back(g);
        cf.spec.groups.push_back(g);
      }
      cf.participant_count = static_cast<int>(by_participant.size());
      cf.linear = fit(cf.spec);
      phase.one_done();
      cf.spec.u_min = cf.linear.u_min;  // every later fit of this condition shares the bounds
      cf.spec.u_max = cf.linear.u_max;
      cf.flags = cf.linear.flags;
      cf.c = std::pow(10.0, -cf.linear.params.u[0]);
      const ProfileInterval profile =
          profile_interval(cf.spec, cf.linear, 0, options.level, condition_count == 1 ? threads : 1);
      phase.one_done();
      cf.c_profile = c_interval(profile.lo, profile.hi, profile.lo_open, profile.hi_open);
      if (profile.lo_open || profile.hi_open) cf.flags.add("interval_open");
      cf.c_wald = wald_c(cf.linear, 0, options.level);
      cf.beta = std::exp(cf.linear.params.log_beta);
      if (const double se = cf.linear.se(cf.linear.index_log_beta()); std::isfinite(se)) {
        const double z = z_of(options.level);
        cf.beta_wald = {std::exp(cf.linear.params.log_beta - z * se), std::exp(cf.linear.params.log_beta + z * se), false, false};
      }
      fit_linearity(cf, sized_groups, options);
      phase.one_done();
      fit_participants(cf, by_participant, options);
      if (by_participant.size() < 2) cf.flags.add("one_participant");
      phase.one_done();
    });
  }

  // The bootstraps over participants: each condition's, then the worst case's, each resample a fit
  // of its own on the threads.
  std::map<std::string, double> condition_lambda, condition_beta;
  int total_bootstrap = 0;
  std::set<std::string> people;
  for (const auto& by_participant : condition_groups) {
    if (by_participant.size() >= 2) total_bootstrap += options.bootstrap;
    for (const auto& [participant, groups] : by_participant) people.insert(participant);
  }
  if (order.size() > 1 && people.size() >= 2) total_bootstrap += options.bootstrap;  // the worst case's
  {
    Phase phase(options, "bootstrap", total_bootstrap);
    const auto one_done = [&phase] { phase.one_done(); };
    for (std::size_t k = 0; k < conditions.size(); ++k) {
      ConditionFit& cf = conditions[k];
      if (condition_groups[k].size() >= 2 && options.bootstrap > 0) {
        std::vector<std::vector<Group>> groups;
        for (auto& [name_p, g] : condition_groups[k]) groups.push_back(g);
        cf.bootstrap = bootstrap_participants(cf.spec, groups, cf.linear.params, options.bootstrap,
                                              sampling::derive_seed(options.seed, k), threads, options.level, one_done);
        const double profile_width = std::log10(cf.c_profile.hi / cf.c_profile.lo);
        const double boot_width = std::log10(cf.bootstrap.c.hi / cf.bootstrap.c.lo);
        if (std::isfinite(profile_width) && boot_width > 1.5 * profile_width) cf.flags.add("participants_differ");
      }
      condition_lambda[cf.condition] = cf.linear.params.lambda;
      condition_beta[cf.condition] = std::exp(cf.linear.params.log_beta);
      out.conditions.push_back(std::move(cf));
    }
    out.population = population_fit(out, condition_groups, options);
    out.worst = worst_case(out, condition_groups, options, threads, one_done);
  }

  // Staircases: (session, round, staircase) in log order.
  std::map<std::tuple<std::size_t, int, std::string>, std::vector<const Trial*>> staircases;
  std::vector<std::tuple<std::size_t, int, std::string>> staircase_order;
  for (const Trial& t : data.trials) {
    const auto key = std::make_tuple(t.session, t.row.condition_index, t.row.staircase);
    if (!staircases.count(key)) staircase_order.push_back(key);
    staircases[key].push_back(&t);
  }
  // The catch trials a balanced-scored session's QUEST saw, by staircase (one pass, not one per staircase).
  std::map<std::tuple<std::size_t, int, std::string>, std::vector<const Trial*>> staircase_catches;
  for (const Trial& t : data.catch_trials)
    if (data.sessions[t.session].yesno_scoring == "balanced")
      staircase_catches[std::make_tuple(t.session, t.row.condition_index, t.row.staircase)].push_back(&t);
  // Checked before any fit, so that the first bad row in log order is the one named.
  for (const auto& key : staircase_order) {
    const auto& trials = staircases[key];
    const trial_log::TrialRow& first = trials.front()->row;
    const std::string condition = condition_name(first.pattern, first.contrast);
    for (const Trial* t : trials)
      if (t->row.artifact_px != first.artifact_px || condition_name(t->row.pattern, t->row.contrast) != condition)
        throw std::runtime_error(data.sessions[std::get<0>(key)].log_file + ":" + std::to_string(t->line) + ": staircase '" +
                                 first.staircase + "' of round " + std::to_string(first.condition_index) +
                                 " changes artifact size or condition");
  }
  out.staircases.resize(staircase_order.size());
  {
    Phase phase(options, "staircases", static_cast<int>(staircase_order.size()));
    parallel_for(static_cast<int>(staircase_order.size()), threads, [&](int index) {
      const auto& key = staircase_order[static_cast<std::size_t>(index)];
      const auto& trials = staircases.at(key);
      const SessionInfo& session = data.sessions[std::get<0>(key)];
      const trial_log::TrialRow& first = trials.front()->row;
      StaircaseFit& sf = out.staircases[static_cast<std::size_t>(index)];
      sf.participant = session.participant;
      sf.session_id = session.session_id;
      sf.condition = condition_name(first.pattern, first.contrast);
      sf.staircase = first.staircase;
      sf.artifact_px = first.artifact_px;
      sf.round = first.condition_index;
      sf.tail = procedure::is_tail_staircase(sf.staircase, session.tail_p_threshold);
      ModelSpec spec = base_spec(options, out.p_threshold, out.guess, out.quest_delta);
      // A staircase's 20-40 trials sit near its threshold and cannot tell a slope: free, it ran to
      // its bound on half of clean simulated staircases (a step function, flagged). The slope and
      // the lapse are the condition's, so each staircase gives its threshold only.
      spec.lapse.fixed = condition_lambda.at(sf.condition);
      spec.slope.fixed = condition_beta.at(sf.condition);
      std::vector<BinomialRow> rows;
      for (const Trial* t : trials) {
        rows.push_back({model_x(options.family, t->row.intensity), static_cast<double>(t->row.correct), 1.0});
        sf.track.push_back({t->row.trial, t->row.intensity, t->row.filter_radius_px, t->row.correct, t->row.clamped != 0});
      }
      spec.groups.push_back({merge_rows(std::move(rows)), 0, 0.0, participant_guess(session.participant)});
      sf.fit = fit(spec);
      sf.flags = sf.fit.flags;
      sf.c = std::pow(10.0, -sf.fit.params.u[0]);
      const Interval w = wald_c(sf.fit, 0, options.level);
      sf.c_lo = w.lo;
      sf.c_hi = w.hi;
      const auto catches = staircase_catches.find(key);
      recompute_quest(sf, session, trials, catches == staircase_catches.end() ? std::vector<const Trial*>{} : catches->second);
      const double final_sd = sf.quest_recomputed ? sf.quest_sd : sf.logged_quest_sd;
      sf.converged = final_sd <= session.sd_below && !sf.fit.flags.has("threshold_at_bound") &&
                     !sf.fit.flags.has("covariance_failed") && !sf.fit.flags.has("not_converged");
      if (!sf.converged) sf.flags.add("staircase_not_converged");
      phase.one_done();
    });
  }
  out.thesis = thesis_estimates(out);
  return out;
}

}  // namespace penumbra::analysis
