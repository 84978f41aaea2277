// The filter-to-resolution rule, its clamping and the hysteresis controller (label `unit`).
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

#include "adaptive/cascades.h"
#include "adaptive/resolution_rule.h"
#include "psychometric/psychometric.h"

namespace penumbra::adaptive {
namespace {

TEST(ResolutionRule, PublishedConstantGivesTheThesisResolutions) {
  // r = c·a: a radius of 3.47 texels of a 1024 map hides that map's staircase exactly.
  EXPECT_DOUBLE_EQ(required_texels_uv(3.47, FilterRadiusUv{3.47 / 1024.0}), 1024.0);
  // World space: a 0.1-unit radius over a 20-unit view plane needs c · 200 texels.
  EXPECT_NEAR(required_texels_ws(3.47, LightExtentWs{20.0}, FilterRadiusWs{0.1}), 694.0, 1e-9);
  // Doubling the radius halves the resolution.
  EXPECT_DOUBLE_EQ(required_texels_ws(3.47, LightExtentWs{20.0}, FilterRadiusWs{0.2}),
                   required_texels_ws(3.47, LightExtentWs{20.0}, FilterRadiusWs{0.1}) / 2);
}

TEST(ResolutionRule, ExtremesAreClampedAndFinite) {
  const ResolutionLimits lim{16, 8192, 32};
  const double inf = std::numeric_limits<double>::infinity(), nan = std::nan("");
  // Not lengths (r = 0, r < 0, NaN, L = 0, L = inf): refused by the rule, which used to clamp them
  // (to max, max, max, min, max); ResolutionRule.RefusesWhatIsNotAPositiveFiniteLength.
  EXPECT_THROW(required_texels_uv(3.47, FilterRadiusUv{0.0}), std::invalid_argument);
  EXPECT_EQ(clamp_resolution(required_texels_uv(3.47, FilterRadiusUv{1e-300}), lim), 8192);  // r → 0
  EXPECT_THROW(required_texels_uv(3.47, FilterRadiusUv{-1.0}), std::invalid_argument);
  EXPECT_THROW(required_texels_uv(3.47, FilterRadiusUv{nan}), std::invalid_argument);
  EXPECT_EQ(clamp_resolution(required_texels_uv(3.47, FilterRadiusUv{1e300}), lim), 16);    // r huge
  EXPECT_THROW(required_texels_ws(3.47, LightExtentWs{0.0}, FilterRadiusWs{0.1}), std::invalid_argument);
  EXPECT_EQ(clamp_resolution(required_texels_ws(3.47, LightExtentWs{1e-30}, FilterRadiusWs{0.1}), lim), 16);  // L → 0
  EXPECT_THROW(required_texels_ws(3.47, LightExtentWs{inf}, FilterRadiusWs{0.1}), std::invalid_argument);
  EXPECT_EQ(clamp_resolution(required_texels_ws(3.47, LightExtentWs{1e300}, FilterRadiusWs{1e-300}), lim), 8192);  // r_uv underflows
  EXPECT_EQ(clamp_resolution(inf, lim), 8192);
  EXPECT_EQ(clamp_resolution(-inf, lim), 16);
  EXPECT_EQ(clamp_resolution(nan, lim), 8192);
  // Degenerate limits still give a positive size.
  EXPECT_EQ(clamp_resolution(100, {0, 0, 0}), 1);
  EXPECT_EQ(clamp_resolution(100, {64, 32, 7}), 64);  // max below min: min wins
}

// Each parameter of the rule, given 0, a negative, NaN or infinity, is refused by name: a value
// swapped or never set must not come back as a plausible resolution.
TEST(ResolutionRule, RefusesWhatIsNotAPositiveFiniteLength) {
  const double inf = std::numeric_limits<double>::infinity(), nan = std::nan("");
  auto message = [](auto&& call) -> std::string {
    try {
      call();
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "(no exception)";
  };
  auto starts_with = [](const std::string& text, const std::string& prefix) { return text.rfind(prefix, 0) == 0; };
  for (const double bad : {0.0, -0.0, -1.0, nan, inf, -inf}) {
    SCOPED_TRACE(bad);
    EXPECT_PRED2(starts_with, message([&] { required_texels_ws(bad, LightExtentWs{20.0}, FilterRadiusWs{0.1}); }),
                 "required_texels_ws: c must be positive and finite, got ");
    EXPECT_PRED2(starts_with, message([&] { required_texels_ws(3.47, LightExtentWs{bad}, FilterRadiusWs{0.1}); }),
                 "required_texels_ws: light_extent_ws must be positive and finite, got ");
    EXPECT_PRED2(starts_with, message([&] { required_texels_ws(3.47, LightExtentWs{20.0}, FilterRadiusWs{bad}); }),
                 "required_texels_ws: radius_ws must be positive and finite, got ");
    EXPECT_PRED2(starts_with, message([&] { required_texels_uv(bad, FilterRadiusUv{0.01}); }),
                 "required_texels_uv: c must be positive and finite, got ");
    EXPECT_PRED2(starts_with, message([&] { required_texels_uv(3.47, FilterRadiusUv{bad}); }),
                 "required_texels_uv: radius_uv must be positive and finite, got ");
  }
  EXPECT_EQ(message([] { required_texels_ws(3.47, LightExtentWs{0.05}, FilterRadiusWs{-20}); }),
            "required_texels_ws: radius_ws must be positive and finite, got -20");
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
    // The process id: CTest runs each test of this fixture as its own process, side by side under
    // -j2, and the same names raced (a test read another's file now and then).
    const auto p = std::filesystem::temp_directory_path() / ("penumbra_cal_" + std::to_string(::getpid()) + "_" + std::to_string(n_++) + ".json");
    std::ofstream(p) << text;
    files_.push_back(p);
    return p;
  }
  void TearDown() override {
    for (const auto& f : files_) std::filesystem::remove(f);
  }
  // `text` as a calibration file is refused in one line naming the file and then `field`.
  void expect_refused(const std::string& text, const std::string& field) {
    SCOPED_TRACE(text);
    const auto p = write(text);
    try {
      load_calibration(p);
      ADD_FAILURE() << "accepted " << text;
    } catch (const CalibrationError& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find(p.string() + field), std::string::npos) << msg;
      EXPECT_EQ(msg.find('\n'), std::string::npos);
    }
  }
  std::vector<std::filesystem::path> files_;
  int n_ = 0;
};

TEST_F(CalibrationFile, ShippedDefaultIsThePublishedConstant) {
  const Calibration cal = load_calibration(PENUMBRA_SOURCE_DIR "/data/calibration/default.json");
  EXPECT_EQ(cal.schema_version, 2);
  ASSERT_EQ(cal.entries.size(), 1u);
  const CalibrationEntry& e = cal.entries[0];
  EXPECT_EQ(e.technique, "pcf");
  EXPECT_EQ(e.kernel, "");
  EXPECT_DOUBLE_EQ(e.c, kPublishedC);
  EXPECT_EQ(e.obtained_by, CalibrationMethod::published);
  EXPECT_EQ(e.participants, 10);
  // The thesis gives no interval: none is read (nor written as [3.47, 3.47]).
  EXPECT_FALSE(e.has_ci95);
  EXPECT_FALSE(cal.choose("pcf", "disk").has_ci95);
  // Issue 29: the published entry says what its c is a threshold of, as this project reads the
  // thesis (yes/no scored as balanced percent correct): F 0.674, QUEST's assumed slope 3.5; in 2AFC
  // terms (F* 0.6465) 3.54, or 3.97 if QUEST was fed the jagged trials only.
  ASSERT_TRUE(e.threshold.has_value());
  EXPECT_EQ(e.threshold->task, "yesno");
  EXPECT_NEAR(e.threshold->criterion_f, 0.6737, 1e-4);
  EXPECT_TRUE(e.threshold->beta_assumed);
  EXPECT_NEAR(c_at_visibility(e, 0.6464646464646464).c, 3.54, 0.01);
  EXPECT_NEAR(c_at_visibility(3.47, 0.8105, 0.6464646464646464, 3.5), 3.97, 0.01);
  // Issue 48: far from the criterion the interval carries the psychometric family: the published
  // entry has no interval of c or of its (assumed) slope, yet at F 0.1 it is no longer one number
  // (the log-Weibull's long lower tail asks the largest c there; the normal and logistic less).
  const CAtVisibility far = c_at_visibility(e, 0.1);
  EXPECT_LT(far.lo, 0.95 * far.c);
  EXPECT_GE(far.hi, far.c);
  EXPECT_LE(far.lo, far.family_lo);
  EXPECT_GE(far.hi, far.family_hi);
  // The published entry states no kernel: the study's disk is assumed (its reading), so PCF's disk
  // takes it as measured and the grid (the main job's PCF) as a fallback, said so (issue 48).
  EXPECT_FALSE(cal.choose("pcf", "disk").fallback);
  const CalibrationChoice grid = cal.choose("pcf", "grid");
  EXPECT_DOUBLE_EQ(grid.c, kPublishedC);
  EXPECT_TRUE(grid.fallback);
  EXPECT_EQ(grid.from,
            "pcf entry (published, 10 participants), not measured for pcf grid: measured with the disk kernel (the study's, assumed: the "
            "entry states none), not with grid; a pcf grid entry would match");
  EXPECT_EQ(grid.would_match, "a pcf grid entry");
  // Another technique gets PCF's entry, said to be a fallback.
  const CalibrationChoice vsm = cal.choose("vsm", "");
  EXPECT_DOUBLE_EQ(vsm.c, kPublishedC);
  EXPECT_TRUE(vsm.fallback);
  EXPECT_EQ(vsm.from, "pcf entry (published, 10 participants), not measured for vsm: measured for pcf, not for vsm; a vsm entry would match");
}

// A version-1 file (one top-level c, as penumbra-fit wrote before entries per technique) loads as
// the PCF entry for any kernel; a fitted one counts as a study.
TEST_F(CalibrationFile, VersionOneFilesLoadAsThePcfEntry) {
  const Calibration fitted = load_calibration(write(R"({"c": 4.25, "ci95": [3.5, 5.0], "condition": "step/1",
                                                        "source": "penumbra-fit: joint fit", "per_condition": []})"));
  EXPECT_EQ(fitted.schema_version, 1);
  ASSERT_EQ(fitted.entries.size(), 1u);
  EXPECT_EQ(fitted.entries[0].technique, "pcf");
  EXPECT_EQ(fitted.entries[0].kernel, "");
  EXPECT_EQ(fitted.entries[0].obtained_by, CalibrationMethod::study);
  EXPECT_EQ(fitted.entries[0].condition, "step/1");
  const CalibrationChoice c = fitted.choose("pcf", "disk");
  EXPECT_DOUBLE_EQ(c.c, 4.25);
  EXPECT_DOUBLE_EQ(c.ci95_lo, 3.5);
  EXPECT_DOUBLE_EQ(c.ci95_hi, 5.0);
  EXPECT_FALSE(c.fallback);
  // Measured with the study's disk: for the Poisson kernel it stands in, said so (issue 48).
  EXPECT_TRUE(fitted.choose("pcf", "poisson").fallback);
  EXPECT_EQ(load_calibration(write(R"({"c": 3})")).entries[0].obtained_by, CalibrationMethod::published);
}

// The lookup order: technique and kernel, the technique for any kernel, another kernel of the
// technique, the PCF entry, the published value; every fallback says what it stands in for.
TEST_F(CalibrationFile, EachTechniqueGetsItsOwnEntryOrASaidFallback) {
  const Calibration cal = load_calibration(write(R"({"schema_version": 2, "entries": [
      {"technique": "pcf", "kernel": "poisson", "c": 3.0, "ci95": [2.5, 3.5], "obtained_by": "study", "participants": 5, "trials": 900},
      {"technique": "pcf", "kernel": "grid", "c": 2.0, "obtained_by": "image-observer"},
      {"technique": "vsm", "kernel": "", "c": 4.0, "obtained_by": "simulated"},
      {"technique": "rpcf", "kernel": "wide", "c": 0.8, "obtained_by": "study", "participants": 1}]})"));
  EXPECT_EQ(cal.entries[0].trials, 900);
  struct Case {
    const char* technique;
    const char* kernel;
    double c;
    bool fallback;
    const char* from;
  };
  for (const Case& k : {Case{"pcf", "poisson", 3.0, false, "pcf poisson entry (people, 5 participants)"},
                        Case{"pcf", "grid", 2.0, false, "pcf grid entry (image observer)"},
                        Case{"vsm", "", 4.0, false, "vsm entry (psychometric simulation)"},
                        Case{"rpcf", "", 0.8, true,
                             "rpcf wide entry (people, 1 participant), not measured for rpcf: measured with the wide kernel; a rpcf entry "
                             "would match"},
                        Case{"msm", "", 3.0, true,
                             "pcf poisson entry (people, 5 participants), not measured for msm: measured for pcf, not for msm; a msm entry "
                             "would match"}}) {
    SCOPED_TRACE(std::string(k.technique) + " " + k.kernel);
    const CalibrationChoice got = cal.choose(k.technique, k.kernel);
    EXPECT_DOUBLE_EQ(got.c, k.c);
    EXPECT_EQ(got.fallback, k.fallback);
    EXPECT_EQ(got.from, k.from);
    ASSERT_TRUE(got.entry.has_value());
  }
  // No PCF entry to stand in: the published value, said so.
  const Calibration only_vsm = load_calibration(
      write(R"({"schema_version": 2, "entries": [{"technique": "vsm", "c": 4.0, "obtained_by": "study"}]})"));
  const CalibrationChoice esm = only_vsm.choose("esm", "");
  EXPECT_DOUBLE_EQ(esm.c, kPublishedC);
  EXPECT_TRUE(esm.fallback);
  EXPECT_FALSE(esm.entry.has_value());
  EXPECT_EQ(esm.from, "published PCF value, not measured for esm; a esm entry would match");
}

// Issue 48: kernel matching is loud. The renderer's Poisson disk rotated per pixel is another filter
// than the unrotated one every entry was measured with (the study draws one tap pattern and refuses
// pcf.rotate), and a grid is not the disk an entry without a kernel was measured with: each is a
// fallback naming why and what would match.
TEST_F(CalibrationFile, AnotherKernelOrRotationIsAFallbackSaidWithWhatWouldMatch) {
  const Calibration predicted = load_calibration(PENUMBRA_SOURCE_DIR "/data/calibration/predicted.json");
  const CalibrationChoice unrotated = predicted.choose("pcf", "poisson", false);
  EXPECT_FALSE(unrotated.fallback) << unrotated.from;
  const CalibrationChoice rotated = predicted.choose("pcf", "poisson", true);
  EXPECT_TRUE(rotated.fallback);
  ASSERT_TRUE(rotated.entry.has_value());
  EXPECT_EQ(rotated.entry->kernel, "poisson");
  EXPECT_DOUBLE_EQ(rotated.c, unrotated.c);
  EXPECT_NE(rotated.from.find("not measured for pcf poisson rotated per pixel: measured unrotated"), std::string::npos) << rotated.from;
  EXPECT_EQ(rotated.would_match, "an entry for pcf poisson measured rotated, or pcf.rotate false with a pcf poisson entry");
  EXPECT_NE(rotated.fallback_reason.find("unrotated"), std::string::npos);
  // Grid against the published (disk) entry, and against a disk entry stated as such.
  const Calibration published = load_calibration(PENUMBRA_SOURCE_DIR "/data/calibration/default.json");
  const CalibrationChoice grid = published.choose("pcf", "grid");
  EXPECT_TRUE(grid.fallback);
  EXPECT_NE(grid.fallback_reason.find("disk"), std::string::npos) << grid.fallback_reason;
  const Calibration disk = load_calibration(write(R"({"schema_version": 2, "entries": [
      {"technique": "pcf", "kernel": "disk", "c": 3.1, "obtained_by": "study", "participants": 8}]})"));
  EXPECT_FALSE(disk.choose("pcf", "disk").fallback);
  const CalibrationChoice disk_for_grid = disk.choose("pcf", "grid");
  EXPECT_TRUE(disk_for_grid.fallback);
  EXPECT_EQ(disk_for_grid.from,
            "pcf disk entry (people, 8 participants), not measured for pcf grid: measured with the disk kernel, not with grid; a pcf grid "
            "entry would match");
  // An exact match says no reason.
  EXPECT_TRUE(disk.choose("pcf", "disk").fallback_reason.empty());
}

TEST_F(CalibrationFile, BadVersionTwoFilesNameTheField) {
  struct Case {
    std::string text, field;
  };
  const std::string ok_entry = R"({"technique": "pcf", "c": 3, "obtained_by": "study"})";
  const Case cases[] = {
      {R"({"schema_version": 3, "entries": [)" + ok_entry + "]}", ": schema_version: expected 2 (or no field: a version-1 file"},
      {R"({"schema_version": "2", "entries": [)" + ok_entry + "]}", ": schema_version: expected 2"},
      {R"({"schema_version": 2.5, "entries": [)" + ok_entry + "]}", ": schema_version: expected 2"},
      {R"({"schema_version": 2})", ": entries: missing"},
      {R"({"schema_version": 2, "entries": []})", ": entries: expected a non-empty array"},
      {R"({"schema_version": 2, "entries": {}})", ": entries: expected a non-empty array"},
      {R"({"schema_version": 2, "c": 3, "entries": [)" + ok_entry + "]}", ": c: a version-2 file has its c in entries[]"},
      {R"({"schema_version": 2, "entries": [7]})", ": entries[0]: expected an object"},
      {R"({"schema_version": 2, "entries": [{"c": 3, "obtained_by": "study"}]})", ": entries[0].technique: missing"},
      {R"({"schema_version": 2, "entries": [{"technique": "", "c": 3, "obtained_by": "study"}]})", ": entries[0].technique: expected a non-empty string, got \"\""},
      {R"({"schema_version": 2, "entries": [{"technique": "pcf", "obtained_by": "study"}]})", ": entries[0].c: missing"},
      {R"({"schema_version": 2, "entries": [{"technique": "pcf", "c": 1e308, "obtained_by": "study"}]})", ": entries[0].c: expected a number in [0.01, 1000] texels, got 1e+308"},
      {R"({"schema_version": 2, "entries": [{"technique": "pcf", "c": 3, "ci95": [4, 5], "obtained_by": "study"}]})", ": entries[0].ci95: expected 0 < lo"},
      {R"({"schema_version": 2, "entries": [{"technique": "pcf", "c": 3}]})", ": entries[0].obtained_by: missing"},
      {R"({"schema_version": 2, "entries": [{"technique": "pcf", "c": 3, "obtained_by": "guess"}]})", ": entries[0].obtained_by: obtained_by 'guess': expected study, image-observer"},
      {R"({"schema_version": 2, "entries": [{"technique": "pcf", "c": 3, "obtained_by": "study", "participants": -1}]})", ": entries[0].participants: expected an integer in [0, 2147483647] or null, got -1"},
      {R"({"schema_version": 2, "entries": [{"technique": "pcf", "c": 3, "obtained_by": "study", "trials": 4294967296}]})", ": entries[0].trials: expected an integer in [0, 2147483647] or null, got 4294967296"},
      {R"({"schema_version": 2, "entries": [)" + ok_entry + ", " + ok_entry + "]}", ": entries[1]: a second entry for pcf"},
  };
  for (const auto& c : cases) expect_refused(c.text, c.field);
}

// A study config given as --calibration is named as such, with the file that is wanted, instead of
// "c: missing".
TEST_F(CalibrationFile, AStudyConfigIsNamedAsOneWithTheFileWanted) {
  const auto p = write(R"({"name": "lab", "task": "2afc", "rounds": [{"pattern": "stair", "contrast": 1}], "quest": {"beta": 3.5}})");
  try {
    load_calibration(p);
    ADD_FAILURE() << "a study config was read as a calibration";
  } catch (const CalibrationError& e) {
    const std::string msg = e.what();
    EXPECT_EQ(msg.rfind(p.string() + ": a study config (penumbra-study --config), not a calibration file", 0), 0u) << msg;
    EXPECT_NE(msg.find("calibration.json penumbra-fit writes"), std::string::npos) << msg;
    EXPECT_EQ(msg.find("missing"), std::string::npos) << msg;
  }
  // A file with an interval says it has one.
  const Calibration with = load_calibration(write(R"({"c": 3, "ci95": [2.5, 3.5]})"));
  EXPECT_TRUE(with.entries.at(0).has_ci95);
  EXPECT_TRUE(with.choose("pcf", "grid").has_ci95);
}

TEST_F(CalibrationFile, BadFilesNameTheField) {
  struct Case {
    std::string text, field;
  };
  const Case cases[] = {
      {"{}", ": c: missing"},
      {R"({"c": "3"})", ": c: expected a number"},
      {R"({"c": -1})", ": c: expected a number in [0.01, 1000] texels, got -1"},
      {R"({"c": 0})", ": c: expected a number in [0.01, 1000] texels, got 0"},
      {R"({"c": 3, "ci95": [4, 5]})", ": ci95: expected 0 < lo <= c <= hi"},
      {R"({"c": 3, "ci95": [1]})", ": ci95: expected an array of 2 numbers, got an array of 1 element"},
      {R"({"c": 3, "condition": 7})", ": condition: expected a string"},
      {R"([1, 2])", ": (top level): expected an object"},
      {R"({"c": 3,)", ":1:9: malformed JSON"},
      // Issue 14.8: c is kept as a float; 1e308 became inf and 1e-300 became 0. A duplicated key
      // was read as its last value.
      {R"({"c": 1e308})", ": c: expected a number in [0.01, 1000] texels, got 1e+308"},
      {R"({"c": 1e-300})", ": c: expected a number in [0.01, 1000] texels, got 1e-300"},
      {R"({"c": 3, "ci95": [2, 1e300]})", ": ci95[1]: expected a number in (0, 1000], got 1e+300"},
      {R"({"c": 3, "c": 4})", ": c: duplicate key"},
      {R"({"c": 1e400})", ":1:7: malformed JSON: number overflow"},
  };
  for (const auto& c : cases) expect_refused(c.text, c.field);
  EXPECT_THROW(load_calibration("/nonexistent/calibration.json"), CalibrationError);
}

// Issue 48: an entry's population block (penumbra-fit's multilevel fit, as it writes it) is read,
// and c_at_observer_percentile gives the fitted percentile's own c and interval, any other
// percentile from the mean and the spread with the corners of their intervals; an entry without
// the block (the published constant, a predicted entry) is refused naming the entry.
TEST_F(CalibrationFile, APercentileObserversCComesFromThePopulationBlock) {
  const Calibration cal = load_calibration(write(R"json({"schema_version": 2, "entries": [
      {"technique": "pcf", "kernel": "grid", "c": 3.13, "ci95": [2.73, 3.73], "obtained_by": "simulated", "participants": 6,
       "population": {"method": "multilevel: ...", "participants": 6, "condition": "the worst condition (stair/1)",
                      "mean_c": 3.184, "mean_c_ci95": [2.732, 3.734], "sd_log10": 0.05, "sd_log10_ci95": [0.02, 0.09],
                      "observer_percentile": "90", "percentile_c": 3.273, "percentile_c_ci95": [2.824, 4.583],
                      "worst_interval": "the largest of the conditions' simultaneous (Bonferroni) intervals"}},
      {"technique": "vsm", "c": 3.06, "obtained_by": "image-observer", "population": null}]})json"));
  const CalibrationEntry& grid = cal.entries[0];
  ASSERT_TRUE(grid.population.has_value());
  EXPECT_EQ(grid.population->participants, 6);
  EXPECT_EQ(grid.population->percentile, 90.0);
  const CAtPercentile fitted = c_at_observer_percentile(grid, 90);
  EXPECT_TRUE(fitted.fitted);
  EXPECT_EQ(fitted.c, 3.273);
  EXPECT_EQ(fitted.lo, 2.824);
  EXPECT_EQ(fitted.hi, 4.583);
  // The median observer is the population's mean (z = 0): its interval is the mean's.
  const CAtPercentile median = c_at_observer_percentile(grid, 50);
  EXPECT_FALSE(median.fitted);
  EXPECT_NEAR(median.c, 3.184, 1e-12);
  EXPECT_NEAR(median.lo, 2.732, 1e-12);
  EXPECT_NEAR(median.hi, 3.734, 1e-12);
  // 97.5 %: z = 1.95996; the spread's upper bound raises the upper corner, its lower the lower.
  const double z = 1.959963984540054;
  const CAtPercentile p975 = c_at_observer_percentile(grid, 97.5);
  EXPECT_NEAR(p975.c, 3.184 * std::pow(10.0, z * 0.05), 1e-9);
  EXPECT_NEAR(p975.lo, 2.732 * std::pow(10.0, z * 0.02), 1e-9);
  EXPECT_NEAR(p975.hi, 3.734 * std::pow(10.0, z * 0.09), 1e-9);
  // Below the median the spread lowers c: the larger spread gives the lower corner.
  const CAtPercentile p10 = c_at_observer_percentile(grid, 10);
  EXPECT_LT(p10.c, median.c);
  EXPECT_NEAR(p10.lo, 2.732 * std::pow(10.0, -1.2815515655446004 * 0.09), 1e-9);
  EXPECT_NEAR(p10.hi, 3.734 * std::pow(10.0, -1.2815515655446004 * 0.02), 1e-9);
  // Refusals: no population block (null or absent), a percentile outside (0, 100).
  EXPECT_FALSE(cal.entries[1].population.has_value());
  try {
    c_at_observer_percentile(cal.entries[1], 90);
    ADD_FAILURE() << "an entry without a population gave a percentile";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("vsm entry (image observer) has no population block"), std::string::npos) << e.what();
  }
  const Calibration published = load_calibration(PENUMBRA_SOURCE_DIR "/data/calibration/default.json");
  EXPECT_THROW(c_at_observer_percentile(published.entries[0], 90), std::invalid_argument);
  for (const double bad : {0.0, 100.0, -5.0, std::nan("")}) EXPECT_THROW(c_at_observer_percentile(grid, bad), std::invalid_argument) << bad;
  // A malformed block is refused naming the field.
  expect_refused(R"json({"schema_version": 2, "entries": [{"technique": "pcf", "c": 3, "obtained_by": "study",
      "population": {"mean_c": 3, "sd_log10": 0.05, "observer_percentile": "ninety"}}]})json",
                 ": entries[0].population.observer_percentile: expected a percentile in (0, 100)");
  expect_refused(R"json({"schema_version": 2, "entries": [{"technique": "pcf", "c": 3, "obtained_by": "study",
      "population": {"sd_log10": 0.05}}]})json",
                 ": entries[0].population.mean_c");
}

// Issue 48: the families' slopes are matched where the data are (at the criterion) and differ in
// the tail. family_slope gives the normal and logistic the log-Weibull's dF/dx at F* (checked by a
// finite difference of each core), so the curves agree near F* (within 1 % of c at F 0.55 and
// 0.75) and part in the tail: at F 0.1 the hull of c is wider than the slope's own interval, and
// holds each family's value; at the criterion nothing but the entry's ci95 is left.
TEST(CAtVisibility, FarFromTheCriterionTheIntervalHoldsEveryFamily) {
  const double f_star = 0.6464646464646464, beta = 3.5, c = 3.0;
  const double threshold_x = -std::log10(c);
  const auto slope = [&](psychometric::Model m, double b) {
    const double alpha = threshold_x - psychometric::core_inverse(m, f_star, 0.0, b);
    const double h = 1e-6;
    return (psychometric::core(m, threshold_x + h, alpha, b) - psychometric::core(m, threshold_x - h, alpha, b)) / (2 * h);
  };
  const double lw = slope(psychometric::Model::log_weibull, beta);
  for (const auto& [name, model] : {std::pair{"normal", psychometric::Model::normal}, std::pair{"logistic", psychometric::Model::logistic}}) {
    const double b = family_slope("log-weibull", beta, name, f_star);
    EXPECT_NEAR(slope(model, b) / lw, 1.0, 1e-6) << name;
    EXPECT_NEAR(family_slope(name, b, "log-weibull", f_star), beta, 1e-9) << name;
    for (const double near : {0.55, 0.75})
      EXPECT_NEAR(c_at_visibility(c, f_star, near, b, name) / c_at_visibility(c, f_star, near, beta), 1.0, 0.01) << name << " " << near;
  }
  EXPECT_DOUBLE_EQ(family_slope("weibull", beta, "log-weibull", f_star), beta);
  CalibrationEntry e;
  e.c = c;
  e.ci95_lo = 2.9;
  e.ci95_hi = 3.1;
  e.has_ci95 = true;
  ThresholdDefinition t;
  t.criterion_f = f_star;
  t.beta = beta;
  t.beta_lo = 3.0;
  t.beta_hi = 4.0;
  t.beta_assumed = false;
  e.threshold = t;
  const CAtVisibility far = c_at_visibility(e, 0.1);
  double slope_lo = INFINITY, slope_hi = 0;
  for (const double ce : {2.9, 3.1})
    for (const double b : {3.0, 4.0}) {
      slope_lo = std::min(slope_lo, c_at_visibility(ce, f_star, 0.1, b));
      slope_hi = std::max(slope_hi, c_at_visibility(ce, f_star, 0.1, b));
    }
  EXPECT_LE(far.lo, slope_lo);
  EXPECT_GE(far.hi, slope_hi);
  EXPECT_GT(far.family_hi / far.family_lo, 1.05);  // the family alone moves c(0.1) by more than 5 %
  for (const char* name : {"normal", "logistic"}) {
    const double v = c_at_visibility(c, f_star, 0.1, family_slope("log-weibull", beta, name, f_star), name);
    EXPECT_LE(far.lo, v) << name;
    EXPECT_GE(far.hi, v) << name;
  }
  const CAtVisibility at = c_at_visibility(e, f_star);
  EXPECT_DOUBLE_EQ(at.c, c);
  EXPECT_DOUBLE_EQ(at.lo, 2.9);
  EXPECT_DOUBLE_EQ(at.hi, 3.1);
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
