// The shared psychometric model math.

#include <gtest/gtest.h>

#include <cmath>

#include "psychometric/psychometric.h"

namespace {

namespace psy = penumbra::psychometric;
using psy::Model;

constexpr Model kModels[] = {Model::weibull, Model::log_weibull, Model::normal, Model::logistic};

TEST(Psychometric, KnownValues) {
  const psy::Params<double> pure{1.0, 2.0, 0.0, 0.0};
  EXPECT_NEAR(psy::probability(Model::weibull, 1.0, pure), 1.0 - std::exp(-1.0), 1e-15);
  EXPECT_NEAR(psy::probability(Model::weibull, 2.0, pure), 1.0 - std::exp(-4.0), 1e-15);
  EXPECT_NEAR(psy::probability(Model::log_weibull, 1.0, pure), 1.0 - std::exp(-1.0), 1e-15);
  EXPECT_NEAR(psy::probability(Model::log_weibull, 1.5, pure), 1.0 - std::exp(-10.0), 1e-15);
  EXPECT_NEAR(psy::probability(Model::normal, 1.5, pure), 0.8413447460685429, 1e-15);  // Phi(1)
  EXPECT_NEAR(psy::probability(Model::logistic, 1.0, pure), 0.5, 1e-15);
  EXPECT_NEAR(psy::probability(Model::logistic, 1.5, pure), 1.0 / (1.0 + std::exp(-1.0)), 1e-15);
  const psy::Params<double> afc{1.0, 2.0, 0.5, 0.04};
  EXPECT_NEAR(psy::probability(Model::logistic, 1.0, afc), 0.5 + 0.46 * 0.5, 1e-15);
}

TEST(Psychometric, GuessAndLapseBoundTheCurve) {
  for (Model model : kModels) {
    const psy::Params<double> params{model == Model::weibull ? 2.0 : 0.3, 3.0, 0.25, 0.03};
    const double low = model == Model::weibull ? 1e-9 : -50.0;
    EXPECT_NEAR(psy::probability(model, low, params), 0.25, 1e-12) << psy::model_name(model);
    EXPECT_NEAR(psy::probability(model, 1e3, params), 0.97, 1e-12) << psy::model_name(model);
    double previous = 0.0;
    for (double x = 0.01; x < 5.0; x += 0.01) {
      const double p = psy::probability(model, x, params);
      EXPECT_GE(p, previous) << psy::model_name(model) << " at " << x;
      previous = p;
    }
  }
}

TEST(Psychometric, ThresholdIsWhereTheCurveReachesTheChosenPercentCorrect) {
  for (Model model : kModels) {
    for (double pc : {0.6, 0.75, 0.82, 0.95}) {
      const double threshold_x = model == Model::weibull ? 0.4 : -0.55;
      const double alpha = psy::alpha_for_threshold(model, threshold_x, pc, 3.5, 0.5, 0.02);
      const psy::Params<double> params{alpha, 3.5, 0.5, 0.02};
      EXPECT_NEAR(psy::probability(model, threshold_x, params), pc, 1e-12) << psy::model_name(model) << " " << pc;
      EXPECT_NEAR(psy::threshold(model, pc, params), threshold_x, 1e-12) << psy::model_name(model) << " " << pc;
    }
    // Unreachable levels: at or below the guess rate, at or above 1 - lapse.
    const psy::Params<double> params{1.0, 3.5, 0.5, 0.02};
    EXPECT_TRUE(std::isnan(psy::threshold(model, 0.5, params)));
    EXPECT_TRUE(std::isnan(psy::threshold(model, 0.99, params)));
    EXPECT_TRUE(std::isnan(psy::alpha_for_threshold(model, 0.1, 0.3, 3.5, 0.5, 0.0)));
  }
}

TEST(Psychometric, QuestTableIsTheLogWeibullWithLapseDeltaTimesOneMinusGamma) {
  for (double x = -2.0; x <= 2.0; x += 0.013) {
    const double lapse = psy::quest_lapse(0.01, 0.5);
    EXPECT_NEAR(psy::quest_weibull(x, 3.5, 0.01, 0.5),
                psy::probability(Model::log_weibull, x, psy::Params<double>{0.0, 3.5, 0.5, lapse}), 1e-15);
  }
  EXPECT_DOUBLE_EQ(psy::quest_lapse(0.01, 0.5), 0.005);
}

TEST(Psychometric, InverseErf) {
  for (double y = -0.999999; y < 1.0; y += 0.0123) EXPECT_NEAR(std::erf(psy::inverse_erf(y)), y, 2e-16) << y;
  EXPECT_NEAR(psy::inverse_erf(0.5), 0.4769362762044699, 1e-15);
  EXPECT_EQ(psy::inverse_erf(1.0), INFINITY);
  EXPECT_TRUE(std::isnan(psy::inverse_erf(1.5)));
}

TEST(Psychometric, ModelNames) {
  for (Model model : kModels) EXPECT_EQ(psy::parse_model(psy::model_name(model)), model);
  EXPECT_EQ(psy::parse_model("gumbel"), Model::log_weibull);
  EXPECT_FALSE(psy::parse_model("probit").has_value());
}

}  // namespace
