// The multilevel fit (issue 48) on simulated studies whose participants differ: participant i's c is
// c_true 10^(z_i sd), z_i standard normal, the same offset in every condition. The fit recovers the
// planted population mean and spread within their intervals, and the c of the 90th-percentile
// observer lies above the mean's by z_0.9 sd (log10), the planted one within its interval.
#include <gtest/gtest.h>

#include <cmath>

#include "data/simulate.h"
#include "fit/multilevel_fit.h"
#include "fit/study_fit.h"

namespace {

using namespace penumbra::analysis;

SimulatedStudy spread_study(double sd_log10, std::uint64_t seed) {
  SimulatedStudy s;
  s.participants = 10;
  s.artifact_px = {5, 10, 20};
  s.trials_per_staircase = 40;
  s.conditions = {SimulatedCondition{}, SimulatedCondition{}};
  s.conditions[0].pattern = "stair";
  s.conditions[1].pattern = "step";
  s.conditions[0].planted.c_true = 3.0;
  s.conditions[1].planted.c_true = 3.3;  // 10 % above
  for (auto& c : s.conditions) c.planted.lapse = 0.01;
  s.participant_sd_log10 = sd_log10;
  s.seed = seed;
  return s;
}

StudyFitOptions quick() {
  StudyFitOptions o;
  o.bootstrap = 0;
  o.threads = 2;
  o.observer_percentile = 0.9;
  return o;
}

TEST(Multilevel, StudentTQuantileMatchesTables) {
  EXPECT_NEAR(student_t_quantile(0.975, 5), 2.5706, 0.002);
  EXPECT_NEAR(student_t_quantile(0.975, 9), 2.2622, 0.002);
  EXPECT_NEAR(student_t_quantile(0.975, 1e9), 1.95996, 1e-4);
}

TEST(Multilevel, RecoversThePlantedPopulationMeanSpreadAndPercentile) {
  const double sd = 0.08, z90 = 1.2815515655446004;
  for (std::uint64_t seed : {11u, 12u}) {
    SCOPED_TRACE(seed);
    const SimulatedStudy s = spread_study(sd, seed);
    const StudyFit f = fit_study(as_dataset(s, simulate_study(s)), quick());
    const MultilevelFit& m = f.population;
    ASSERT_TRUE(m.fitted);
    EXPECT_TRUE(m.converged);
    ASSERT_EQ(m.conditions.size(), 2u);
    EXPECT_EQ(m.participants, 10);
    EXPECT_NEAR(m.z, z90, 1e-9);
    EXPECT_LE(m.sd_ci.lo, sd);
    EXPECT_GE(m.sd_ci.hi, sd);
    EXPECT_GT(m.sd_ci.lo, 0.0) << "a spread of 0.08 log10 is seen";
    for (std::size_t k = 0; k < 2; ++k) {
      const auto& c = m.conditions[k];
      const double planted = s.conditions[k].planted.c_true;
      EXPECT_LE(c.mean_c_ci.lo, planted) << k;
      EXPECT_GE(c.mean_c_ci.hi, planted) << k;
      // The percentile observer: above the mean by z_0.9 sd_hat, and the planted one in its interval.
      EXPECT_NEAR(std::log10(c.percentile_c / c.mean_c), z90 * m.sd_log10, 1e-9);
      const double planted_90 = planted * std::pow(10.0, z90 * sd);
      EXPECT_LE(c.percentile_c_ci.lo, planted_90) << k;
      EXPECT_GE(c.percentile_c_ci.hi, planted_90) << k;
      EXPECT_GT(c.percentile_c_ci.lo, c.mean_c_ci.lo);
      // The simultaneous interval holds the one-at-a-time one.
      EXPECT_LE(c.mean_c_ci_simultaneous.lo, c.mean_c_ci.lo);
      EXPECT_GE(c.mean_c_ci_simultaneous.hi, c.mean_c_ci.hi);
    }
    EXPECT_EQ(m.worst, 1);
    EXPECT_LE(m.worst_mean_c_ci.lo, 3.3);
    EXPECT_GE(m.worst_mean_c_ci.hi, 3.3);
  }
}

// Participants who do not differ: the spread's interval reaches down to (near) 0 and the percentile
// observer's c stays near the mean's.
TEST(Multilevel, IdenticalParticipantsShowLittleSpread) {
  const SimulatedStudy s = spread_study(0.0, 21);
  const StudyFit f = fit_study(as_dataset(s, simulate_study(s)), quick());
  const MultilevelFit& m = f.population;
  ASSERT_TRUE(m.fitted);
  EXPECT_LT(m.sd_ci.lo, 0.01);
  EXPECT_LT(m.sd_log10, 0.05);
  EXPECT_LT(m.sd_ci.hi, 0.08) << "a spread of 0.08 would show";
}

}  // namespace
