// The image observer's curve arithmetic and its decision noise fitted to a threshold
// (observers/observer_curve.h), on deviation curves written down in closed form.

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <stdexcept>
#include <vector>

#include "observers/observer_curve.h"

namespace {

namespace obs = penumbra::observers;

// A curve of one artifact size: jagged deviation d(r/a) on a log grid, the straight image's 0.
std::vector<obs::CurvePoint> curve(const std::function<double(double)>& deviation, double ratio_min, double step, double ratio_max) {
  std::vector<obs::CurvePoint> points;
  for (double ratio = ratio_min; ratio <= ratio_max; ratio *= step) points.push_back({ratio, {deviation(ratio)}, {0.0}});
  return points;
}

// Phi^-1(0.82): 2afc P = Phi(d / (sqrt2 w)) reaches 0.82 where d = sqrt2 z w.
constexpr double kZ82 = 0.915365087842814;

TEST(ObserverCurve, TheFittedWeberPutsAMonotoneCurvesThresholdOnTheTarget) {
  // d = 0.02 / (r/a): its threshold at weber w is r/a = 0.02 / (sqrt2 z w) exactly; the grid's
  // log interpolation of P is exact only in the limit, so a fine grid must land within 0.1 %.
  const obs::ConditionCurves sizes = {curve([](double x) { return 0.02 / x; }, 0.5, 1.01, 10)};
  for (const double target : {1.5, 2.5, 3.47, 6.0}) {
    const obs::WeberFit fit = obs::fit_weber({sizes}, target, 0.82);
    EXPECT_NEAR(fit.c, target, 1e-6 * target) << target;
    EXPECT_NEAR(fit.weber, 0.02 / (std::sqrt(2.0) * kZ82 * target), 1e-3 * fit.weber) << target;
    // Read back by the curve's own reading at that weber.
    EXPECT_NEAR(obs::replicate_c(sizes, fit.weber, 0.82), target, 1e-6 * target);
  }
  // A larger decision noise needs a larger deviation: a smaller filter.
  EXPECT_GT(obs::replicate_c(sizes, 0.002, 0.82), obs::replicate_c(sizes, 0.003, 0.82));
}

TEST(ObserverCurve, ReplicatesAverageInLogAndACurveStillAboveTheCriterionIsBeyondTheGrid) {
  const obs::ConditionCurves low = {curve([](double x) { return 0.02 / x; }, 0.5, 1.01, 10)};
  const obs::ConditionCurves high = {curve([](double x) { return 0.04 / x; }, 0.5, 1.01, 10)};
  const double w = 0.006;  // thresholds 2.57 and 5.15, both on the grid
  EXPECT_NEAR(obs::mean_c({low, high}, w, 0.82), std::sqrt(obs::replicate_c(low, w, 0.82) * obs::replicate_c(high, w, 0.82)), 1e-12);
  EXPECT_NEAR(obs::replicate_c(high, w, 0.82) / obs::replicate_c(low, w, 0.82), 2.0, 0.01);
  // At a tiny weber d never falls below the criterion on the grid: c is beyond it, not the last ratio.
  EXPECT_TRUE(std::isinf(obs::replicate_c(low, 1e-5, 0.82)));
  EXPECT_TRUE(std::isinf(obs::mean_c({low, high}, 1e-5, 0.82)));
  // Every artifact size counts: one beyond the grid makes the condition's c beyond it.
  const obs::ConditionCurves two_sizes = {low[0], curve([](double) { return 1.0; }, 0.5, 1.01, 10)};
  EXPECT_TRUE(std::isinf(obs::replicate_c(two_sizes, w, 0.82)));
  // Outside what the grid can show the fit refuses instead of returning its bracket's end.
  EXPECT_THROW(obs::fit_weber({low}, 50.0, 0.82), std::invalid_argument);
  EXPECT_THROW(obs::fit_weber({low}, 0.1, 0.82), std::invalid_argument);
}

TEST(ObserverCurve, ATargetInsideAJumpOfANonMonotoneCurveGivesTheJumpAndSaysWhatItReaches) {
  // A curve with a dip (the stair's nulls): d falls like 0.02 / x but drops to a tenth of it on
  // r/a in [2, 3]. As weber grows the last crossing jumps from above 3 to below 2: no weber
  // gives c = 2.5, and the fit returns the nearer side of the jump with the c it reaches.
  const obs::ConditionCurves dip = {curve([](double x) { return (x >= 2 && x <= 3 ? 0.1 : 1.0) * 0.02 / x; }, 0.5, 1.01, 10)};
  const obs::WeberFit fit = obs::fit_weber({dip}, 2.5, 0.82);
  EXPECT_GT(std::abs(fit.c - 2.5), 0.4) << fit.c;
  EXPECT_NEAR(fit.c, obs::replicate_c(dip, fit.weber, 0.82), 1e-12);
  // Away from the jump it is exact again.
  EXPECT_NEAR(obs::fit_weber({dip}, 4.0, 0.82).c, 4.0, 1e-6);
}

}  // namespace
