#include "fit/plan.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <stdexcept>
#include <thread>

#include "data/simulate.h"
#include "fit/statistics.h"
#include "fit/study_fit.h"
#include "sampling/random.h"

namespace penumbra::analysis {

PlanResult plan_study(const PlanOptions& o) {
  if (o.participants < 2) throw std::invalid_argument("plan: --participants must be at least 2");
  if (o.conditions < 2) throw std::invalid_argument("plan: --conditions must be at least 2");
  if (o.studies < 1) throw std::invalid_argument("plan: --studies must be at least 1");
  if (!(o.difference >= 0) || !(o.sd_log10 >= 0)) throw std::invalid_argument("plan: --difference and --sd must be >= 0");
  PlanResult out;
  out.options = o;
  out.worst_c = o.c * (1 + o.difference);
  out.studies.resize(static_cast<std::size_t>(o.studies));
  static const std::pair<const char*, double> kConditions[] = {{"stair", 1.0}, {"step", 1.0}, {"stair", 0.5}, {"step", 0.5},
                                                                {"stair", 0.25}, {"step", 0.25}};
  std::atomic<int> next{0};
  auto worker = [&] {
    for (int i = next++; i < o.studies; i = next++) {
      SimulatedStudy s;
      s.participants = o.participants;
      s.trials_per_staircase = o.trials_per_staircase;
      s.artifact_px = o.artifact_px;
      s.conditions.clear();
      for (int k = 0; k < o.conditions; ++k) {
        SimulatedCondition c;
        c.pattern = kConditions[k % 6].first;
        c.contrast = kConditions[k % 6].second / (1 + k / 6);
        c.planted.c_true = k == 0 ? out.worst_c : o.c;
        c.planted.slope = o.beta;
        c.planted.lapse = o.lapse;
        s.conditions.push_back(c);
      }
      s.participant_sd_log10 = o.sd_log10;
      s.seed = sampling::derive_seed(o.seed, static_cast<std::uint64_t>(i));
      StudyFitOptions fo;
      fo.bootstrap = 0;
      fo.threads = 1;
      const StudyFit f = fit_study(as_dataset(s, simulate_study(s)), fo);
      PlanStudy& r = out.studies[static_cast<std::size_t>(i)];
      r.entry_c = f.worst.c;
      r.ci_lo = std::min(f.worst.ci95.lo, f.worst.c);
      r.ci_hi = std::max(f.worst.ci95.hi, f.worst.c);
      r.population_lo = f.worst.population.lo;
      r.population_hi = f.worst.population.hi;
      r.lr_p = f.worst.lr_p;
    }
  };
  const int threads = o.threads > 0 ? o.threads : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  std::vector<std::thread> pool;
  for (int t = 1; t < std::min(threads, o.studies); ++t) pool.emplace_back(worker);
  worker();
  for (std::thread& t : pool) t.join();
  int detected = 0, covered = 0, covered_population = 0;
  double log_ratio = 0;
  std::vector<double> half_widths;
  for (const PlanStudy& r : out.studies) {
    detected += r.lr_p < o.alpha ? 1 : 0;
    covered += r.ci_lo <= out.worst_c && out.worst_c <= r.ci_hi ? 1 : 0;
    covered_population += r.population_lo <= out.worst_c && out.worst_c <= r.population_hi ? 1 : 0;
    log_ratio += std::log10(r.entry_c / out.worst_c);
    half_widths.push_back(100.0 * (std::sqrt(r.ci_hi / r.ci_lo) - 1));
  }
  const double n = o.studies;
  out.power = detected / n;
  out.power_se = std::sqrt(out.power * (1 - out.power) / n);
  out.coverage = covered / n;
  out.coverage_population = covered_population / n;
  out.median_half_width_percent = median(half_widths);
  out.bias_percent = 100.0 * (std::pow(10.0, log_ratio / n) - 1);
  return out;
}

}  // namespace penumbra::analysis
