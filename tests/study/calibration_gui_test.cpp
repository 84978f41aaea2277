// `penumbra-study calibrate-display` in its window under Xvfb (run through run_under_xvfb.sh):
// xdotool types the synthetic monitor's luminance for each grey level shown, and the written file
// holds those readings and their gamma; a non-number is not taken; the checkerboard match turns
// arrow-key presses into the matched level and its gamma; Escape writes nothing.
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <thread>

#include <nlohmann/json.hpp>

#include "app_process.h"

namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using namespace penumbra;

const std::string kExe = PENUMBRA_STUDY_EXE;

fs::path fresh(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("penumbra-calgui-" + name + "-" + std::to_string(::getpid()));
  fs::remove_all(d);
  return d;
}

using test::slurp;

// penumbra-study in the background (app_process.h), and xdotool into its window.
class App : public test::App {
 public:
  explicit App(const std::vector<std::string>& args) : test::App(kExe, args) {}
};

bool xdo(App& app, const std::string& args) { return test::xdo(app, "Penumbra display calibration", args); }

double monitor_cd_m2(double level) { return 0.5 + 120.0 * std::pow(level / 255.0, 2.4); }

class CalibrationGui : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!std::getenv("DISPLAY")) GTEST_SKIP() << "no X display: run through run_under_xvfb.sh";
  }
};

TEST_F(CalibrationGui, TypedReadingsOfEachLevelBecomeTheCalibration) {
  const fs::path out = fresh("typed.json");
  App app({"calibrate-display", "--levels", "5", "--windowed", "480x320", "-o", out.string()});
  const std::vector<int> levels = {0, 64, 128, 191, 255};
  for (std::size_t i = 0; i < levels.size(); ++i) {
    const std::string shown = "showing level " + std::to_string(levels[i]) + " (" + std::to_string(i + 1) + " of 5)";
    ASSERT_TRUE(app.wait_for(shown)) << app.output();
    if (i == 1) {
      // A decimal comma is refused with a word about the point (it once became 81), and the box
      // empties: the reading typed next is taken alone, not appended to the refused one.
      ASSERT_TRUE(xdo(app, "type --delay 30 '8,1'"));
      ASSERT_TRUE(xdo(app, "key Return"));
      ASSERT_TRUE(app.wait_for("level 64: refused: '8,1': a decimal comma; type a point (8.1)")) << app.output();
    }
    if (i == 2) {  // not a number
      ASSERT_TRUE(xdo(app, "type --delay 30 'abc'"));
      ASSERT_TRUE(xdo(app, "key Return"));
      ASSERT_TRUE(app.wait_for("level 128: refused: 'abc' is not a number")) << app.output();
    }
    char typed[32];
    std::snprintf(typed, sizeof typed, "%.3f", monitor_cd_m2(levels[i]));
    ASSERT_TRUE(xdo(app, std::string("type --delay 30 '") + typed + "'"));
    ASSERT_TRUE(xdo(app, "key Return"));
    ASSERT_TRUE(app.wait_for("level " + std::to_string(levels[i]) + ": " + typed + " cd/m2")) << app.output();
  }
  // The review shows every reading and the fit; Enter writes (the window closes: xdotool may fail as it does).
  ASSERT_TRUE(app.wait_for("review: 5 readings, Enter writes")) << app.output();
  xdo(app, "key Return");
  ASSERT_EQ(app.wait_exit(), 0) << app.output();
  const nlohmann::json j = nlohmann::json::parse(slurp(out));
  ASSERT_EQ(j.at("points").size(), 5u);
  for (std::size_t i = 0; i < levels.size(); ++i) {
    EXPECT_EQ(j["points"][i]["level"], levels[i]);
    EXPECT_NEAR(j["points"][i]["luminance_cd_m2"].get<double>(), monitor_cd_m2(levels[i]), 0.0005);
  }
  EXPECT_NEAR(j.at("gamma").get<double>(), 2.4, 0.002);  // readings rounded to 0.001 cd/m2
  EXPECT_EQ(j.at("monitor").at("fullscreen"), false);
  EXPECT_EQ(j.at("monitor").at("framebuffer_px"), nlohmann::json({480, 320}));
  EXPECT_EQ(j.at("source"), "photometer readings typed in the window");
  fs::remove(out);
}

TEST_F(CalibrationGui, CheckerboardMatchGivesTheGammaOfTheMatchedLevel) {
  const fs::path out = fresh("board.json");
  {
    App app({"calibrate-display", "--checkerboard", "--windowed", "480x320", "-o", out.string()});
    ASSERT_TRUE(app.wait_for("grey level 128")) << app.output();
    ASSERT_TRUE(xdo(app, "key Prior Prior Prior Prior Prior Prior"));  // Page Up x 6: 188
    ASSERT_TRUE(app.wait_for("grey level 188")) << app.output();
    ASSERT_TRUE(xdo(app, "key Down Down"));
    ASSERT_TRUE(app.wait_for("grey level 186")) << app.output();
    xdo(app, "key Return");  // accepted: the window closes (xdotool may fail as it does)
    ASSERT_EQ(app.wait_exit(), 0) << app.output();
    EXPECT_NE(app.output().find("matched grey level 186\n"), std::string::npos) << app.output();
  }
  const nlohmann::json j = nlohmann::json::parse(slurp(out));
  EXPECT_EQ(j.at("method"), "checkerboard-match");
  EXPECT_EQ(j.at("model"), "gamma");
  EXPECT_EQ(j.at("matched_level"), 186);
  EXPECT_NEAR(j.at("gamma").get<double>(), std::log(0.5) / std::log(186.0 / 255.0), 1e-12);
  EXPECT_TRUE(j.at("points").empty());
  fs::remove(out);
  // Escape: nothing written, one line, exit 1.
  App app({"calibrate-display", "--checkerboard", "--windowed", "480x320", "-o", out.string()});
  ASSERT_TRUE(app.wait_for("grey level 128")) << app.output();
  ASSERT_TRUE(xdo(app, "key Up"));
  ASSERT_TRUE(app.wait_for("grey level 129")) << app.output();
  xdo(app, "key Escape");
  EXPECT_EQ(app.wait_exit(), 1);
  EXPECT_NE(app.output().find("penumbra-study: calibrate-display: stopped before a match was accepted; nothing written\n"), std::string::npos)
      << app.output();
  EXPECT_FALSE(fs::exists(out));
}

}  // namespace
