// QUEST against the real Psychtoolbox: fixtures/quest_psychtoolbox.json was written by
// scripts/quest_reference/generate_quest_fixtures.m running Psychtoolbox 3.0.18's Quest*.m in
// Octave. Every number must agree to 1e-9 (relative for the small pdf values).

#include <gtest/gtest.h>

#include <cmath>
#include <algorithm>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>
#include <string>

#include "quest/quest.h"

namespace {

using nlohmann::json;
using penumbra::quest::Quest;
using penumbra::quest::QuestParams;

const json& fixtures() {
  static const json data = [] {
    std::ifstream in(std::string(PENUMBRA_QUEST_FIXTURES) + "/quest_psychtoolbox.json");
    if (!in) throw std::runtime_error("cannot open quest_psychtoolbox.json");
    return json::parse(in);
  }();
  return data;
}

double value(const json& v) {
  if (v.is_null()) return NAN;
  if (v.is_string()) return v.get<std::string>() == "inf" ? INFINITY : -INFINITY;
  return v.get<double>();
}

QuestParams params_of(const json& c) {
  const json& p = c.at("params");
  QuestParams params;
  params.t_guess = value(p.at("tGuess"));
  params.t_guess_sd = value(p.at("tGuessSd"));
  params.p_threshold = value(p.at("pThreshold"));
  params.beta = value(p.at("beta"));
  params.delta = value(p.at("delta"));
  params.gamma = value(p.at("gamma"));
  params.grain = value(p.at("grain"));
  if (!p.at("range").is_null()) params.range = value(p.at("range"));
  return params;
}

void expect_close(double expected, double actual, const std::string& what, double tolerance = 1e-9) {
  if (std::isnan(expected)) {
    EXPECT_TRUE(std::isnan(actual)) << what;
    return;
  }
  if (std::isinf(expected)) {
    EXPECT_EQ(actual, expected) << what;
    return;
  }
  EXPECT_NEAR(actual, expected, tolerance * std::max(1.0, std::abs(expected))) << what;
}

class PsychtoolboxFixture : public testing::TestWithParam<std::string> {};

const json& case_named(const std::string& name) {
  for (const json& c : fixtures().at("cases"))
    if (c.at("name") == name) return c;
  throw std::runtime_error("no fixture case " + name);
}

TEST_P(PsychtoolboxFixture, MatchesQuestStarM) {
  const json& c = case_named(GetParam());
  Quest quest(params_of(c));
  EXPECT_EQ(quest.dim(), c.at("dim").get<int>());
  expect_close(value(c.at("gamma_used")), quest.params().gamma, "gamma used");
  expect_close(value(c.at("x_threshold")), quest.x_threshold(), "xThreshold", 1e-12);
  expect_close(value(c.at("quantile_order")), quest.quantile_order(), "quantileOrder", 1e-12);
  expect_close(value(c.at("prior_quantile")), quest.quantile(), "prior quantile");
  expect_close(value(c.at("prior_mode")), quest.mode(), "prior mode");

  const std::string responses = c.at("responses");
  const std::string placement = c.at("placement");
  const bool given = c.contains("intensities");
  std::size_t checkpoint = 0;
  for (std::size_t k = 0; k < responses.size(); ++k) {
    double intensity;
    if (given) {
      intensity = value(c.at("intensities").at(k));
    } else if (k == 0 && !c.at("first").is_null()) {
      intensity = value(c.at("first"));
    } else {
      intensity = placement == "quantile" ? quest.quantile() : placement == "mean" ? quest.mean() : quest.mode();
    }
    if (c.contains("intensities_used"))
      expect_close(value(c.at("intensities_used").at(k)), intensity, "intensity of trial " + std::to_string(k + 1));
    quest.update(intensity, responses[k] == '1' ? 1 : 0);
    const json& checkpoints = c.at("checkpoints");
    if (checkpoint < checkpoints.size() && checkpoints[checkpoint].at("trial").get<std::size_t>() == k + 1) {
      const json& point = checkpoints[checkpoint++];
      const std::string at = " after trial " + std::to_string(k + 1);
      expect_close(value(point.at("intensity")), intensity, "intensity" + at);
      expect_close(value(point.at("mean")), quest.mean(), "mean" + at);
      expect_close(value(point.at("sd")), quest.sd(), "sd" + at);
      expect_close(value(point.at("mode")), quest.mode(), "mode" + at);
      expect_close(value(point.at("quantile")), quest.quantile(), "quantile" + at);
    }
  }
  EXPECT_EQ(checkpoint, c.at("checkpoints").size());

  expect_close(value(c.at("mean")), quest.mean(), "mean");
  expect_close(value(c.at("sd")), quest.sd(), "sd");
  expect_close(value(c.at("mode")), quest.mode(), "mode");
  expect_close(value(c.at("quantile")), quest.quantile(), "quantile");
  for (std::size_t i = 0; i < c.at("quantile_orders").size(); ++i) {
    const double order = value(c.at("quantile_orders")[i]);
    expect_close(value(c.at("quantiles")[i]), quest.quantile(order), "quantile at order " + std::to_string(order));
  }
  for (std::size_t i = 0; i < c.at("p_x").size(); ++i) {
    const double x = value(c.at("p_x")[i]);
    expect_close(value(c.at("p")[i]), quest.p(x), "QuestP at " + std::to_string(x), 1e-12);
  }
  for (std::size_t i = 0; i < c.at("pdf_t").size(); ++i) {
    const double t = value(c.at("pdf_t")[i]);
    const double expected = value(c.at("pdf")[i]);
    EXPECT_NEAR(quest.pdf_at(t), expected, 1e-9 * expected + 1e-300) << "QuestPdf at " << t;
  }

  Quest recomputed = quest;
  recomputed.recompute();
  expect_close(value(c.at("recompute_mean")), recomputed.mean(), "QuestRecompute mean");
  expect_close(value(c.at("recompute_sd")), recomputed.sd(), "QuestRecompute sd");

  if (c.contains("beta_analysis")) {
    const json& expected = c.at("beta_analysis");
    const auto analysis = penumbra::quest::beta_analysis(quest);
    expect_close(value(expected.at("t")), analysis.t, "beta analysis t");
    expect_close(value(expected.at("sd")), analysis.sd, "beta analysis sd");
    expect_close(value(expected.at("beta")), analysis.beta, "beta analysis beta");
    expect_close(value(expected.at("beta_sd")), analysis.beta_sd, "beta analysis beta_sd");
  }
  if (c.contains("beta_analysis_error")) {
    // Psychtoolbox underflows to zero probability for every slope and fails; ours rescales the
    // joint pdf and still answers (docs/quest.md). The answer must agree with the long run's QUEST.
    const auto analysis = penumbra::quest::beta_analysis(quest);
    EXPECT_NEAR(analysis.t, quest.mean(), 0.05);
    EXPECT_TRUE(std::isfinite(analysis.beta) && analysis.beta > 1.0 && analysis.beta < 16.0) << analysis.beta;
  }
}

INSTANTIATE_TEST_SUITE_P(Psychtoolbox, PsychtoolboxFixture,
                         testing::Values("psychopy_reference", "default_dim_quantile_40", "mean_placement_40",
                                         "mode_placement_first_40", "out_of_range_intensities", "half_grain_rounding",
                                         "gamma_above_pthreshold", "flat_prior", "four_afc_odd_range", "yes_no",
                                         "long_300_beta_analysis", "long_10000"));

TEST(PsychtoolboxFixture, EveryCaseIsTested) { EXPECT_EQ(fixtures().at("cases").size(), 12u); }

TEST(PsychtoolboxFixture, RejectsWhatPsychtoolboxRejects) {
  const auto create = [](double t_guess, double p_threshold, double gamma, std::optional<double> range) {
    QuestParams params;
    params.t_guess = t_guess;
    params.t_guess_sd = 1.0;
    params.p_threshold = p_threshold;
    params.gamma = gamma;
    params.range = range;
    return Quest(params);
  };
  for (const json& error : fixtures().at("errors")) EXPECT_FALSE(error.at("message").get<std::string>().empty());
  EXPECT_THROW(create(0, 0.999, 0.5, std::nullopt), std::invalid_argument);  // pthreshold_outside_table
  EXPECT_THROW(create(0, 0.82, 0.5, 0.0), std::invalid_argument);            // range_zero
  EXPECT_THROW(create(0, 0.82, 0.5, -2.0), std::invalid_argument);           // range_negative
  EXPECT_THROW(create(NAN, 0.82, 0.5, std::nullopt), std::invalid_argument);  // tguess_nan
  EXPECT_THROW(create(INFINITY, 0.82, 0.5, std::nullopt), std::invalid_argument);  // tguess_inf
  EXPECT_THROW(create(0, 0.4, 0.6, std::nullopt), std::invalid_argument);     // gamma_above_pthreshold_still_omits
  Quest quest = create(0, 0.82, 0.5, std::nullopt);
  EXPECT_THROW(quest.quantile(1.5), std::invalid_argument);  // quantile_order_above_one
  EXPECT_THROW(quest.update(0.0, 2), std::invalid_argument);  // response_two
}

}  // namespace
