// penumbra-observer-fit (issue 48, docs/study.md "The observer against people"): the image
// observer's decision noise fitted to one human threshold reproduces it, the weber it prints gives
// the same c when penumbra-observer-curve reads the same renders with it, and the held-out
// prediction is the one docs/results/study.md reports (within this smaller run's own interval);
// a command line it cannot use is refused in one line naming the option. Label slow: about 220
// renders (100 s on the shared 2-core machine).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

#include "tool_run.h"

namespace {

namespace fs = std::filesystem;
using penumbra::test::bytes;
using penumbra::test::fresh_dir;
using penumbra::test::Ran;
using penumbra::test::run_in;

const std::string kFit = PENUMBRA_OBSERVER_FIT_EXE;
const std::string kCurve = PENUMBRA_OBSERVER_CURVE_EXE;
// The documented run (docs/results/study.md, 2026-12-06: 8 grids of 2 stimuli, both contrasts)
// at a quarter of its renders: stair and step at full contrast, 4 grids of 1 stimulus each.
const std::string kGrid = "--artifact-px 10 --ratio-min 1 --ratio-max 8 --ratio-step 1.08";
// What that documented run printed: fitted to the step's 3.47, the stair's c held out; fitted to
// the stair's 2.5, the step's.
constexpr double kDocumentedStairFromStep = 2.08, kDocumentedStepFromStair = 3.80;

const nlohmann::json& prediction(const nlohmann::json& fit, const std::string& condition) {
  for (const auto& p : fit["predictions"])
    if (p["condition"] == condition) return p;
  throw std::runtime_error("no prediction of " + condition);
}

TEST(ObserverFit, TheFittedWeberReproducesItsTargetAndTheHeldOutPredictionIsTheDocumentedOne) {
  const fs::path dir = fresh_dir("penumbra-observer-fit-", "fit");
  const Ran ran = run_in(dir, kFit, kGrid + " --human step/1=3.47 --human stair/1=2.5 --contrast 1 --grids 4 --seeds 1 --json fit.json");
  ASSERT_EQ(ran.status, 0) << ran.err;
  const nlohmann::json out = nlohmann::json::parse(bytes(dir / "fit.json"));
  ASSERT_EQ(out["fits"].size(), 2u);
  const nlohmann::json& from_step = out["fits"][0];
  const nlohmann::json& from_stair = out["fits"][1];
  ASSERT_EQ(from_step["condition"], "step/1");
  ASSERT_EQ(from_stair["condition"], "stair/1");

  // The fitted parameter reproduces its target within the stated 1 % (the step's c is
  // continuous in weber there; the stair's can jump, and the fit says what it reaches).
  EXPECT_NEAR(from_step["c"].get<double>(), 3.47, 0.01 * 3.47);
  const double weber = from_step["weber"].get<double>();
  EXPECT_GT(weber, 0.0025);  // near the shipped 0.003 that was set by hand on the same condition
  EXPECT_LT(weber, 0.0032);

  // Read by the other tool: grid 0 is penumbra-observer-curve's own grid and stimuli, so at that
  // weber it must print grid 0's c.
  char weber_text[64];
  std::snprintf(weber_text, sizeof weber_text, "%.17g", weber);
  const Ran curve = run_in(dir, kCurve, kGrid + " --pattern step --seeds 1 --weber " + weber_text + " --json curve.json");
  ASSERT_EQ(curve.status, 0) << curve.err;
  const nlohmann::json curve_json = nlohmann::json::parse(bytes(dir / "curve.json"));
  EXPECT_NEAR(curve_json["entries"][0]["per_condition"][0]["c"].get<double>(), from_step["c_per_grid"][0].get<double>(), 1e-9);

  // Held out: the stair predicted from the step lies below people's 2.5 and this run's interval
  // holds the documented run's value; the other way round the step is predicted above 3.47.
  const nlohmann::json& stair = prediction(from_step, "stair/1");
  EXPECT_LT(stair["c"].get<double>(), 2.5);
  EXPECT_NEAR(stair["error"].get<double>(), stair["c"].get<double>() / 2.5 - 1, 1e-12);
  EXPECT_LE(stair["ci95"][0].get<double>(), kDocumentedStairFromStep);
  EXPECT_GE(stair["ci95"][1].get<double>(), kDocumentedStairFromStep);
  const nlohmann::json& step = prediction(from_stair, "step/1");
  EXPECT_GT(step["c"].get<double>(), 3.47);
  EXPECT_LE(step["ci95"][0].get<double>(), kDocumentedStepFromStair);
  EXPECT_GE(step["ci95"][1].get<double>(), kDocumentedStepFromStair);

  // People's ordering, checked on every grid under both fits.
  for (const auto& fit : out["fits"]) {
    for (const auto& check : fit["checks"]) {
      if (check["check"] != "step above stair") continue;
      EXPECT_EQ(check["grids_passing"], check["grids"]) << fit["condition"];
    }
  }
}

TEST(ObserverFit, ACommandLineItCannotUseIsRefusedInOneLineNamingTheOption) {
  const fs::path dir = fresh_dir("penumbra-observer-fit-", "refusals");
  for (const std::string& args : {std::string("--human step/1=3.47"), std::string("--human step/1=3.47,stair/0.7=2.5"),
                                  std::string("--human step/1=3.47,step/1=3.5"), std::string("--human stair/1=x,step/1=3"),
                                  std::string("--human wave/1=2,step/1=3")}) {
    const Ran ran = run_in(dir, kFit, args + " --json never.json");
    EXPECT_EQ(ran.status, 2) << args << ": " << ran.err;
    EXPECT_EQ(ran.err.find("penumbra-observer-fit: --human"), 0u) << args << ": " << ran.err;
    EXPECT_EQ(std::count(ran.err.begin(), ran.err.end(), '\n'), 1) << args << ": " << ran.err;
    EXPECT_FALSE(fs::exists(dir / "never.json")) << args;
  }
}

}  // namespace
