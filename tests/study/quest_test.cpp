// QUEST: the published PsychoPy reference staircase and Psychtoolbox's edge behaviour.

#include <gtest/gtest.h>

#include <cmath>
#include <numeric>
#include <stdexcept>
#include <string>
#include <vector>

#include "quest/quest.h"
#include "sampling/random.h"

namespace {

using penumbra::quest::Quest;
using penumbra::quest::QuestParams;

QuestParams psychopy_params() {
  QuestParams params;
  params.t_guess = 50;
  params.t_guess_sd = 50;
  params.p_threshold = 0.82;
  params.beta = 3.5;
  params.delta = 0.01;
  params.gamma = 0.5;
  params.grain = 0.01;
  params.range = 100;
  return params;
}

QuestParams default_params() {
  QuestParams params;
  params.t_guess = -0.5;
  params.t_guess_sd = 0.5;
  return params;
}

// PsychoPy's QuestHandler test (the first acceptance reference): first trial at 50, then
// quantile placement.
TEST(Quest, PsychoPyReferenceStaircase) {
  const std::vector<int> responses = {1, 1, 0, 0, 1, 1, 0, 0, 1, 1};
  const std::vector<double> expected = {50,
                                        45.139710407074872,
                                        37.291086503930742,
                                        58.297413127139947,
                                        80.182967131096547,
                                        75.295251409003527,
                                        71.57627192423783,
                                        79.881680484036906,
                                        90.712313302815517,
                                        88.265808957695796};
  Quest quest(psychopy_params());
  EXPECT_EQ(quest.dim(), 10000);
  for (std::size_t k = 0; k < responses.size(); ++k) {
    const double intensity = k == 0 ? 50.0 : quest.quantile();
    EXPECT_NEAR(intensity, expected[k], 1e-9) << "trial " << k + 1;
    quest.update(intensity, responses[k]);
  }
  EXPECT_NEAR(quest.mean(), 86.0772169427, 1e-9);
  EXPECT_NEAR(quest.mode(), 80.11, 1e-9);
  EXPECT_NEAR(quest.quantile(), 86.3849031085, 1e-9);
  EXPECT_TRUE(quest.warnings().empty());
}

TEST(Quest, TableSizeFollowsRangeAndGrain) {
  QuestParams params = default_params();
  EXPECT_EQ(Quest(params).dim(), 500);
  params.range = 5.0;
  EXPECT_EQ(Quest(params).dim(), 500);
  params.range = 6.03;
  params.grain = 0.05;
  EXPECT_EQ(Quest(params).dim(), 122);  // 120.6 rounded up to an even count
  params.range = 0.001;
  EXPECT_EQ(Quest(params).dim(), 2);
  const Quest quest(params);
  EXPECT_EQ(quest.x().size(), 3u);
  EXPECT_EQ(quest.x2().size(), 5u);
}

TEST(Quest, InvalidParametersGetOneLineErrors) {
  const auto expect_error = [](QuestParams params, const std::string& fragment) {
    try {
      Quest quest(params);
      ADD_FAILURE() << "no error for " << fragment;
    } catch (const std::invalid_argument& error) {
      const std::string message = error.what();
      EXPECT_NE(message.find(fragment), std::string::npos) << message;
      EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    }
  };
  QuestParams params = default_params();
  params.range = 0.0;
  expect_error(params, "range");
  params.range = -1.0;
  expect_error(params, "range");
  params.range = NAN;
  expect_error(params, "range");
  params.range = 1e9;
  expect_error(params, "larger than");
  params = default_params();
  params.t_guess = NAN;
  expect_error(params, "tGuess");
  params.t_guess = -INFINITY;
  expect_error(params, "tGuess");
  params = default_params();
  params.t_guess_sd = 0.0;
  expect_error(params, "tGuessSd");
  params.t_guess_sd = NAN;
  expect_error(params, "tGuessSd");
  params = default_params();
  params.p_threshold = 0.999;  // above the table's top, delta*gamma + 1 - delta = 0.995
  expect_error(params, "omits");
  params.p_threshold = 0.45;  // below the guess rate
  expect_error(params, "omits");
  params.p_threshold = 1.5;
  expect_error(params, "pThreshold");
  params = default_params();
  params.grain = 0.0;
  expect_error(params, "grain");
  params = default_params();
  params.beta = -1.0;
  expect_error(params, "beta");
  params = default_params();
  params.delta = 2.0;
  expect_error(params, "delta");
}

TEST(Quest, GammaAbovePThresholdIsReducedToHalfWithAWarning) {
  QuestParams params = default_params();
  params.gamma = 0.9;
  const Quest quest(params);
  EXPECT_EQ(quest.params().gamma, 0.5);
  ASSERT_EQ(quest.warnings().size(), 1u);
  EXPECT_EQ(quest.warnings()[0], "reducing gamma from 0.90 to 0.5");
  EXPECT_NEAR(quest.p(-100.0), 0.5, 1e-12);  // the table now starts at the reduced guess rate
}

TEST(Quest, ThresholdShiftPutsPThresholdAtZero) {
  const Quest quest(default_params());
  EXPECT_NEAR(quest.p(0.0), 0.82, 1e-5);  // linear interpolation on the grain-0.01 table
  EXPECT_NEAR(quest.quantile_order(), 0.5, 0.2);
  EXPECT_EQ(quest.p(-1e9), quest.p2().front());
  EXPECT_EQ(quest.p(1e9), quest.p2().back());
}

TEST(Quest, FlatPriorAndFirstMaximumMode) {
  QuestParams params = default_params();
  params.t_guess_sd = INFINITY;
  const Quest quest(params);
  for (double value : quest.pdf()) EXPECT_EQ(value, quest.pdf().front());
  EXPECT_DOUBLE_EQ(quest.mode(), params.t_guess - 250 * params.grain);  // first of the tied maxima
  EXPECT_NEAR(quest.mean(), params.t_guess, 1e-12);
}

TEST(Quest, QuantileEdges) {
  Quest quest(default_params());
  EXPECT_THROW(quest.quantile(-0.01), std::invalid_argument);
  EXPECT_THROW(quest.quantile(1.01), std::invalid_argument);
  EXPECT_THROW(quest.quantile(NAN), std::invalid_argument);
  EXPECT_DOUBLE_EQ(quest.quantile(0.0), -0.5 - 2.5);  // below the first cumulative value: x(1)
  // Psychtoolbox interpolates the cumulative sum as if each bin's mass sat at its right edge, so
  // the median of a symmetric prior is half a grain below its centre.
  EXPECT_NEAR(quest.quantile(0.5), -0.505, 1e-9);
  EXPECT_LT(quest.quantile(0.25), quest.quantile(0.75));
  EXPECT_LE(quest.quantile(1.0), -0.5 + 2.5);
}

TEST(Quest, OutOfRangeIntensityIsUsedAtTheEdgeWithAWarning) {
  QuestParams params = default_params();
  params.range = 1.0;  // dim 100: intensities tGuess +- 0.5 are inside
  Quest at_edge(params), beyond(params), infinite(params), inside(params);
  at_edge.update(-0.5 + 0.5, 1);
  inside.update(-0.5 + 0.5049, 1);  // rounds to the last step
  beyond.update(-0.5 + 7.0, 1);
  infinite.update(INFINITY, 1);
  EXPECT_TRUE(at_edge.warnings().empty());
  EXPECT_TRUE(inside.warnings().empty());
  ASSERT_EQ(beyond.warnings().size(), 1u);
  EXPECT_NE(beyond.warnings()[0].find("intensity 6.500 out of range -1.00 to 0.00"), std::string::npos)
      << beyond.warnings()[0];
  EXPECT_EQ(beyond.pdf(), at_edge.pdf());
  EXPECT_EQ(infinite.pdf(), at_edge.pdf());
  EXPECT_EQ(inside.pdf(), at_edge.pdf());
  Quest low(params), low_edge(params);
  low.update(-1e300, 0);
  low_edge.update(-1.0, 0);
  EXPECT_EQ(low.pdf(), low_edge.pdf());
  EXPECT_EQ(low.warnings().size(), 1u);
  EXPECT_EQ(low.intensities().front(), -1e300);  // the history keeps what was really shown
  EXPECT_THROW(low.update(NAN, 1), std::invalid_argument);
  EXPECT_THROW(low.update(0.0, -1), std::invalid_argument);
}

// MATLAB's round() sends halves away from zero; banker's rounding would give different columns.
TEST(Quest, IntensityQuantisationRoundsHalvesAwayFromZero) {
  QuestParams params = default_params();
  params.t_guess = 0.0;
  params.grain = 0.25;
  params.range = 4.0;
  const auto pdf_after = [&params](double intensity) {
    Quest quest(params);
    quest.update(intensity, 1);
    return quest.pdf();
  };
  EXPECT_EQ(pdf_after(0.125), pdf_after(0.25));
  EXPECT_EQ(pdf_after(-0.125), pdf_after(-0.25));
  EXPECT_EQ(pdf_after(0.625), pdf_after(0.75));  // 2.5 steps -> 3, not 2
  EXPECT_NE(pdf_after(0.125), pdf_after(0.0));
}

TEST(Quest, TenThousandTrialsWithoutUnderflow) {
  const QuestParams params = default_params();
  Quest quest(params);
  penumbra::sampling::Random random(7);
  const double t_actual = -0.62;
  for (int trial = 0; trial < 10000; ++trial) {
    const double intensity = quest.quantile();
    quest.update(intensity, quest.simulate(intensity, t_actual, random.uniform()) ? 1 : 0);
  }
  double total = 0.0;
  for (double value : quest.pdf()) {
    ASSERT_TRUE(std::isfinite(value));
    total += value;
  }
  EXPECT_NEAR(total, 1.0, 1e-12);
  EXPECT_GT(quest.sd(), 0.0);
  EXPECT_LT(quest.sd(), 0.01);
  EXPECT_NEAR(quest.mean(), t_actual, 0.02);
  EXPECT_EQ(quest.trial_count(), 10000u);
  EXPECT_NO_THROW(penumbra::quest::beta_analysis(quest));  // Psychtoolbox underflows here
}

TEST(Quest, ReplayRestoresTheExactState) {
  Quest live(default_params());
  penumbra::sampling::Random random(3);
  for (int trial = 0; trial < 200; ++trial) {
    const double intensity = trial % 3 == 0 ? live.mean() : live.quantile();
    live.update(intensity, random.uniform() < 0.7 ? 1 : 0);
  }
  const Quest replayed = penumbra::quest::replay(default_params(), live.intensities(), live.responses());
  EXPECT_EQ(replayed.pdf(), live.pdf());  // bit for bit
  EXPECT_EQ(replayed.quantile(), live.quantile());
  Quest recomputed = live;
  recomputed.recompute();  // QuestRecompute normalises only every 100 trials
  EXPECT_NEAR(recomputed.mean(), live.mean(), 1e-12);
  EXPECT_NEAR(recomputed.quantile(), live.quantile(), 1e-12);
  EXPECT_THROW(penumbra::quest::replay(default_params(), {0.1}, {1, 0}), std::invalid_argument);
}

TEST(Quest, PdfAtClampsToTheGrid) {
  const Quest quest(default_params());
  EXPECT_EQ(quest.pdf_at(-1e9), quest.pdf().front());
  EXPECT_EQ(quest.pdf_at(1e9), quest.pdf().back());
  EXPECT_EQ(quest.pdf_at(-0.5), quest.pdf()[250]);
  EXPECT_EQ(quest.pdf_at(-0.5 + 0.0049), quest.pdf()[250]);
  EXPECT_EQ(quest.pdf_at(-0.5 + 0.0051), quest.pdf()[251]);
}

TEST(Quest, SimulateComparesTheTableWithTheDraw) {
  const Quest quest(default_params());
  EXPECT_TRUE(quest.simulate(0.0, 0.0, 0.8199));   // at threshold p = 0.82
  EXPECT_FALSE(quest.simulate(0.0, 0.0, 0.8201));
  EXPECT_TRUE(quest.simulate(-100.0, 0.0, 0.0));    // clamped to the table: p = gamma-ish > 0
  EXPECT_FALSE(quest.simulate(100.0, 0.0, 0.999));  // clamped: p = 0.995
}

TEST(Quest, BetaAnalysisSeparatesShallowFromSteepObservers) {
  const auto estimate = [](double planted_beta) {
    QuestParams params = default_params();
    Quest quest(params);
    QuestParams truth = params;
    truth.beta = planted_beta;
    const Quest observer(truth);
    penumbra::sampling::Random random(11);
    for (int trial = 0; trial < 400; ++trial) {
      // Spread trials around threshold so the slope is visible.
      const double intensity = quest.quantile() + 0.15 * std::sin(trial * 0.7);
      quest.update(intensity, observer.simulate(intensity, -0.6, random.uniform()) ? 1 : 0);
    }
    return penumbra::quest::beta_analysis(quest);
  };
  const auto shallow = estimate(1.5);
  const auto steep = estimate(8.0);
  EXPECT_LT(shallow.beta, 3.0);
  EXPECT_GT(steep.beta, 4.5);
  EXPECT_NEAR(shallow.t, -0.6, 0.1);
  EXPECT_NEAR(steep.t, -0.6, 0.05);
}

}  // namespace
