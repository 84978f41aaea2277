// Display calibration (study/display): the gamma fit recovers a synthetic monitor's gamma, the
// table model gives the readings back, encode inverts the measured transfer to within half a
// level's luminance step, the checkerboard arithmetic, and the strict CSV and JSON readers.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>

#include "display/display_calibration.h"
#include "display/display_fit.h"
#include "display/typed_readings.h"

namespace {

namespace fs = std::filesystem;
using namespace penumbra;

// The synthetic monitor of every display test: black 0.5 cd/m², white 120.5, gamma 2.4.
double monitor_cd_m2(double level) { return 0.5 + 120.0 * std::pow(level / 255.0, 2.4); }

std::vector<display::Reading> synthetic_readings(int count, double relative_noise = 0, unsigned seed = 1) {
  std::mt19937 random(seed);
  std::normal_distribution<double> noise(0.0, relative_noise);
  std::vector<display::Reading> r;
  for (int level : display::calibration_levels(count)) r.push_back({level, monitor_cd_m2(level) * (1 + noise(random))});
  return r;
}

fs::path scratch(const std::string& name) { return fs::temp_directory_path() / ("penumbra-dispcal-" + name + "-" + std::to_string(::getpid())); }

TEST(DisplayCalibration, LevelsSpanTheRangeEvenly) {
  EXPECT_EQ(display::calibration_levels(9), (std::vector<int>{0, 32, 64, 96, 128, 159, 191, 223, 255}));
  EXPECT_EQ(display::calibration_levels(17)[1], 16);
  EXPECT_EQ(display::calibration_levels(256)[200], 200);
  EXPECT_THROW(display::calibration_levels(4), std::invalid_argument);
  EXPECT_THROW(display::calibration_levels(257), std::invalid_argument);
}

TEST(DisplayCalibration, GammaFitRecoversTheSyntheticMonitor) {
  const auto exact = display::fit_readings(synthetic_readings(9), display::Model::gamma);
  EXPECT_NEAR(exact.gamma, 2.4, 1e-6);
  EXPECT_NEAR(*exact.black_cd_m2, 0.5, 1e-6);
  EXPECT_NEAR(*exact.white_cd_m2, 120.5, 1e-6);
  EXPECT_LT(*exact.residual_rms_cd_m2, 1e-6);
  // 0.5 % photometer noise per reading, 17 levels, ten noise draws: within 0.02 every time.
  for (unsigned seed = 1; seed <= 10; ++seed) {
    const auto noisy = display::fit_readings(synthetic_readings(17, 0.005, seed), display::Model::gamma);
    EXPECT_NEAR(noisy.gamma, 2.4, 0.02) << "seed " << seed;
    EXPECT_GT(*noisy.residual_rms_cd_m2, 0.0);
  }
}

TEST(DisplayCalibration, TableModelGivesTheReadingsBack) {
  const auto readings = synthetic_readings(9, 0.01, 3);
  const auto c = display::fit_readings(readings, display::Model::table);
  ASSERT_EQ(c.model, display::Model::table);
  const double black = readings.front().luminance_cd_m2, white = readings.back().luminance_cd_m2;
  for (const auto& r : readings)
    EXPECT_NEAR(c.relative_luminance(r.level), (r.luminance_cd_m2 - black) / (white - black), 1e-12) << "level " << r.level;
  // Monotone between the readings, and close to the monitor there (17 readings of a smooth curve).
  const auto fine = display::fit_readings(synthetic_readings(17), display::Model::table);
  double previous = -1, worst = 0;
  for (int v = 0; v <= 255; ++v) {
    const double rel = fine.relative_luminance(v);
    EXPECT_GE(rel, previous) << "level " << v;
    previous = rel;
    worst = std::max(worst, std::abs(rel - (monitor_cd_m2(v) - 0.5) / 120.0));
  }
  EXPECT_LT(worst, 0.002);
}

// encode() picks the level whose luminance is nearest: the error is at most half the luminance
// step between the neighbouring levels, for both models.
TEST(DisplayCalibration, EncodeInvertsTheMeasuredTransferToHalfAStep) {
  for (const auto model : {display::Model::gamma, display::Model::table}) {
    const auto c = display::fit_readings(synthetic_readings(17), model);
    for (int i = 0; i <= 1000; ++i) {
      const double linear = i / 1000.0;
      const int v = c.encode(linear);
      const double step = std::max(c.relative_luminance(std::min(v + 1, 255)) - c.relative_luminance(v),
                                   c.relative_luminance(v) - c.relative_luminance(std::max(v - 1, 0)));
      EXPECT_LE(std::abs(c.relative_luminance(v) - linear), step / 2 + 1e-12) << display::to_string(model) << " linear " << linear;
    }
    EXPECT_EQ(c.encode(0.0), 0);
    EXPECT_EQ(c.encode(1.0), 255);
  }
}

TEST(DisplayCalibration, CheckerboardMatchArithmetic) {
  // (m / 255)^gamma = 0.5: an sRGB-like monitor (2.2) matches at 186, a gamma 2.4 one at 191.
  EXPECT_NEAR(display::checkerboard_gamma(186), std::log(0.5) / std::log(186.0 / 255.0), 1e-12);
  EXPECT_NEAR(display::checkerboard_gamma(186), 2.197, 0.001);
  EXPECT_NEAR(display::checkerboard_gamma(191), 2.3985, 0.0001);
  EXPECT_NEAR(display::checkerboard_gamma(128), 1.0, 0.01);
  for (int m : {186, 191}) EXPECT_NEAR(std::pow(m / 255.0, display::checkerboard_gamma(m)), 0.5, 1e-12);
  const auto c = display::checkerboard_calibration(191);
  EXPECT_EQ(c.method, "checkerboard-match");
  EXPECT_EQ(c.encode(0.5), 191);  // the matched grey is half way, by construction
  EXPECT_THROW(display::checkerboard_gamma(0), std::invalid_argument);
  EXPECT_THROW(display::checkerboard_gamma(255), std::invalid_argument);
  EXPECT_THROW(display::checkerboard_gamma(20), std::invalid_argument);  // gamma 0.27: not a monitor
}

TEST(DisplayCalibration, JsonRoundTripAndRefusals) {
  auto c = display::fit_readings(synthetic_readings(9), display::Model::gamma);
  c.created_utc = "2026-12-02T09:00:00.000Z";
  const nlohmann::json j = display::to_json(c);
  const auto back = display::parse_calibration(j, "x.json");
  EXPECT_EQ(display::to_json(back), j);
  EXPECT_EQ(display::fingerprint(display::to_json(back)), display::fingerprint(j));
  const auto board = display::checkerboard_calibration(186);
  EXPECT_EQ(display::to_json(display::parse_calibration(display::to_json(board), "b.json")), display::to_json(board));

  struct Case {
    std::function<void(nlohmann::json&)> edit;
    std::string message;
  };
  const std::vector<Case> cases{
      {[](nlohmann::json& x) { x["schema_version"] = 2; }, "x.json: schema_version: expected 1 (a display-calibration.json of this version), got 2"},
      {[](nlohmann::json& x) { x["gama"] = 2; }, "x.json: gama: unknown key (allowed: schema_version, created_utc, model, method, gamma, black_cd_m2, white_cd_m2, points, "
                                                      "residual_rms_cd_m2, matched_level, source, monitor)"},
      {[](nlohmann::json& x) { x["model"] = "spline"; }, "x.json: model: model 'spline': expected gamma or table"},
      {[](nlohmann::json& x) { x["gamma"] = 9; }, "x.json: gamma: expected a number in [0.5, 5], got 9"},
      {[](nlohmann::json& x) { x["points"][3]["luminance_cd_m2"] = 1.0; },
       "x.json: points: level 96: 1 cd/m2, not above level 64's 4.84827 (luminance must rise with the level: remeasure)"},
      {[](nlohmann::json& x) { x["points"][0]["level"] = 300; }, "x.json: points[0].level: expected an integer in [0, 255], got 300"},
      {[](nlohmann::json& x) { x["white_cd_m2"] = nullptr; }, "x.json: white_cd_m2: expected black_cd_m2 and white_cd_m2 with white above black"},
      // Issue 27: a file took what the CSV refuses, and a gamma its readings contradict.
      {[](nlohmann::json& x) { x["points"][8]["luminance_cd_m2"] = 1e308; },
       "x.json: points[8].luminance_cd_m2: expected a number in [0, 100000], got 1e+308"},
      {[](nlohmann::json& x) { x["gamma"] = 1.8; },
       "x.json: gamma: 1.8 (black 0.5, white 120.5) contradicts the points: the model misses them by 8.16618 cd/m2 RMS, more than 2.4 "
       "(twice residual_rms_cd_m2, at least 2 % of the range)"},
  };
  for (const Case& k : cases) {
    nlohmann::json bad = j;
    k.edit(bad);
    try {
      display::parse_calibration(bad, "x.json");
      ADD_FAILURE() << "accepted: " << k.message;
    } catch (const std::runtime_error& e) {
      EXPECT_EQ(std::string(e.what()), k.message);
    }
  }
  nlohmann::json edited = display::to_json(board);
  edited["gamma"] = 2.4;  // not what level 186 means
  EXPECT_THROW(display::parse_calibration(edited, "b.json"), std::runtime_error);
}

TEST(DisplayCalibration, CsvReadingsAreReadStrictly) {
  const fs::path p = scratch("readings.csv");
  auto write = [&](const std::string& text) { std::ofstream(p, std::ios::binary) << text; };
  write("level,luminance_cd_m2\r\n255, 120.5\n0,0.5\n64,8.44\n128,26.6\n192,61.0\n");
  const auto r = display::read_readings_csv(p);
  ASSERT_EQ(r.size(), 5u);
  EXPECT_EQ(r.front().level, 0);
  EXPECT_EQ(r.back().level, 255);
  EXPECT_DOUBLE_EQ(r.back().luminance_cd_m2, 120.5);
  const std::string f = p.string();
  const std::vector<std::pair<std::string, std::string>> bad{
      {"", f + ": empty; expected the header 'level,luminance_cd_m2' and one row per level"},
      {"level,luminance\n0,1\n", f + ":1: expected the header 'level,luminance_cd_m2', found 'level,luminance'"},
      {"level,luminance_cd_m2\n0,0.5\n64,n/a\n", f + ":3: column 'luminance_cd_m2': 'n/a' is not a number"},
      {"level,luminance_cd_m2\n0,0.5\n256,3\n", f + ":3: column 'level': '256' is not an 8-bit level (an integer 0..255)"},
      {"level,luminance_cd_m2\n0,0.5\n12.5,3\n", f + ":3: column 'level': '12.5' is not an 8-bit level (an integer 0..255)"},
      {"level,luminance_cd_m2\n0,0.5\n64,8,1\n", f + ":3: expected 2 columns (level,luminance_cd_m2), found 3"},
      {"level,luminance_cd_m2\n0,0.5\n\n", f + ":3: empty line; expected 'level,luminance_cd_m2' values"},
      {"level,luminance_cd_m2\n0,0.5\n64,-1\n", f + ":3: column 'luminance_cd_m2': '-1' is not a luminance in [0, 100000] cd/m2"},
      {"level,luminance_cd_m2\n0,0.5\n64,1e308\n", f + ":3: column 'luminance_cd_m2': '1e308' is not a luminance in [0, 100000] cd/m2"},
      {"level,luminance_cd_m2\n0,0.5\n64,inf\n", f + ":3: column 'luminance_cd_m2': 'inf' is not a number"},
      {"level,luminance_cd_m2\n0,0.5\n64,0x10\n", f + ":3: column 'luminance_cd_m2': '0x10' is not a number"},
      {"level,luminance_cd_m2\n0,0.5\n64,8\n64,9\n", f + ":4: column 'level': 64 was read already on line 3"},
      {"level,luminance_cd_m2\n0,0.5\n64,8\n128,7\n192,61\n255,120\n",
       f + ":4: column 'luminance_cd_m2': 7 cd/m2 at level 128 is not above 8 at level 64 (line 3); luminance must rise with the level"},
      {"level,luminance_cd_m2\n0,0.5\n128,26\n255,120\n", f + ": 3 reading(s): expected at least 5 levels, including 0 and 255"},
      {"level,luminance_cd_m2\n16,0.5\n64,8\n128,26\n192,61\n255,120\n",
       f + ": expected readings of level 0 (black) and 255 (white); the lowest is 16, the highest 255"},
  };
  for (const auto& [text, message] : bad) {
    write(text);
    try {
      display::read_readings_csv(p);
      ADD_FAILURE() << "accepted: " << text;
    } catch (const std::runtime_error& e) {
      EXPECT_EQ(std::string(e.what()), message);
    }
  }
  fs::remove(p);
}

// Issue 26: readings typed into the window go through the CSV's number rule. "8,1" once became 81
// (the text box dropped the comma); a refused reading stayed in the box and the next one was
// appended to it ("30" then "95,1" gave 30951, accepted).
TEST(DisplayCalibration, TypedReadingsAreStrictNumbersAndTheFieldEmptiesAfterEachEntry) {
  EXPECT_DOUBLE_EQ(display::parse_luminance(" 8.1 "), 8.1);
  EXPECT_DOUBLE_EQ(display::parse_luminance("1e2"), 100.0);
  auto refusal = [](const std::string& text) {
    try {
      display::parse_luminance(text);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_EQ(refusal("8,1"), "'8,1': a decimal comma; type a point (8.1)");
  EXPECT_EQ(refusal("95,1"), "'95,1': a decimal comma; type a point (95.1)");
  EXPECT_EQ(refusal("1,234.5"), "'1,234.5' is not a number");
  EXPECT_EQ(refusal(""), "no reading typed: a luminance in cd/m2, e.g. 85.2");
  EXPECT_EQ(refusal("nan"), "'nan' is not a number");
  EXPECT_EQ(refusal("-0.5"), "'-0.5' is not a luminance in [0, 100000] cd/m2");

  display::TypedReadings t(display::calibration_levels(5), display::Model::gamma);  // 0, 64, 128, 191, 255
  t.field() = "0.5";
  EXPECT_EQ(t.enter(), display::TypedReadings::Outcome::accepted);
  EXPECT_EQ(t.field(), "");
  t.field() = "8,1";
  EXPECT_EQ(t.enter(), display::TypedReadings::Outcome::refused);
  EXPECT_EQ(t.message(), "'8,1': a decimal comma; type a point (8.1)");
  EXPECT_EQ(t.field(), "") << "a refused reading leaves the box";
  EXPECT_EQ(t.current(), 1u);
  t.field() = "0.4";  // not above black
  EXPECT_EQ(t.enter(), display::TypedReadings::Outcome::refused);
  EXPECT_EQ(t.message(),
            "0.4 is not above level 0's 0.5: luminance must rise with the level (measure again, or select level 0 with Up/Down and read it again)");
  EXPECT_EQ(t.field(), "");
  for (const char* v : {"8.44", "26.6", "61"}) {
    t.field() = v;
    EXPECT_EQ(t.enter(), display::TypedReadings::Outcome::accepted) << v;
  }
  // A white no monitor has (a slip: 30951 for 120.5) is asked about; Enter on it again keeps it.
  t.field() = "30951";
  EXPECT_EQ(t.enter(), display::TypedReadings::Outcome::confirm);
  EXPECT_NE(t.message().find("white (level 255) at 30951 cd/m2 is outside the range of monitors (20..2000 cd/m2)"), std::string::npos)
      << t.message();
  EXPECT_EQ(t.field(), "30951");
  EXPECT_FALSE(t.reviewing());
  t.field() = "120.5";  // or another value, taken as any other
  EXPECT_EQ(t.enter(), display::TypedReadings::Outcome::accepted);
  ASSERT_TRUE(t.reviewing());
  ASSERT_TRUE(t.fitted().has_value()) << t.fit_problem();
  EXPECT_NEAR(t.fitted()->gamma, 2.4, 0.1);  // readings of the synthetic monitor, rounded
  EXPECT_EQ(t.fit_warning(), "");
  EXPECT_EQ(t.level(), 255) << "the review selects the level read last";
  t.remeasure();  // Backspace on the review: white again
  EXPECT_FALSE(t.reviewing());
  EXPECT_EQ(t.level(), 255);
  t.field() = "30951";
  EXPECT_EQ(t.enter(), display::TypedReadings::Outcome::confirm);
  EXPECT_EQ(t.enter(), display::TypedReadings::Outcome::accepted);  // confirmed
  EXPECT_TRUE(t.reviewing());
}

// The sum of squared residuals of the gamma model with black 0 at `gamma`, white at its least
// squares value for that gamma (linear in white): a brute-force check of the constrained fit.
double cost_with_black_zero(const std::vector<display::Reading>& r, double gamma) {
  double ls = 0, ss = 0;
  for (const auto& p : r) {
    const double shape = std::pow(p.level / 255.0, gamma);
    ls += p.luminance_cd_m2 * shape;
    ss += shape * shape;
  }
  const double white = ls / ss;
  double cost = 0;
  for (const auto& p : r) cost += std::pow(white * std::pow(p.level / 255.0, gamma) - p.luminance_cd_m2, 2);
  return cost;
}

// Issue 44: five plausible readings typed in the window (0.31, 9.2, 41.5, 98.7, 181 cd/m²) were
// refused after the last level, "black level -0.0823 cd/m², below 0". Black >= 0 is part of the
// model now: the fit is the best one with black at 0, and it says so.
TEST(DisplayCalibration, TheReportedFiveReadingsFitWithANonNegativeBlack) {
  const std::vector<display::Reading> r{{0, 0.31}, {64, 9.2}, {128, 41.5}, {191, 98.7}, {255, 181}};
  const auto c = display::fit_readings(r, display::Model::gamma);
  EXPECT_EQ(*c.black_cd_m2, 0.0) << "the free optimum lies below 0: the bound holds black at 0";
  EXPECT_GT(c.gamma, 1.8);
  EXPECT_LT(c.gamma, 2.6);
  EXPECT_NEAR(*c.white_cd_m2, 181, 3);
  // The best fit with black at 0: no gamma on a fine grid does better.
  double best = INFINITY;
  for (double g = 0.5; g <= 5; g += 1e-4) best = std::min(best, cost_with_black_zero(r, g));
  const double cost = std::pow(*c.residual_rms_cd_m2, 2) * static_cast<double>(r.size());
  EXPECT_LE(cost, best + 1e-9) << "gamma " << c.gamma;
  EXPECT_NEAR(cost, best, 1e-6);
  EXPECT_EQ(display::check_fitted_levels(*c.black_cd_m2, *c.white_cd_m2, "the gamma model's"), "");
  EXPECT_NE(display::gamma_fit_note(c).find("black held at 0 cd/m2"), std::string::npos) << display::gamma_fit_note(c);
  // What is written is read back: the file's own check of the model against its points passes.
  const fs::path p = scratch("five.json");
  display::write_calibration(p, c);
  const auto back = display::load_calibration(p);
  EXPECT_EQ(*back.black_cd_m2, 0.0);
  EXPECT_DOUBLE_EQ(back.gamma, c.gamma);
  fs::remove(p);
  // A monitor whose black the readings show above 0 keeps it: the bound is not active.
  const auto synthetic = display::fit_readings(synthetic_readings(9), display::Model::gamma);
  EXPECT_NEAR(*synthetic.black_cd_m2, 0.5, 1e-6);
  EXPECT_EQ(display::gamma_fit_note(synthetic), "");
}

// Readings the gamma curve does not follow near black (crushed blacks: nearly black up to level
// 64, then a steep climb) once gave black -2.8 cd/m² and a refusal; the constrained fit holds
// black at 0 and says so. Readings no gamma curve follows (an S-shaped picture mode) are fitted
// and named as missed, where the table follows them. Impossible readings stay refused.
TEST(DisplayCalibration, ReadingsTheGammaCurveMissesFitWithBlackAtZeroAndPointToTheTable) {
  const std::vector<display::Reading> r{{0, 0.3}, {64, 2.0}, {128, 30.0}, {191, 95.0}, {255, 180.0}};
  const auto gamma = display::fit_readings(r, display::Model::gamma);
  EXPECT_EQ(*gamma.black_cd_m2, 0.0);
  EXPECT_EQ(display::gamma_fit_note(gamma), "black held at 0 cd/m2 (the gamma curve through the other readings passes below 0 at level 0, read as 0.3)");
  const auto s_curve = display::fit_readings({{0, 0.3}, {64, 3.0}, {128, 60.0}, {191, 165.0}, {255, 180.0}}, display::Model::gamma);
  const std::string note = display::gamma_fit_note(s_curve);
  EXPECT_NE(note.find("the gamma model misses the readings by"), std::string::npos) << note;
  EXPECT_NE(note.find("the table model follows them"), std::string::npos) << note;
  // The table model is the readings: its black is the reading of level 0.
  const auto table = display::fit_readings(r, display::Model::table);
  EXPECT_EQ(*table.black_cd_m2, 0.3);
  EXPECT_EQ(*table.white_cd_m2, 180.0);
  EXPECT_EQ(display::gamma_fit_note(table), "");
  EXPECT_THROW(display::check_fitted_levels(-1.045, 1812, "the gamma model's"), std::invalid_argument);
  EXPECT_EQ(display::check_fitted_levels(0.3, 150, "the gamma model's"), "");
  EXPECT_NE(display::check_fitted_levels(0.3, 30951, "the gamma model's").find("outside the range of monitors"), std::string::npos);
  // Still refused, with one line: luminance that falls, a negative or a non-finite one.
  auto refusal = [](std::vector<display::Reading> bad) {
    try {
      display::fit_readings(std::move(bad), display::Model::gamma);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_EQ(refusal({{0, 0.3}, {64, 9}, {128, 8}, {191, 95}, {255, 180}}),
            "level 128: 8 cd/m2, not above level 64's 9 (luminance must rise with the level: remeasure)");
  EXPECT_EQ(refusal({{0, -0.1}, {64, 9}, {128, 41}, {191, 95}, {255, 180}}), "level 0: -0.1 is not a luminance in [0, 100000] cd/m2");
  EXPECT_EQ(refusal({{0, 0.3}, {64, NAN}, {128, 41}, {191, 95}, {255, 180}}), "level 64: nan is not a luminance in [0, 100000] cd/m2");
}

// Issue 44: Backspace on the review read only level 255 again; any level can be selected and read
// again now, before the review and from it, and the table model is there for typed readings.
TEST(DisplayCalibration, AnyTypedLevelCanBeReadAgainAndTheTableChosen) {
  display::TypedReadings t(display::calibration_levels(5), display::Model::gamma);  // 0, 64, 128, 191, 255
  for (const char* v : {"0.31", "9.2", "41.5"}) {
    t.field() = v;
    ASSERT_EQ(t.enter(), display::TypedReadings::Outcome::accepted) << v;
  }
  EXPECT_EQ(t.level(), 191);
  t.select(-2);  // Up twice, before the review: level 64, read already
  EXPECT_EQ(t.level(), 64);
  ASSERT_TRUE(t.reading(1).has_value());
  EXPECT_EQ(*t.reading(1), 9.2);
  t.field() = "42";  // not below level 128's 41.5
  EXPECT_EQ(t.enter(), display::TypedReadings::Outcome::refused);
  EXPECT_EQ(t.message(),
            "42 is not below level 128's 41.5: luminance must rise with the level (measure again, or select level 128 with Up/Down and read it again)");
  t.field() = "9.4";
  EXPECT_EQ(t.enter(), display::TypedReadings::Outcome::accepted);
  EXPECT_EQ(t.level(), 191) << "the next level not read yet";
  for (const char* v : {"98.7", "181"}) {
    t.field() = v;
    ASSERT_EQ(t.enter(), display::TypedReadings::Outcome::accepted) << v;
  }
  ASSERT_TRUE(t.reviewing());
  ASSERT_TRUE(t.fitted().has_value()) << t.fit_problem();  // was: refused, black -0.08 cd/m2
  EXPECT_EQ(*t.fitted()->black_cd_m2, 0.0);
  EXPECT_NE(t.fit_warning().find("black held at 0"), std::string::npos) << t.fit_warning();
  // From the review: level 64 again (Up three times from white), and back to the review.
  t.select(-3);
  EXPECT_EQ(t.level(), 64);
  t.remeasure();
  EXPECT_FALSE(t.reviewing());
  EXPECT_EQ(t.level(), 64);
  t.field() = "9.3";
  EXPECT_EQ(t.enter(), display::TypedReadings::Outcome::accepted);
  ASSERT_TRUE(t.reviewing());
  EXPECT_EQ(t.readings().size(), 5u);
  EXPECT_EQ(t.readings()[1].luminance_cd_m2, 9.3);
  EXPECT_EQ(t.readings()[4].luminance_cd_m2, 181.0);
  // Tab on the review: the table model, its black the reading of level 0.
  t.set_model(display::Model::table);
  ASSERT_TRUE(t.fitted().has_value()) << t.fit_problem();
  EXPECT_EQ(t.fitted()->model, display::Model::table);
  EXPECT_EQ(*t.fitted()->black_cd_m2, 0.31);
  EXPECT_EQ(t.fit_warning(), "");
  t.set_model(display::Model::gamma);
  EXPECT_EQ(t.fitted()->model, display::Model::gamma);
}

// The readings file the window keeps: written as the CSV reader reads it, the numbers as typed,
// read back half way (to go on from) or whole (to finish with --luminances).
TEST(DisplayCalibration, KeptReadingsRoundTripAndAWindowGoesOnFromThem) {
  const std::vector<display::Reading> some{{64, 9.2}, {0, 0.31}, {128, 41.5}};
  EXPECT_EQ(display::readings_csv(some), "level,luminance_cd_m2\n0,0.31\n64,9.2\n128,41.5\n");
  const fs::path p = scratch("kept.csv");
  std::ofstream(p, std::ios::binary) << display::readings_csv(some);
  const auto back = display::read_readings_csv(p, display::ReadingsSet::partial);
  ASSERT_EQ(back.size(), 3u);
  EXPECT_EQ(back[1].level, 64);
  EXPECT_EQ(back[1].luminance_cd_m2, 9.2);
  try {
    display::read_readings_csv(p);
    ADD_FAILURE() << "three readings taken for a calibration";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), p.string() + ": 3 reading(s): expected at least 5 levels, including 0 and 255");
  }
  std::ofstream(p, std::ios::binary) << "level,luminance_cd_m2\n0,0.31\n64,0.2\n";
  EXPECT_THROW(display::read_readings_csv(p, display::ReadingsSet::partial), std::runtime_error) << "still rising";
  fs::remove(p);
  display::TypedReadings t(display::calibration_levels(5), display::Model::gamma, back);
  EXPECT_FALSE(t.reviewing());
  EXPECT_EQ(t.read_count(), 3u);
  EXPECT_EQ(t.level(), 191) << "the first level not read";
  EXPECT_THROW(display::TypedReadings(display::calibration_levels(5), display::Model::gamma, {{100, 20}}), std::invalid_argument);
  const std::vector<display::Reading> all{{0, 0.31}, {64, 9.2}, {128, 41.5}, {191, 98.7}, {255, 181}};
  display::TypedReadings done(display::calibration_levels(5), display::Model::table, all);
  EXPECT_TRUE(done.reviewing());
  ASSERT_TRUE(done.fitted().has_value());
  EXPECT_EQ(done.fitted()->model, display::Model::table);
}

}  // namespace
