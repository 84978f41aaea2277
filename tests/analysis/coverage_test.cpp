// Coverage (label slow): over 120 simulated studies (10 participants x 3 sizes x 40 trials) the
// 95 % profile-likelihood interval of c contains the planted c 90-98 % of the time.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numeric>
#include <thread>
#include <vector>

#include "data/simulate.h"
#include "fit/plan.h"
#include "fit/study_fit.h"

namespace {

using namespace penumbra::analysis;

TEST(Coverage, ProfileIntervalCoversThePlantedC) {
  constexpr int kStudies = 120;
  const double planted[3] = {2.0, 3.47, 5.0};
  int covered = 0, covered_wald = 0;
  for (int i = 0; i < kStudies; ++i) {
    SimulatedStudy s;
    s.conditions[0].planted.c_true = planted[i % 3];
    s.conditions[0].planted.lapse = 0.01;
    s.seed = 90000 + static_cast<std::uint64_t>(i);
    StudyFitOptions o;
    o.bootstrap = 0;
    const StudyFit f = fit_study(as_dataset(s, simulate_study(s)), o);
    const ConditionFit& c = f.conditions[0];
    const double truth = planted[i % 3];
    covered += c.c_profile.lo <= truth && truth <= c.c_profile.hi ? 1 : 0;
    covered_wald += c.c_wald.lo <= truth && truth <= c.c_wald.hi ? 1 : 0;
  }
  const double rate = double(covered) / kStudies;
  std::printf("coverage of the 95 %% profile interval: %d/%d = %.3f (Wald %d/%d)\n", covered, kStudies, rate,
              covered_wald, kStudies);
  EXPECT_GE(rate, 0.90);
  EXPECT_LE(rate, 0.98);
}

// Issue 48 (label slow, about 15 min of CPU on 2 threads): the entry's c with no significance gate.
// Three conditions, one of them 0, 5 or 10 % above the other two (planted c 3.0), and participants
// identical or differing by sd 0.08 log10 of c (the same offset in every condition); 6-10
// participants x 3 sizes x 40 trials. The entry's ci95 must hold the worst condition's planted c
// (the population's median observer's) in at least 90 % of the studies in every case. Run with the
// bootstrap off: the ci95 then holds the profile and the population intervals only, and the
// bootstrap's can only widen it, so the coverage measured is a lower bound of penumbra-fit's.
// PENUMBRA_COVERAGE_STUDIES sets the studies per case (default 30).
TEST(Coverage, TheEntrysIntervalCoversTheWorstConditionWhateverTheDifferences) {
  const int studies = std::getenv("PENUMBRA_COVERAGE_STUDIES") ? std::atoi(std::getenv("PENUMBRA_COVERAGE_STUDIES")) : 30;
  struct Case {
    double above, sd_log10;
  };
  const Case cases[] = {{0.0, 0.0}, {0.05, 0.0}, {0.10, 0.0}, {0.0, 0.08}, {0.05, 0.08}};
  std::printf("%-10s %-8s %8s %10s %10s %12s %10s %10s\n", "above", "sd", "studies", "ci95", "profile", "population", "bias %",
              "pooled");
  for (const Case& k : cases) {
    std::vector<int> covered(static_cast<std::size_t>(studies)), covered_profile(covered), covered_population(covered), pooled(covered);
    std::vector<double> log_ratio(static_cast<std::size_t>(studies));
    std::atomic<int> next{0};
    auto worker = [&] {
      for (int i = next++; i < studies; i = next++) {
        SimulatedStudy s;
        s.participants = 6 + i % 5;
        s.conditions.clear();
        for (const auto& [pattern, contrast] : {std::pair{"stair", 1.0}, {"step", 1.0}, {"stair", 0.5}}) {
          SimulatedCondition c;
          c.pattern = pattern;
          c.contrast = contrast;
          c.planted.c_true = 3.0;
          c.planted.lapse = 0.02;
          s.conditions.push_back(c);
        }
        s.conditions[1].planted.c_true = 3.0 * (1 + k.above);
        s.participant_sd_log10 = k.sd_log10;
        s.seed = 480000 + static_cast<std::uint64_t>(i) + static_cast<std::uint64_t>(1000 * (k.above * 100 + k.sd_log10 * 1000));
        const double worst = 3.0 * (1 + k.above);
        StudyFitOptions o;
        o.bootstrap = 0;
        o.threads = 1;
        const StudyFit f = fit_study(as_dataset(s, simulate_study(s)), o);
        const WorstCase& w = f.worst;
        const auto holds = [&](const Interval& v) { return v.lo <= worst && worst <= v.hi ? 1 : 0; };
        const auto idx = static_cast<std::size_t>(i);
        covered[idx] = holds(w.ci95);
        covered_profile[idx] = holds(w.profile);
        covered_population[idx] = holds(w.population);
        pooled[idx] = w.method == "pooled" ? 1 : 0;
        log_ratio[idx] = std::log10(w.c / worst);
      }
    };
    std::thread other(worker);
    worker();
    other.join();
    const auto sum = [](const std::vector<int>& v) { return std::accumulate(v.begin(), v.end(), 0); };
    const double bias = std::pow(10.0, std::accumulate(log_ratio.begin(), log_ratio.end(), 0.0) / studies) - 1;
    std::printf("%-10.0f %-8.2f %8d %5d %4.0f%% %5d %3.0f%% %6d %4.0f%% %+10.2f %10d\n", 100 * k.above, k.sd_log10, studies, sum(covered),
                100.0 * sum(covered) / studies, sum(covered_profile), 100.0 * sum(covered_profile) / studies, sum(covered_population),
                100.0 * sum(covered_population) / studies, 100 * bias, sum(pooled));
    std::fflush(stdout);
    EXPECT_GE(sum(covered), static_cast<int>(std::ceil(0.9 * studies))) << "above " << k.above << ", sd " << k.sd_log10;
  }
}

// Issue 48 (label slow, about 2 min of CPU): penumbra-fit plan's power is the rate at which the
// conditions' LR test finds a planted difference: near its level when there is none, near 1 for a
// clear one (30 % with 10 identical participants); the coverage it prints holds in both.
TEST(Coverage, ThePlannersPowerSeparatesNoDifferenceFromAClearOne) {
  PlanOptions o;
  o.participants = 10;
  o.conditions = 3;
  o.sd_log10 = 0.0;
  o.studies = 10;
  o.threads = 2;
  o.difference = 0.0;
  const PlanResult none = plan_study(o);
  o.difference = 0.30;
  const PlanResult clear = plan_study(o);
  for (const PlanResult* r : {&none, &clear}) {
    int detected = 0;
    for (const PlanStudy& s : r->studies) detected += s.lr_p < o.alpha ? 1 : 0;
    EXPECT_DOUBLE_EQ(r->power, detected / 10.0);
    EXPECT_GE(r->coverage, 0.9);
    std::printf("difference %.0f %%: power %.2f +- %.2f, coverage %.2f, half-width %.1f %%, bias %+.2f %%\n", 100 * r->options.difference,
                r->power, r->power_se, r->coverage, r->median_half_width_percent, r->bias_percent);
  }
  EXPECT_LE(none.power, 0.3);
  EXPECT_GE(clear.power, 0.9);
}

}  // namespace
