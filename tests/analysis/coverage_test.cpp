// Coverage (label slow): over 120 simulated studies (10 participants x 3 sizes x 40 trials) the
// 95 % profile-likelihood interval of c contains the planted c 90-98 % of the time.
#include <gtest/gtest.h>

#include <cstdio>

#include "data/simulate.h"
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

}  // namespace
