// psychometric.h must work with Ceres Jets: the fitter differentiates through these functions.

#include <ceres/jet.h>
#include <gtest/gtest.h>

#include "psychometric/psychometric.h"

namespace {

namespace psy = penumbra::psychometric;
using Jet = ceres::Jet<double, 2>;

TEST(PsychometricJet, DerivativesMatchFiniteDifferences) {
  for (psy::Model model : {psy::Model::weibull, psy::Model::log_weibull, psy::Model::normal, psy::Model::logistic}) {
    const double alpha = model == psy::Model::weibull ? 0.5 : -0.3;
    const double beta = 2.5;
    const double x = model == psy::Model::weibull ? 0.6 : -0.2;
    const psy::Params<Jet> params{Jet(alpha, 0), Jet(beta, 1), Jet(0.5), Jet(0.02)};
    const Jet p = psy::probability(model, Jet(x), params);
    const double h = 1e-6;
    const auto at = [&](double a, double b) {
      return psy::probability(model, x, psy::Params<double>{a, b, 0.5, 0.02});
    };
    EXPECT_NEAR(p.a, at(alpha, beta), 1e-15);
    EXPECT_NEAR(p.v[0], (at(alpha + h, beta) - at(alpha - h, beta)) / (2 * h), 1e-7) << psy::model_name(model);
    EXPECT_NEAR(p.v[1], (at(alpha, beta + h) - at(alpha, beta - h)) / (2 * h), 1e-7) << psy::model_name(model);

    const Jet threshold = psy::threshold(model, Jet(0.82), params);
    const auto threshold_at = [&](double a) {
      return psy::threshold(model, 0.82, psy::Params<double>{a, beta, 0.5, 0.02});
    };
    EXPECT_NEAR(threshold.v[0], (threshold_at(alpha + h) - threshold_at(alpha - h)) / (2 * h), 1e-6)
        << psy::model_name(model);
  }
}

}  // namespace
