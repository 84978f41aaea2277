// penumbra-fit on sessions run in participants' browsers (penumbra-study serve, docs/study-online.md):
// written here by the lab's own Session writer as the server writes them (observer kind person,
// a presentation of kind "browser" with the virtual chinrest's numbers, online.json with the data
// quality), answered by a planted psychometric observer. The fit takes each participant's pixels
// per degree from the browser, prints and reports the data-quality table, excludes sessions only
// by --exclude-quality and names each excluded one with its reason; bad criteria are refused
// naming the option.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "io/atomic_file.h"
#include "observers/psychometric_observer.h"
#include "procedure/config.h"
#include "procedure/session.h"
#include "procedure/session_flow.h"
#include "fit_exe.h"

namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using namespace penumbra;

fs::path fresh(const std::string& name) { return test::fresh_dir("penumbra-fit-online-", name); }
int run(const std::string& args, std::string* output) { return test::run_fit(args, output); }

json read_json(const fs::path& p) {
  std::ifstream in(p);
  return json::parse(in);
}

// One round, three staircases of 30 trials: enough for a usable fit of a planted c.
procedure::StudyConfig short_config(const fs::path& dir) {
  const json config = {
      {"name", "online-fit"},
      {"task", "2afc"},
      {"artifact_px", {5, 10, 20}},
      {"rounds", {{{"pattern", "stair"}, {"contrast", 1.0}}}},
      {"quest", {{"t_guess", -0.5}, {"t_guess_sd", 1.0}, {"p_threshold", 0.82}, {"beta", 3.5}, {"delta", 0.01}, {"gamma", 0.5}, {"grain", 0.01}}},
      {"intensity_bounds", {-2.0, 1.0}},
      {"stopping", {{"min_trials", 30}, {"max_trials", 30}, {"sd_below", 0.1}}},
      {"seed", 1},
      {"round_order", "shuffled"},
      {"stimulus", {{"size_px", 320}, {"kernel", "disk"}}},
      {"display", {{"width_px", 1920}, {"height_px", 1080}, {"width_mm", 527}, {"height_mm", 296}, {"viewing_distance_mm", 600},
                   {"transfer", "srgb"}, {"monitor", 0}}}};
  std::ofstream(dir / "online-fit.json") << config.dump(2);
  return procedure::load_config(dir / "online-fit.json");
}

struct Browser {
  double viewing_distance_mm = 600;
  std::vector<double> blindspot_mm;  // the chinrest's readings
  int fullscreen_exits = 0, tab_switches = 0, page_loads = 1;
  double fast_fraction = 0;          // of trials answered in 60 ms (anticipations)
};

// The CSS pixels per degree the server computes from the chinrest, and the stimulus size it sends
// (here rounded to whole CSS pixels, so that the stimulus pixels per degree differ from the config's).
constexpr double kPxPerMm = 3.78;
double css_ppd(const Browser& b) { return 2.0 * b.viewing_distance_mm * std::tan(0.5 * M_PI / 180.0) * kPxPerMm; }
double stimulus_css_px(const procedure::StudyConfig& c, const Browser& b) {
  return std::round(c.stimulus_size_px * css_ppd(b) / c.display.pixels_per_degree());
}

// A browser session as penumbra-study serve writes it, answered by a planted observer (c = 3).
fs::path browser_session(const procedure::StudyConfig& config, const fs::path& sessions, const std::string& id, const Browser& b,
                         std::uint64_t seed) {
  const fs::path dir = sessions / id;
  const json extra = {{"observer_kind", "person"},
                      {"config_file", "online-fit.json"},
                      {"presentation_options", {{"kind", "browser"}, {"served_by", "penumbra-study serve"}}},
                      {"consent", procedure::consent_record(config.text("consent"), procedure::utc_now())}};
  procedure::Session session = procedure::Session::create(config, dir, id, extra);
  session.record_presentation({{"kind", "browser"},
                               {"px_per_mm", kPxPerMm},
                               {"viewing_distance_mm", b.viewing_distance_mm},
                               {"pixels_per_degree", css_ppd(b)},
                               {"stimulus_css_px", stimulus_css_px(config, b)},
                               {"window_css_px", {1280, 800}},
                               {"device_pixel_ratio", 1.25},
                               {"refresh_hz", 60},
                               {"screen_width_css_px", 1536},
                               {"screen_height_css_px", 864},
                               {"user_agent", "Mozilla/5.0 (X11; Linux x86_64) AppleWebKit/537.36 (KHTML, like Gecko) Chrome/131.0.0.0 Safari/537.36"},
                               {"chinrest", {{"px2mm", kPxPerMm}, {"view_dist_mm", b.viewing_distance_mm}, {"blindspot_distances_mm", b.blindspot_mm}}},
                               {"fits", true}});
  observers::PlantedModel planted;
  planted.c_true = 3.0;
  observers::PsychometricObserver observer({{"stair/1", planted}}, seed);
  int n = 0;
  while (const auto plan = session.next()) {
    const bool correct = observer.respond({session.condition(plan->round), plan->stimulus.artifact_px, plan->stimulus.filter_radius_px}).correct;
    const bool left = (plan->target == "left") == correct;
    // Every k-th trial an anticipation (60 ms), the rest about half a second.
    const int every = b.fast_fraction > 0 ? static_cast<int>(std::lround(1 / b.fast_fraction)) : 0;
    const double rt_ms = every > 0 && n % every == 0 ? 60.0 : 480.0 + 10.0 * (n % 7);
    session.record(*plan, left ? "left" : "right", rt_ms);
    ++n;
  }
  const json online = {{"intake", {{"answers", {{"age", "30"}, {"vision", "no"}}}}},
                       {"quality", {{"fullscreen_exits", b.fullscreen_exits}, {"tab_switches", b.tab_switches}, {"page_loads", b.page_loads},
                                    {"events", json::array()}}}};
  io::write_file_atomic(dir / "online.json", online.dump(2) + "\n");
  return dir;
}

struct Study {
  procedure::StudyConfig config;
  std::vector<fs::path> sessions;
  std::string args() const {
    std::string a;
    for (const fs::path& s : sessions) a += s.string() + " ";
    return a;
  }
};

// Four participants at 500-800 mm; P4 planted bad: seven tab switches, a fifth of its answers
// anticipations, a chinrest whose readings spread widely.
Study online_study(const fs::path& dir) {
  Study s{short_config(dir), {}};
  fs::create_directories(dir / "sessions");
  const std::vector<Browser> browsers = {
      {500, {495, 500, 505}, 0, 0, 1, 0}, {600, {590, 600, 610}, 1, 1, 2, 0}, {700, {690, 700, 710}, 0, 2, 1, 0},
      {800, {500, 800, 1100}, 1, 7, 1, 0.2}};
  for (std::size_t i = 0; i < browsers.size(); ++i)
    s.sessions.push_back(browser_session(s.config, dir / "sessions", "P" + std::to_string(i + 1), browsers[i], 11 + i));
  return s;
}

TEST(FitOnline, BrowserSessionsFitWithTheirOwnPixelsPerDegreeAndADataQualityTable) {
  const fs::path dir = fresh("ppd");
  const Study study = online_study(dir);
  std::string out;
  ASSERT_EQ(run(study.args() + "-o " + (dir / "fit").string() + " --bootstrap 0 --no-progress", &out), 0) << out;
  EXPECT_NE(out.find("calibration.json: entry pcf disk (people, 4 participants)"), std::string::npos) << out;
  const json report = read_json(dir / "fit" / "report.json");
  EXPECT_EQ(report["sessions"], 4);
  // Each participant's stimulus pixels per degree: the chinrest's CSS pixels per degree times the
  // stimulus pixels per CSS pixel the page showed, not the config's monitor (38.15).
  const std::vector<double> distances = {500, 600, 700, 800};
  const double config_ppd = study.config.display.pixels_per_degree();
  bool differs = false;
  for (std::size_t i = 0; i < distances.size(); ++i) {
    Browser b;
    b.viewing_distance_mm = distances[i];
    const double expected = css_ppd(b) * study.config.stimulus_size_px / stimulus_css_px(study.config, b);
    const std::string id = "P" + std::to_string(i + 1);
    EXPECT_NEAR(report["pixels_per_degree"][id].get<double>(), expected, 1e-9) << id;
    differs = differs || std::abs(expected - config_ppd) > 1e-3;
  }
  EXPECT_TRUE(differs) << "the test's rounding should make at least one participant's differ from the config's " << config_ppd;
  // The data quality, per session, in report.json ...
  const json& quality = report["data_quality"];
  ASSERT_EQ(quality["sessions"].size(), 4u) << quality.dump(1);
  EXPECT_TRUE(quality["criteria"].empty());
  EXPECT_TRUE(quality["excluded"].empty());
  const json& p4 = quality["sessions"][3];
  EXPECT_EQ(p4["participant"], "P4");
  EXPECT_EQ(p4["kind"], "browser");
  EXPECT_EQ(p4["browser"], "Chrome 131");
  EXPECT_EQ(p4["screen_css_px"], json({1536, 864}));
  EXPECT_EQ(p4["device_pixel_ratio"], 1.25);
  EXPECT_EQ(p4["refresh_hz"], 60);
  EXPECT_EQ(p4["tab_switches"], 7);
  EXPECT_EQ(p4["fullscreen_exits"], 1);
  EXPECT_EQ(p4["trials"], 90);
  EXPECT_EQ(p4["rt_fast"], 18);  // every fifth of 90 trials
  EXPECT_NEAR(p4["rt_outliers"].get<double>(), 0.2, 1e-12);
  EXPECT_NEAR(p4["chinrest_cv"].get<double>(), 300.0 / 800.0, 1e-12);  // readings 500, 800, 1100: sd 300
  EXPECT_NEAR(quality["sessions"][0]["chinrest_cv"].get<double>(), 5.0 / 500.0, 1e-12);
  EXPECT_EQ(quality["sessions"][0]["rt_outliers"], 0.0);
  // ... and as a table, printed and in summary.txt, saying that nothing was excluded.
  for (const std::string& text : {out, [&] {
         std::ifstream in(dir / "fit" / "summary.txt");
         return std::string(std::istreambuf_iterator<char>(in), {});
       }()}) {
    EXPECT_NE(text.find("data quality (per session"), std::string::npos) << text;
    EXPECT_NE(text.find("RT < 150 ms or > 3 x the session's median"), std::string::npos) << text;
    EXPECT_NE(text.find("exclusion criteria: none (--exclude-quality); every session is fitted"), std::string::npos) << text;
    EXPECT_EQ(text.find("EXCLUDED"), std::string::npos) << text;
  }
  fs::remove_all(dir);
}

TEST(FitOnline, APlantedBadSessionIsReportedAndExcludedWithItsReasonOnlyOnRequest) {
  const fs::path dir = fresh("exclude");
  const Study study = online_study(dir);
  std::string out;
  const std::string criteria = " --exclude-quality 'fullscreen_exits>2,tab_switches>3,rt_outliers>10%,chinrest_cv>0.1'";
  ASSERT_EQ(run(study.args() + "-o " + (dir / "fit").string() + " --bootstrap 0 --no-progress" + criteria, &out), 0) << out;
  const std::string reason = "EXCLUDED P4 (" + study.sessions[3].string() + "): tab_switches 7 > 3, rt_outliers 20.0 % > 10 %, chinrest_cv 0.375 > 0.1";
  EXPECT_NE(out.find(reason), std::string::npos) << out;
  EXPECT_NE(out.find("1 of 4 sessions excluded, 3 fitted"), std::string::npos) << out;
  EXPECT_NE(out.find("calibration.json: entry pcf disk (people, 3 participants)"), std::string::npos) << out;
  const json report = read_json(dir / "fit" / "report.json");
  EXPECT_EQ(report["sessions"], 3);
  EXPECT_FALSE(report["pixels_per_degree"].contains("P4"));
  EXPECT_EQ(report["inputs"].size(), 4u) << "the inputs as given, the excluded one among them";
  const json& quality = report["data_quality"];
  ASSERT_EQ(quality["excluded"].size(), 1u) << quality.dump(1);
  EXPECT_EQ(quality["excluded"][0]["participant"], "P4");
  EXPECT_EQ(quality["excluded"][0]["because"],
            json({"tab_switches 7 > 3", "rt_outliers 20.0 % > 10 %", "chinrest_cv 0.375 > 0.1"}));
  EXPECT_EQ(quality["criteria"].size(), 4u);
  EXPECT_EQ(quality["sessions"].size(), 4u) << "an excluded session stays in the table";
  EXPECT_TRUE(quality["sessions"][3]["excluded"].get<bool>());
  // Criteria every session fails: nothing to fit, one line, nothing written.
  ASSERT_EQ(run(study.args() + "-o " + (dir / "none").string() + " --bootstrap 0 --no-progress --exclude-quality 'page_loads>0'", &out), 1) << out;
  EXPECT_NE(out.find("penumbra-fit: every session is excluded by --exclude-quality page_loads>0"), std::string::npos) << out;
  EXPECT_FALSE(fs::exists(dir / "none"));
  fs::remove_all(dir);
}

TEST(FitOnline, BadQualityCriteriaAreRefusedNamingTheOption) {
  const fs::path dir = fresh("refuse");
  const Study study = online_study(dir);
  for (const std::string bad : {"tab_switches", "tab_switches>x", "tab_switches>-1", "tab_switches>1.5", "rt_outliers>10",
                                 "rt_outliers>100%", "chinrest_cv>0.1%", "speed>1", "tab_switches>1,tab_switches>2", "tab_switches>1,", "chinrest_cv> 0.1", "chinrest_cv>0x1", "chinrest_cv>inf", "chinrest_cv>1e-1",
                                 "''"}) {
    std::string out;
    EXPECT_EQ(run(study.sessions[0].string() + " -o " + (dir / "fit").string() + " --bootstrap 0 --no-progress --exclude-quality " +
                      (bad == "''" ? bad : "'" + bad + "'"),
                  &out),
              2)
        << bad << "\n" << out;
    EXPECT_EQ(out.rfind("penumbra-fit: --exclude-quality", 0), 0u) << bad << "\n" << out;
    EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 1) << bad << "\n" << out;
    EXPECT_FALSE(fs::exists(dir / "fit")) << bad;
  }
  fs::remove_all(dir);
}

}  // namespace
