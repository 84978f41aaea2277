// Simulated observers and staircase simulations (the simulation acceptance criterion).

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "observers/psychometric_observer.h"
#include "observers/staircase_simulation.h"

namespace {

namespace obs = penumbra::observers;
namespace psy = penumbra::psychometric;

TEST(PsychometricObserver, PlantsTheThresholdAtCTrueTimesTheArtifact) {
  for (psy::Model model : {psy::Model::log_weibull, psy::Model::weibull, psy::Model::normal, psy::Model::logistic}) {
    obs::PlantedModel planted;
    planted.c_true = 3.47;
    planted.model = model;
    planted.lapse = 0.02;
    const obs::PsychometricObserver observer({{"stair", planted}}, 1);
    // Planted on F (lapse free), as QUEST defines a threshold: F(c a) = F*, so psi there is
    // gamma + (1 - gamma - lapse) F*; 0.82 exactly when the lapse is QUEST's delta (1 - gamma).
    const double f_star = psy::criterion_f(0.82, 0.5, 0.01);
    EXPECT_NEAR(f_star, 0.6464646464646464, 1e-15);
    for (double artifact_px : {1.0, 4.0, 10.0, 20.0}) {
      const obs::Stimulus at_threshold{"stair", artifact_px, 3.47 * artifact_px};
      EXPECT_NEAR(observer.p_correct(at_threshold), 0.5 + (1 - 0.5 - 0.02) * f_star, 1e-12) << psy::model_name(model) << " a=" << artifact_px;
      const obs::Stimulus sharper{"stair", artifact_px, 2.0 * artifact_px};
      EXPECT_GT(observer.p_correct(sharper), 0.82);  // smaller filter: artifact easier to see
    }
    EXPECT_NEAR(observer.threshold_intensity("stair"), -std::log10(3.47), 1e-15);
    planted.lapse = psy::quest_lapse(0.01, 0.5);
    const obs::PsychometricObserver quest_like({{"stair", planted}}, 1);
    EXPECT_NEAR(quest_like.p_correct({"stair", 5.0, 3.47 * 5.0}), 0.82, 1e-12) << psy::model_name(model);
  }
}

TEST(PsychometricObserver, PerConditionParametersAndSeededAnswers) {
  obs::PlantedModel full, half;
  full.c_true = 3.47;
  half.c_true = 2.5;  // lower contrast: harder to see, a smaller filter suffices
  const std::map<std::string, obs::PlantedModel> conditions = {{"full", full}, {"half", half}};
  obs::PsychometricObserver a(conditions, 42), b(conditions, 42), c(conditions, 43);
  const obs::Stimulus stimulus{"full", 4.0, 4.0 * 3.47};
  int agree_same = 0, agree_other = 0, correct = 0;
  const int n = 20000;
  for (int i = 0; i < n; ++i) {
    const bool ra = a.respond(stimulus).correct;
    agree_same += ra == b.respond(stimulus).correct;
    agree_other += ra == c.respond(stimulus).correct;
    correct += ra;
  }
  EXPECT_EQ(agree_same, n);
  EXPECT_LT(agree_other, n);
  const double at_threshold = 0.5 + 0.5 * psy::criterion_f(0.82, 0.5, 0.01);  // no lapse: a little above 0.82
  EXPECT_NEAR(static_cast<double>(correct) / n, at_threshold, 0.01);
  EXPECT_NEAR(a.p_correct({"half", 4.0, 4.0 * 2.5}), at_threshold, 1e-12);
  EXPECT_THROW(a.respond({"unknown", 4.0, 10.0}), std::invalid_argument);
  EXPECT_THROW(a.p_correct({"full", 0.0, 10.0}), std::invalid_argument);
  obs::PlantedModel bad;
  bad.c_true = -1.0;
  EXPECT_THROW(obs::PsychometricObserver({{"x", bad}}, 1), std::invalid_argument);
  bad.c_true = 3.0;
  bad.p_threshold = 0.999;  // above QUEST's own ceiling 1 - delta (1 - gamma): no F reaches it
  EXPECT_THROW(obs::PsychometricObserver({{"x", bad}}, 1), std::invalid_argument);
  bad.p_threshold = 0.82;
  bad.lapse = 0.6;  // more than 1 - guess
  EXPECT_THROW(obs::PsychometricObserver({{"x", bad}}, 1), std::invalid_argument);
}

obs::SimulationConfig acceptance_config() {
  obs::SimulationConfig config;
  config.quest.t_guess = -std::log10(3.47);  // the published c as the prior
  config.quest.t_guess_sd = 0.5;
  config.planted.c_true = 5.0;  // the truth is elsewhere
  config.planted.lapse = penumbra::psychometric::quest_lapse(0.01, 0.5);
  config.trials = 40;
  config.runs = 200;
  config.seed = 1;
  return config;
}

double median_abs_error(const obs::SimulationResult& result) {
  std::vector<double> errors;
  for (const auto& run : result.runs) errors.push_back(std::abs(run.final_mean - result.planted_threshold));
  std::nth_element(errors.begin(), errors.begin() + errors.size() / 2, errors.end());
  return errors[errors.size() / 2];
}

// Acceptance: 40-trial QUEST runs have median final error below 0.05 log10 units over 200 runs.
TEST(StaircaseSimulation, FortyTrialQuestRunsMedianErrorBelowFiveHundredths) {
  int reported = 0;
  const auto result = obs::simulate_runs(acceptance_config(), [&reported](int done, int total) {
    reported = done;
    EXPECT_EQ(total, 200);
  });
  EXPECT_EQ(reported, 200);
  ASSERT_EQ(result.runs.size(), 200u);
  EXPECT_NEAR(result.planted_threshold, -std::log10(5.0), 1e-15);
  EXPECT_LT(median_abs_error(result), 0.05);
}

TEST(StaircaseSimulation, FortyTrialQuestPlusRunsMedianErrorBelowFiveHundredths) {
  obs::SimulationConfig config = acceptance_config();
  config.method = obs::Method::quest_plus;
  config.runs = 100;
  EXPECT_LT(median_abs_error(obs::simulate_runs(config)), 0.05);
}

TEST(StaircaseSimulation, RunsAreReproducibleAndIndependentOfEachOther) {
  obs::SimulationConfig config = acceptance_config();
  config.runs = 5;
  const auto five = obs::simulate_runs(config);
  config.runs = 3;
  const auto three = obs::simulate_runs(config);
  for (std::size_t k = 0; k < 3; ++k) EXPECT_EQ(five.runs[k].final_mean, three.runs[k].final_mean);
  EXPECT_NE(five.runs[0].final_mean, five.runs[1].final_mean);
  config.trials = 0;
  EXPECT_THROW(obs::simulate_runs(config), std::invalid_argument);
}

// Any Observer drives a run: an observer that always sees the artifact pushes the estimate to
// ever weaker stimuli (lower intensity).
TEST(StaircaseSimulation, AcceptsAnyObserver) {
  struct AlwaysSees : obs::Observer {
    obs::Response respond(const obs::Stimulus& stimulus) override {
      EXPECT_GT(stimulus.filter_radius_px, 0.0);
      return {true};
    }
  } observer;
  obs::SimulationConfig config = acceptance_config();
  const obs::RunResult run = obs::run_quest(config, observer);
  EXPECT_LT(run.final_mean, config.quest.t_guess - 0.5);
}

}  // namespace
