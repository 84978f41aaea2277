// QUEST+: Watson (2017) example 1 as reproduced by the questplus package's tests, and slope
// estimation.

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <vector>

#include "psychometric/psychometric.h"
#include "quest/quest_plus.h"
#include "sampling/random.h"

namespace {

namespace psy = penumbra::psychometric;
using penumbra::quest::QuestPlus;
using penumbra::quest::QuestPlusParameter;

std::vector<double> steps(double from, double to, double step) {
  std::vector<double> values;
  for (double v = from; v <= to + 1e-9; v += step) values.push_back(std::round(v / step) * step);
  return values;
}

// Weibull in dB: 1 - lambda - (1 - gamma - lambda) exp(-10^(beta (x - t) / 20)), which is the
// log-Weibull model on x / 20 (dB to log10 amplitude).
double weibull_db(double x_db, const QuestPlusParameter& theta) {
  return psy::probability(psy::Model::log_weibull, x_db / 20.0,
                          psy::Params<double>{theta.threshold / 20.0, theta.slope, 0.5, theta.lapse});
}

TEST(QuestPlus, WatsonExampleOne) {
  const std::vector<double> db = steps(-40, 0, 1);
  QuestPlus staircase(db, penumbra::quest::quest_plus_grid(db, {3.5}, {0.02}), weibull_db);
  const std::string responses = "CCCCIICCCCCCCCICCICCICCCCCCCCCCC";
  const std::vector<double> expected = {-18, -22, -25, -28, -30, -22, -13, -15, -16, -18, -19,
                                        -20, -21, -22, -23, -19, -20, -20, -18, -18, -19, -17,
                                        -17, -18, -18, -18, -19, -19, -19, -19, -19, -19};
  ASSERT_EQ(responses.size(), expected.size());
  for (std::size_t k = 0; k < responses.size(); ++k) {
    const double stimulus = staircase.next();
    EXPECT_EQ(stimulus, expected[k]) << "trial " << k + 1;
    staircase.update(stimulus, responses[k] == 'C' ? 1 : 0);
  }
  EXPECT_EQ(staircase.posterior_mode().threshold, -20.0);
  EXPECT_EQ(staircase.trial_count(), 32u);
}

TEST(QuestPlus, EstimatesTheSlope) {
  const std::vector<double> thresholds = steps(-1.0, 0.0, 0.025);
  const std::vector<double> slopes = {1.0, 1.5, 2.0, 3.0, 4.5, 7.0, 10.0};
  const auto model = [](double x, const QuestPlusParameter& theta) {
    return psy::probability(psy::Model::log_weibull, x, psy::Params<double>{theta.threshold, theta.slope, 0.5, theta.lapse});
  };
  const auto estimate = [&](double planted_slope) {
    QuestPlus staircase(steps(-1.5, 0.5, 0.025), penumbra::quest::quest_plus_grid(thresholds, slopes, {0.01}), model);
    penumbra::sampling::Random random(5);
    const QuestPlusParameter truth{-0.5, planted_slope, 0.01};
    for (int trial = 0; trial < 300; ++trial) {
      const double x = staircase.next();
      staircase.update(x, random.uniform() < model(x, truth) ? 1 : 0);
    }
    return staircase.posterior_mean();
  };
  const QuestPlusParameter shallow = estimate(1.5);
  const QuestPlusParameter steep = estimate(7.0);
  EXPECT_NEAR(shallow.threshold, -0.5, 0.08);
  EXPECT_NEAR(steep.threshold, -0.5, 0.05);
  EXPECT_LT(shallow.slope, 3.0);
  EXPECT_GT(steep.slope, 4.0);
}

TEST(QuestPlus, RejectsBadSetups) {
  const auto flat = [](double, const QuestPlusParameter&) { return 0.5; };
  const auto grid = penumbra::quest::quest_plus_grid({0.0, 1.0}, {2.0}, {0.0});
  EXPECT_THROW(QuestPlus({}, grid, flat), std::invalid_argument);
  EXPECT_THROW(QuestPlus({0.0}, {}, flat), std::invalid_argument);
  EXPECT_THROW(QuestPlus({0.0}, grid, flat, {1.0}), std::invalid_argument);
  EXPECT_THROW(QuestPlus({0.0}, grid, [](double, const QuestPlusParameter&) { return 1.5; }), std::invalid_argument);
  QuestPlus ok({0.0}, grid, flat);
  EXPECT_THROW(ok.update(NAN, 1), std::invalid_argument);
  EXPECT_THROW(ok.update(0.0, 3), std::invalid_argument);
  // An impossible response sequence (p = 1 everywhere, answered incorrectly) leaves no mass.
  QuestPlus certain({0.0}, grid, [](double, const QuestPlusParameter&) { return 1.0; });
  EXPECT_THROW(certain.update(0.0, 0), std::invalid_argument);
}

}  // namespace
