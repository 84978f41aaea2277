// The filter-to-resolution rule, its clamping and the hysteresis controller (label `unit`).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>

#include "adaptive/cascades.h"
#include "adaptive/resolution_rule.h"

namespace penumbra::adaptive {
namespace {

TEST(ResolutionRule, PublishedConstantGivesTheThesisResolutions) {
  // r = c·a: a radius of 3.47 texels of a 1024 map hides that map's staircase exactly.
  EXPECT_DOUBLE_EQ(required_texels_uv(3.47, 3.47 / 1024.0), 1024.0);
  // World space: a 0.1-unit radius over a 20-unit view plane needs c · 200 texels.
  EXPECT_NEAR(required_texels_ws(3.47, 20.0, 0.1), 694.0, 1e-9);
  // Doubling the radius halves the resolution.
  EXPECT_DOUBLE_EQ(required_texels_ws(3.47, 20.0, 0.2), required_texels_ws(3.47, 20.0, 0.1) / 2);
}

TEST(ResolutionRule, ExtremesAreClampedAndFinite) {
  const ResolutionLimits lim{16, 8192, 32};
  const double inf = std::numeric_limits<double>::infinity(), nan = std::nan("");
  EXPECT_EQ(clamp_resolution(required_texels_uv(3.47, 0.0), lim), 8192);     // r → 0
  EXPECT_EQ(clamp_resolution(required_texels_uv(3.47, 1e-300), lim), 8192);
  EXPECT_EQ(clamp_resolution(required_texels_uv(3.47, -1.0), lim), 8192);    // invalid radius: be safe, not small
  EXPECT_EQ(clamp_resolution(required_texels_uv(3.47, nan), lim), 8192);
  EXPECT_EQ(clamp_resolution(required_texels_uv(3.47, 1e300), lim), 16);    // r huge
  EXPECT_EQ(clamp_resolution(required_texels_ws(3.47, 0.0, 0.1), lim), 16);   // L → 0
  EXPECT_EQ(clamp_resolution(required_texels_ws(3.47, 1e-30, 0.1), lim), 16);
  EXPECT_EQ(clamp_resolution(required_texels_ws(3.47, inf, 0.1), lim), 8192);
  EXPECT_EQ(clamp_resolution(inf, lim), 8192);
  EXPECT_EQ(clamp_resolution(-inf, lim), 16);
  EXPECT_EQ(clamp_resolution(nan, lim), 8192);
  // Degenerate limits still give a positive size.
  EXPECT_EQ(clamp_resolution(100, {0, 0, 0}), 1);
  EXPECT_EQ(clamp_resolution(100, {64, 32, 7}), 64);  // max below min: min wins
}

TEST(ResolutionRule, QuantizationRoundsUpSoTheRuleStillHolds) {
  const ResolutionLimits lim{16, 8192, 32};
  for (double req = 16.5; req < 8192; req *= 1.013) {
    const int res = clamp_resolution(req, lim);
    EXPECT_GE(res, req);
    EXPECT_LT(res, req + 32);
    EXPECT_EQ(res % 32, 0);
  }
}

TEST(ResolutionController, GrowsAtOnceShrinksAfterTheDelay) {
  ResolutionController ctl({{16, 8192, 32}, 10, 0.8});
  EXPECT_EQ(ctl.update(1000), 1024);
  EXPECT_EQ(ctl.update(2000), 2016);  // grow at once
  for (int i = 0; i < 9; ++i) EXPECT_EQ(ctl.update(500), 2016) << "frame " << i;
  EXPECT_EQ(ctl.update(500), 512);    // the tenth frame below 80 % shrinks
  EXPECT_EQ(ctl.update(450), 512);    // within 80 %: stays
  EXPECT_EQ(ctl.changes(), 2);
}

TEST(ResolutionController, ShrinksToTheLargestRequirementOfTheWait) {
  ResolutionController ctl({{16, 8192, 32}, 5, 0.8});
  ctl.update(2048);
  for (double r : {300.0, 900.0, 400.0, 350.0}) ctl.update(r);
  EXPECT_EQ(ctl.update(320), 928);
}

TEST(ResolutionController, SlowNoisyZoomNeverFlipsBackAndForth) {
  // A camera zooming in then out over 2000 frames: the requirement follows a smooth path with
  // ±3 % frame-to-frame noise (depth jitter, animation). The resolution must change monotonically
  // within each half of the path: no grow-shrink-grow oscillation.
  ResolutionController ctl({{16, 8192, 32}, 30, 0.8});
  unsigned seed = 12345;
  auto noise = [&] {
    seed = seed * 1664525u + 1013904223u;
    return 1.0 + 0.03 * (static_cast<double>(seed >> 8) / (1 << 24) * 2 - 1);
  };
  int previous = 0, direction_changes = 0, last_direction = 0, changes = 0;
  for (int f = 0; f < 2000; ++f) {
    const double t = f < 1000 ? f / 1000.0 : (2000 - f) / 1000.0;  // in, then out
    const double required = 256 * std::pow(16.0, t) * noise();
    const int res = ctl.update(required);
    if (previous != 0 && res != previous) {
      ++changes;
      const int dir = res > previous ? 1 : -1;
      if (last_direction != 0 && dir != last_direction) ++direction_changes;
      last_direction = dir;
    }
    previous = res;
  }
  EXPECT_LE(direction_changes, 1) << "only the turn of the zoom may reverse the direction";
  EXPECT_GT(changes, 10) << "the resolution must still follow the zoom";
}

TEST(ResolutionController, ConstantRequirementNeverChanges) {
  ResolutionController ctl({{16, 8192, 32}, 30, 0.8});
  for (int f = 0; f < 500; ++f) ctl.update(700.0 + (f % 2 ? 20.0 : -20.0));  // ±3 % around 700
  EXPECT_LE(ctl.changes(), 1);
}

class CalibrationFile : public ::testing::Test {
 protected:
  std::filesystem::path write(const std::string& text) {
    const auto p = std::filesystem::temp_directory_path() / ("penumbra_cal_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) + "_" + std::to_string(n_++) + ".json");
    std::ofstream(p) << text;
    files_.push_back(p);
    return p;
  }
  void TearDown() override {
    for (const auto& f : files_) std::filesystem::remove(f);
  }
  std::vector<std::filesystem::path> files_;
  int n_ = 0;
};

TEST_F(CalibrationFile, ShippedDefaultIsThePublishedConstant) {
  const Calibration cal = load_calibration(PENUMBRA_SOURCE_DIR "/data/calibration/default.json");
  EXPECT_DOUBLE_EQ(cal.c, 3.47);
  EXPECT_LE(cal.ci95_lo, cal.c);
  EXPECT_GE(cal.ci95_hi, cal.c);
}

TEST_F(CalibrationFile, BadFilesNameTheField) {
  struct Case {
    std::string text, field;
  };
  const Case cases[] = {
      {"{}", ": c: missing"},
      {R"({"c": "3"})", ": c: expected a number"},
      {R"({"c": -1})", ": c: expected a positive number"},
      {R"({"c": 0})", ": c: expected a positive number"},
      {R"({"c": 3, "ci95": [4, 5]})", ": ci95: expected 0 < lo <= c <= hi"},
      {R"({"c": 3, "ci95": [1]})", ": ci95: expected [lo, hi]"},
      {R"({"c": 3, "condition": 7})", ": condition: expected a string"},
      {R"([1, 2])", ": (top level): expected an object"},
      {R"({"c": 3,)", ":1:9: malformed JSON"},
      // Issue 14.8: c is kept as a float; 1e308 became inf and 1e-300 became 0. A duplicated key
      // was read as its last value.
      {R"({"c": 1e308})", ": c: expected a positive number in [0.01, 1000] texels"},
      {R"({"c": 1e-300})", ": c: expected a positive number in [0.01, 1000] texels"},
      {R"({"c": 3, "ci95": [2, 1e300]})", ": ci95: expected 0 < lo <= c <= hi"},
      {R"({"c": 3, "c": 4})", ": c: duplicate key"},
      {R"({"c": 1e400})", ":1:7: malformed JSON: number overflow"},
  };
  for (const auto& c : cases) {
    const auto p = write(c.text);
    try {
      load_calibration(p);
      ADD_FAILURE() << "accepted " << c.text;
    } catch (const CalibrationError& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find(p.string() + c.field), std::string::npos) << msg;
      EXPECT_EQ(msg.find('\n'), std::string::npos);
    }
  }
  EXPECT_THROW(load_calibration("/nonexistent/calibration.json"), CalibrationError);
}

TEST(CascadeSplits, PracticalSchemeBetweenUniformAndLogarithmic) {
  const auto uniform = cascade_splits(1, 100, 4, 0);
  const auto logarithmic = cascade_splits(1, 100, 4, 1);
  const auto practical = cascade_splits(1, 100, 4, 0.5);
  ASSERT_EQ(uniform.size(), 5u);
  EXPECT_DOUBLE_EQ(uniform[1], 1 + 99 * 0.25);
  EXPECT_NEAR(logarithmic[2], 10, 1e-9);  // sqrt(1 * 100)
  for (std::size_t i = 0; i < 5; ++i) EXPECT_NEAR(practical[i], 0.5 * (uniform[i] + logarithmic[i]), 1e-9);
  for (const auto& z : {uniform, logarithmic, practical}) {
    EXPECT_EQ(z.front(), 1);
    EXPECT_EQ(z.back(), 100);
    for (std::size_t i = 1; i < z.size(); ++i) EXPECT_GT(z[i], z[i - 1]);
  }
}

TEST(CascadeSplits, DegenerateInputIsRepaired) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (const auto& z : {cascade_splits(0, 100, 3, 1), cascade_splits(-5, 100, 3, 0.75), cascade_splits(5, 5, 2, 0.5),
                        cascade_splits(5, 1, 2, 0.5), cascade_splits(nan, nan, 2, nan), cascade_splits(1, 10, 0, 2)}) {
    ASSERT_GE(z.size(), 2u);
    EXPECT_GT(z.front(), 0);
    for (std::size_t i = 0; i < z.size(); ++i) EXPECT_TRUE(std::isfinite(z[i]));
    for (std::size_t i = 1; i < z.size(); ++i) EXPECT_GT(z[i], z[i - 1]);
  }
  EXPECT_EQ(cascade_splits(1, 10, 0, 0.5).size(), 2u);  // count < 1 means one cascade
}

TEST(CascadeCount, FewestThatFitAndOneForASceneThatFitsOneMap) {
  // The requirement of a view split n ways: each cascade covers 1/n of an extent needing 3000 texels.
  auto required = [](int n) { return std::vector<double>(static_cast<std::size_t>(n), 3000.0 / n); };
  EXPECT_EQ(choose_cascade_count(4, 4096, required).count, 1);
  const CascadeChoice two = choose_cascade_count(4, 2048, required);
  EXPECT_EQ(two.count, 2);
  EXPECT_TRUE(two.fits);
  EXPECT_EQ(choose_cascade_count(4, 1000, required).count, 3);
  const CascadeChoice none = choose_cascade_count(4, 100, required);
  EXPECT_EQ(none.count, 4);
  EXPECT_FALSE(none.fits);
  // Infinite (hard shadows) and NaN requirements never fit.
  auto inf = [](int n) { return std::vector<double>(static_cast<std::size_t>(n), std::numeric_limits<double>::infinity()); };
  EXPECT_FALSE(choose_cascade_count(4, 8192, inf).fits);
  auto nan = [](int n) { return std::vector<double>(static_cast<std::size_t>(n), std::nan("")); };
  EXPECT_FALSE(choose_cascade_count(2, 8192, nan).fits);
}

}  // namespace
}  // namespace penumbra::adaptive
