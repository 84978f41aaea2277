// penumbra-study run --headless end to end: valid logs, convergence to the planted threshold,
// SIGKILL + --resume equal to an uninterrupted run, refusals with one clear line.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <functional>
#include <fstream>
#include <map>
#include <random>
#include <set>
#include <sstream>
#include <thread>

#include <nlohmann/json.hpp>

#include "log/directory_lock.h"
#include "log/trial_log.h"

namespace {

namespace fs = std::filesystem;
using namespace penumbra;

const std::string kExe = PENUMBRA_STUDY_EXE;
const std::string kConfig = PENUMBRA_DATA_DIR "/studies/default.json";
const std::string kObserver = "psychometric:c=3.0,beta=3.5,lapse=0.02";

fs::path fresh(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("penumbra-e2e-" + name + "-" + std::to_string(::getpid()));
  fs::remove_all(d);
  return d;
}

pid_t spawn(const std::vector<std::string>& args, const fs::path& capture) {
  const pid_t pid = fork();
  if (pid == 0) {
    const int fd = ::open(capture.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    dup2(fd, 1);
    dup2(fd, 2);
    std::vector<char*> argv;
    argv.push_back(const_cast<char*>(kExe.c_str()));
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    execv(kExe.c_str(), argv.data());
    _exit(127);
  }
  return pid;
}

int run(const std::vector<std::string>& args, std::string* output = nullptr) {
  const fs::path cap = fresh("capture");
  int status = 0;
  waitpid(spawn(args, cap), &status, 0);
  if (output) {
    std::ifstream in(cap);
    *output = std::string(std::istreambuf_iterator<char>(in), {});
  }
  fs::remove(cap);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// Rows without the two columns that differ between sessions (session_id, utc_time).
std::vector<std::string> comparable(const std::vector<trial_log::TrialRow>& rows) {
  std::vector<std::string> out;
  for (auto r : rows) {
    r.session_id = "-";
    r.utc_time = "-";
    out.push_back(trial_log::format_row(r));
  }
  return out;
}

TEST(StudyRun, HeadlessSimulationLogsValidRowsAndConvergesToThePlantedThreshold) {
  const fs::path dir = fresh("run");
  ASSERT_EQ(run({"run", "--config", kConfig, "--observer", kObserver, "--headless", "-o", dir.string()}), 0);
  const auto log = trial_log::read(dir / "trials.csv");  // validates every row against the schema
  ASSERT_GT(log.rows.size(), 100u);
  EXPECT_FALSE(log.torn_tail);
  std::map<std::string, std::vector<const trial_log::TrialRow*>> staircases;
  int practice = 0;
  for (std::size_t i = 0; i < log.rows.size(); ++i) {
    const auto& r = log.rows[i];
    EXPECT_EQ(r.trial, static_cast<int>(i));
    EXPECT_GE(r.filter_radius_px, 1.0);
    EXPECT_LE(r.filter_radius_px, 160.0);
    if (r.practice) {
      ++practice;
      continue;
    }
    staircases[std::to_string(r.condition_index) + "/" + r.staircase].push_back(&r);
  }
  EXPECT_EQ(practice, 4);
  ASSERT_EQ(staircases.size(), 12u);  // 4 rounds x 3 artifact sizes
  const double planted = -std::log10(3.0);
  std::vector<double> errors;
  int far = 0;
  for (const auto& [name, rows] : staircases) {
    const auto& last = *rows.back();
    EXPECT_GE(rows.size(), 10u) << name;
    EXPECT_LE(rows.size(), 40u) << name;
    if (rows.size() < 40) {
      EXPECT_LT(last.quest_sd, 0.1) << name;  // stopped by convergence
    }
    errors.push_back(last.quest_mean - planted);
    far += std::abs(errors.back()) > 0.3;
  }
  // QUEST (Psychtoolbox semantics, delta 0.01) against an observer with 2 % lapses: a miss or two at
  // the first, easy trials of a staircase can pin its posterior high until sd_below stops it there.
  // Measured over 7 participants' sessions (84 staircases): 3 ended more than 0.3 log units off, at
  // most one per session; the median error per session was within +-0.025.
  EXPECT_LE(far, 1);
  std::nth_element(errors.begin(), errors.begin() + 6, errors.end());
  EXPECT_NEAR(errors[6], 0.0, 0.05);  // no bias: the median of the 12 staircases
  const std::string json = [&] {
    std::ifstream in(dir / "session.json");
    return std::string(std::istreambuf_iterator<char>(in), {});
  }();
  EXPECT_NE(json.find("\"transfer\": \"srgb\""), std::string::npos);
  EXPECT_NE(json.find("\"p_threshold\": 0.82"), std::string::npos);
  fs::remove_all(dir);
}

// Issue 16: every participant gets another trial sequence and round order from the same config
// (the session seed comes from the config's seed and the participant id); the same participant, or
// the same --seed, replays identically; a --seed that contradicts a resumed session is refused.
TEST(StudyRun, EachParticipantGetsAnotherSequenceAndTheSameOneAgain) {
  auto session = [](const std::string& name, const std::vector<std::string>& extra) {
    const fs::path dir = fresh("rand-" + name);
    std::vector<std::string> args = {"run", "--config", kConfig, "--observer", kObserver, "--headless", "--stop-after", "60",
                                     "-o", dir.string()};
    args.insert(args.end(), extra.begin(), extra.end());
    std::string out;
    EXPECT_EQ(run(args, &out), 0) << out;
    const nlohmann::json json = nlohmann::json::parse(std::ifstream(dir / "session.json"));
    struct Session {
      std::vector<trial_log::TrialRow> rows;
      nlohmann::json randomization;
      fs::path dir;
    };
    return Session{trial_log::read(dir / "trials.csv").rows, json.at("randomization"), dir};
  };
  auto sides = [](const auto& rows) {
    std::string s;
    for (const auto& r : rows) s += r.target.substr(0, 1);
    return s;
  };
  auto seeds = [](const auto& rows) {
    std::vector<std::uint64_t> s;
    for (const auto& r : rows) s.push_back(r.stimulus_seed);
    return s;
  };
  const auto ann = session("ann", {"--participant", "ann"});
  const auto bob = session("bob", {"--participant", "bob"});
  const auto ann_again = session("ann2", {"--participant", "ann"});
  const auto seeded = session("seeded", {"--participant", "cid", "--seed", "12345"});
  const auto seeded_again = session("seeded2", {"--participant", "dee", "--seed", "12345"});
  ASSERT_EQ(ann.rows.size(), 60u);
  ASSERT_EQ(bob.rows.size(), 60u);
  EXPECT_EQ(ann.randomization.at("seed_from"), "participant");
  EXPECT_NE(ann.randomization.at("seed"), bob.randomization.at("seed"));
  EXPECT_NE(sides(ann.rows), sides(bob.rows));
  EXPECT_NE(seeds(ann.rows), seeds(bob.rows));
  // The same participant: the same seed, order, sides and edge phases (and so the same staircases).
  EXPECT_EQ(ann.randomization, ann_again.randomization);
  EXPECT_EQ(comparable(ann.rows), comparable(ann_again.rows));
  EXPECT_EQ(sides(ann.rows), sides(ann_again.rows));
  EXPECT_EQ(seeds(ann.rows), seeds(ann_again.rows));
  // --seed wins over the participant id and is recorded as such.
  EXPECT_EQ(seeded.randomization.at("seed"), 12345u);
  EXPECT_EQ(seeded.randomization.at("seed_from"), "--seed");
  EXPECT_EQ(seeds(seeded.rows), seeds(seeded_again.rows));
  EXPECT_EQ(seeded.randomization.at("round_order"), seeded_again.randomization.at("round_order"));
  // Round orders are shuffled per participant: across 12 participants the default config's four
  // rounds do not all start with the same one (a fixed order would).
  std::set<int> first_rounds;
  for (int i = 0; i < 12; ++i) {
    const fs::path dir = fresh("order-" + std::to_string(i));
    ASSERT_EQ(run({"run", "--config", kConfig, "--observer", kObserver, "--headless", "--stop-after", "1", "--participant",
                   "p" + std::to_string(i), "-o", dir.string()}),
              0);
    const nlohmann::json json = nlohmann::json::parse(std::ifstream(dir / "session.json"));
    const auto order = json.at("randomization").at("round_order").get<std::vector<int>>();
    ASSERT_EQ(std::set<int>(order.begin(), order.end()), (std::set<int>{0, 1, 2, 3}));
    first_rounds.insert(order.front());
    // Practice shows the first round's condition.
    const auto rows = trial_log::read(dir / "trials.csv").rows;
    ASSERT_EQ(rows.size(), 1u);
    EXPECT_EQ(rows[0].condition_index, order.front());
    fs::remove_all(dir);
  }
  EXPECT_GE(first_rounds.size(), 3u);
  // A resume keeps the recorded randomization and refuses a --seed that contradicts it.
  std::string out;
  EXPECT_EQ(run({"run", "--resume", seeded.dir.string(), "--headless", "--seed", "999"}, &out), 2) << out;  // the command line
  EXPECT_NE(out.find("--seed 999: the session was run with seed 12345"), std::string::npos) << out;
  EXPECT_EQ(run({"run", "--resume", seeded.dir.string(), "--headless", "--seed", "12345", "--stop-after", "70"}, &out), 0) << out;
  const auto resumed = trial_log::read(seeded.dir / "trials.csv").rows;
  ASSERT_EQ(resumed.size(), 70u);
  for (const auto* s : {&ann, &bob, &ann_again, &seeded, &seeded_again}) fs::remove_all(s->dir);
}

// Issue 16: display-check reports what the geometry means, and a config with geometry no lab has
// (non-square pixels, the eyes 5 mm from the screen, stimuli wider than the screen) is refused in
// one line by display-check and by run, before a session directory exists.
TEST(StudyRun, DisplayCheckReportsTheGeometryAndRefusesImplausibleOnes) {
  std::string out;
  ASSERT_EQ(run({"display-check", "--config", kConfig}, &out), 0) << out;
  // 1920 px over 527 mm at 600 mm: 2 * 600 * tan(0.5 deg) = 10.47 mm per degree = 38.15 px; 320 px
  // = 87.8 mm = 8.37 deg; 10 px = 2.745 mm = 15.73 arcmin.
  EXPECT_NE(out.find("38.2 px per degree"), std::string::npos) << out;
  EXPECT_NE(out.find("stimulus: 320 px = 8.37 deg"), std::string::npos) << out;
  EXPECT_NE(out.find("10 px = 15.73 arcmin"), std::string::npos) << out;
  struct Case {
    std::string display_or_stimulus, says;
  };
  const Case cases[] = {
      {R"("display": {"height_mm": 100})", "display.height_mm: pixels 0.33"},
      {R"("display": {"viewing_distance_mm": 5})", "display.viewing_distance_mm: expected at least 200 mm"},
      {R"("display": {"width_px": 600, "height_px": 338, "width_mm": 527, "height_mm": 296})", "stimulus.size_px: 320 px twice side by side does not fit"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.display_or_stimulus);
    const fs::path config = fresh("geometry.json");
    std::ofstream(config) << R"({"rounds": [{"pattern": "stair"}], )" << c.display_or_stimulus << "}";
    for (const bool as_run : {false, true}) {
      const fs::path dir = fresh("geometry-session");
      std::vector<std::string> args = as_run ? std::vector<std::string>{"run", "--config", config.string(), "--headless", "-o", dir.string()}
                                             : std::vector<std::string>{"display-check", "--config", config.string()};
      EXPECT_EQ(run(args, &out), 1) << out;
      EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 1) << out;
      EXPECT_NE(out.find(config.string() + ": " + c.says), std::string::npos) << out;
      EXPECT_FALSE(fs::exists(dir));
    }
    fs::remove(config);
  }
}

TEST(StudyRun, SigkillAtARandomTrialThenResumeEqualsAnUninterruptedRun) {
  const fs::path whole = fresh("whole"), killed = fresh("killed");
  ASSERT_EQ(run({"run", "--config", kConfig, "--observer", kObserver, "--headless", "-o", whole.string()}), 0);
  const auto reference = trial_log::read(whole / "trials.csv").rows;

  std::mt19937 rng(static_cast<unsigned>(std::random_device{}()));
  const std::size_t kill_after = 5 + rng() % (reference.size() - 10);
  const fs::path cap = fresh("kill-capture");
  const pid_t pid = spawn({"run", "--config", kConfig, "--observer", kObserver, "--headless", "-o", killed.string(),
                           "--pace-ms", "3"},
                          cap);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  std::size_t lines = 0;
  while (std::chrono::steady_clock::now() < deadline) {
    std::ifstream in(killed / "trials.csv");
    lines = static_cast<std::size_t>(std::count(std::istreambuf_iterator<char>(in), {}, '\n'));
    if (lines >= kill_after + 1) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  ASSERT_EQ(kill(pid, SIGKILL), 0);
  int status = 0;
  waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFSIGNALED(status)) << "the run finished before it could be killed";
  const auto before = trial_log::read(killed / "trials.csv");
  EXPECT_GE(before.rows.size(), kill_after) << "completed trials were lost";
  ASSERT_LT(before.rows.size(), reference.size());

  std::string out;
  ASSERT_EQ(run({"run", "--resume", killed.string(), "--observer", kObserver, "--headless"}, &out), 0) << out;
  const auto resumed = trial_log::read(killed / "trials.csv");
  EXPECT_EQ(comparable(resumed.rows), comparable(reference)) << "killed after " << before.rows.size() << " trials";
  fs::remove_all(whole);
  fs::remove_all(killed);
  fs::remove(cap);
}

// yes/no: half the trials show the straight edge; only the jagged ones feed QUEST (its guess rate
// is the false-alarm rate), and the staircases still find the planted threshold.
TEST(StudyRun, HeadlessYesNoFeedsQuestTheJaggedTrialsAndConverges) {
  const std::string config = PENUMBRA_DATA_DIR "/studies/default-yesno.json";  // no quest block: yesno defaults
  const fs::path dir = fresh("yesno");
  std::string out;
  ASSERT_EQ(run({"run", "--config", config, "--observer", kObserver + ",fa=0.05", "--headless", "-o", dir.string()},
                &out),
            0)
      << out;
  const auto rows = trial_log::read(dir / "trials.csv").rows;
  std::map<std::string, std::vector<const trial_log::TrialRow*>> jagged;
  std::map<std::string, double> last_mean;
  int straight = 0, false_alarms = 0;
  for (const auto& r : rows) {
    EXPECT_EQ(r.task, "yesno");
    ASSERT_TRUE(r.target == "jagged" || r.target == "straight") << r.target;
    ASSERT_TRUE(r.response == "yes" || r.response == "no") << r.response;
    EXPECT_EQ(r.correct, (r.response == "yes") == (r.target == "straight") ? 1 : 0);
    if (r.practice) continue;
    const std::string key = std::to_string(r.condition_index) + "/" + r.staircase;
    if (r.target == "straight") {
      ++straight;
      false_alarms += r.response == "no";
      if (last_mean.count(key)) {
        EXPECT_EQ(r.quest_mean, last_mean[key]) << "a straight trial moved QUEST";
      }
    } else {
      jagged[key].push_back(&r);
    }
    last_mean[key] = r.quest_mean;
  }
  ASSERT_EQ(jagged.size(), 12u);
  ASSERT_GT(straight, 100);
  EXPECT_NEAR(static_cast<double>(false_alarms) / straight, 0.05, 0.04);
  const double planted = -std::log10(3.0);
  double sum_error = 0;
  for (const auto& [name, js] : jagged) {
    EXPECT_GE(js.size(), 10u) << name;  // the stopping rule counts QUEST (jagged) trials
    EXPECT_LE(js.size(), 40u) << name;
    EXPECT_NEAR(js.back()->quest_mean, planted, 0.3) << name;
    sum_error += js.back()->quest_mean - planted;
  }
  EXPECT_NEAR(sum_error / 12, 0.0, 0.1);
  std::ifstream in(dir / "session.json");
  const std::string json(std::istreambuf_iterator<char>(in), {});
  EXPECT_NE(json.find("\"gamma\": 0.05"), std::string::npos);
  EXPECT_NE(json.find("\"p_threshold\": 0.658"), std::string::npos);
  fs::remove_all(dir);
}

TEST(StudyRun, RefusesToOverwriteASessionAndBadConfigsInOneLine) {
  const fs::path dir = fresh("refuse");
  ASSERT_EQ(run({"run", "--config", kConfig, "--headless", "-o", dir.string()}), 0);
  const auto size = fs::file_size(dir / "trials.csv");
  std::string out;
  EXPECT_EQ(run({"run", "--config", kConfig, "--headless", "-o", dir.string()}, &out), 1);
  EXPECT_EQ(out, "penumbra-study: " + dir.string() + ": already holds a session; refusing to overwrite it (use --resume)\n");
  EXPECT_EQ(fs::file_size(dir / "trials.csv"), size);

  const fs::path bad = fresh("bad.json");
  std::ofstream(bad) << R"({"rounds": [{"pattern": "stair"}], "stopping": {"sd_below": "small"}})";
  EXPECT_EQ(run({"run", "--config", bad.string(), "--headless", "-o", fresh("never").string()}, &out), 1);
  EXPECT_EQ(out, "penumbra-study: " + bad.string() + ": stopping.sd_below: expected a number, got \"small\"\n");
  EXPECT_FALSE(fs::exists(fresh("never")));
  // round_order latin-square takes the row from the number the participant id ends in.
  std::ofstream(bad) << R"({"rounds": [{"pattern": "stair"}, {"pattern": "step"}], "round_order": "latin-square"})";
  EXPECT_EQ(run({"run", "--config", bad.string(), "--headless", "--participant", "alice", "-o", fresh("never").string()}, &out), 1);
  EXPECT_EQ(out, "penumbra-study: round_order latin-square: participant 'alice' ends in no number to choose its row of the "
                 "square (use ids like p1, p2, ...)\n");
  EXPECT_FALSE(fs::exists(fresh("never")));
  // The stimulus technique is checked against the renderer's tables before the directory exists.
  for (const auto& [stimulus, says] : std::vector<std::pair<std::string, std::string>>{
           {R"({"technique": "pcss"})", "stimulus.technique: 'pcss' has no fixed filter radius for the trial to set (pcf, vsm, rpcf, msm, evsm and esm have)"},
           {R"({"technique": "pcf", "settings": {"pcf.kernel": "poisson", "pcf.rotate": true}})",
            "stimulus.settings.pcf.rotate: a disk rotated per pixel has no partner here (set it false)"},
           {R"({"technique": "pcf", "settings": {"pcf.kernel": "grid", "pcf.kernal": "grid"}})", "stimulus.settings.pcf.kernal: no such setting"},
           {R"({"technique": "pcf", "settings": {"pcf.kernel": "grid", "pcf.radius": 2}})",
            "stimulus.settings.pcf.radius: set by the study from the trial's filter radius"}}) {
    std::ofstream(bad) << R"({"rounds": [{"pattern": "stair"}], "stimulus": )" << stimulus << "}";
    EXPECT_EQ(run({"run", "--config", bad.string(), "--headless", "-o", fresh("never").string()}, &out), 1);
    EXPECT_EQ(out, "penumbra-study: " + bad.string() + ": " + says + "\n");
    EXPECT_FALSE(fs::exists(fresh("never")));
  }
  fs::remove_all(dir);
  fs::remove(bad);
}

std::string bytes_of(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// Sessions whose stimuli the renderer's techniques draw, answered by the image observer (which
// looks at every pair): session.json records the technique, the log the kernel.
class RendererDrawnStimuli : public ::testing::TestWithParam<std::string> {};

TEST_P(RendererDrawnStimuli, RunASession) {
  const std::string name = GetParam();
  const fs::path dir = fresh(name);
  nlohmann::json config = nlohmann::json::parse(bytes_of(PENUMBRA_DATA_DIR "/studies/" + name + ".json"));
  config["rounds"] = {{{"pattern", "stair"}, {"contrast", 1.0}}};
  config["artifact_px"] = {10};
  config["practice_trials"] = 0;
  config["stopping"] = {{"min_trials", 6}, {"max_trials", 6}, {"sd_below", 0.1}};
  config["stimulus"]["size_px"] = 96;
  const fs::path file = fresh(name + ".json");
  std::ofstream(file) << config.dump();
  std::string out;
  ASSERT_EQ(run({"run", "--config", file.string(), "--observer", "image", "--headless", "-o", dir.string()}, &out), 0) << out;
  const nlohmann::json session = nlohmann::json::parse(bytes_of(dir / "session.json"));
  EXPECT_EQ(session["config"]["stimulus"]["technique"], name == "pcf-grid" ? "pcf" : name);
  if (name == "pcf-grid") {
    EXPECT_EQ(session["config"]["stimulus"]["settings"]["pcf.kernel"], "grid");
  }
  const auto rows = trial_log::read(dir / "trials.csv").rows;
  ASSERT_EQ(rows.size(), 6u);
  for (const auto& r : rows) EXPECT_EQ(r.kernel, "grid");  // PCF's grid; RPCF's box and VSM's box blur
  fs::remove_all(dir);
  fs::remove(file);
}

INSTANTIATE_TEST_SUITE_P(Techniques, RendererDrawnStimuli, ::testing::Values("pcf-grid", "vsm", "rpcf"),
                         [](const ::testing::TestParamInfo<std::string>& p) {
                           std::string n = p.param;
                           std::replace(n.begin(), n.end(), '-', '_');
                           return n;
                         });

// What scripts/predict-calibration.sh predicts by default comes from the registry: every PCF
// kernel, RPCF and the filtered-moments techniques, never a technique without a partner (hard,
// PCSS, the screen-space ones).
TEST(ObserverCurve, ListsTheTechniquesTheStudyCanDraw) {
  const fs::path out = fresh("list.txt");
  ASSERT_EQ(std::system((std::string(PENUMBRA_OBSERVER_CURVE_EXE) + " --list-techniques > " + out.string()).c_str()), 0);
  std::istringstream lines(bytes_of(out));
  std::set<std::string> listed;
  for (std::string line; std::getline(lines, line);) EXPECT_TRUE(listed.insert(line).second) << line << " twice";
  for (const char* drawn : {"pcf:pcf.kernel=grid", "pcf:pcf.kernel=poisson", "pcf:pcf.kernel=disk", "rpcf", "vsm", "msm", "evsm", "esm"})
    EXPECT_TRUE(listed.contains(drawn)) << drawn;
  for (const char* not_drawn : {"hard", "pcss", "edtsm", "edtssm", "erosion", "rbsm", "pcf"}) EXPECT_FALSE(listed.contains(not_drawn)) << not_drawn;
}

// The published orderings with the image observer on stimuli the renderer's PCF grid draws (issue
// 15), never tuned for: at every artifact size the step needs a larger filter than the stair. The
// stair's radii at a = 10 and 20 px (published: ~25 px and >= 50 px) are printed, not bounded;
// the model's are ~11 and ~22 px (docs/results/study.md). The --json output is a calibration.json the
// renderer reads.
TEST(ObserverCurve, StepNeedsALargerFilterThanTheStairOnTheRenderersPcf) {
  const fs::path out = fresh("observer-curve.json");
  const std::string command = std::string(PENUMBRA_OBSERVER_CURVE_EXE) +
                              " --technique pcf --set pcf.kernel=grid --pattern stair,step --artifact-px 10,20 --ratio-min 0.7"
                              " --ratio-max 6 --ratio-step 1.15 --seeds 2 --json " + out.string() + " > /dev/null";
  ASSERT_EQ(std::system(command.c_str()), 0);
  const nlohmann::json file = nlohmann::json::parse(bytes_of(out));
  const nlohmann::json& entry = file["entries"][0];
  EXPECT_EQ(entry["technique"], "pcf");
  EXPECT_EQ(entry["kernel"], "grid");
  EXPECT_EQ(entry["obtained_by"], "image-observer");
  std::map<std::string, std::map<double, double>> c;  // condition -> a -> c
  for (const auto& condition : entry["per_condition"])
    for (const auto& per : condition["per_artifact"]) {
      ASSERT_TRUE(per["c"].is_number()) << condition;
      c[condition["condition"].get<std::string>()][per["artifact_px"].get<double>()] = per["c"].get<double>();
    }
  for (const double a : {10.0, 20.0}) {
    EXPECT_GT(c["step/1"][a], c["stair/1"][a]) << "a = " << a;
    std::printf("a = %g px: stair r = %.1f px (published ~%s), step r = %.1f px\n", a, c["stair/1"][a] * a,
                a == 10 ? "25" : ">= 50", c["step/1"][a] * a);
  }
  EXPECT_EQ(entry["c"], std::max(entry["per_condition"][0]["c"], entry["per_condition"][1]["c"]));
  // Two stimuli per radius: the interval is a bootstrap over them, so it has width and holds c.
  for (const auto& condition : entry["per_condition"]) {
    const double lo = condition["ci95"][0], hi = condition["ci95"][1], value = condition["c"];
    EXPECT_LE(lo, value) << condition["condition"];
    EXPECT_GE(hi, value) << condition["condition"];
    EXPECT_LT(lo, hi) << condition["condition"];
  }
  EXPECT_LE(entry["ci95"][0].get<double>(), entry["c"].get<double>());
  EXPECT_GE(entry["ci95"][1].get<double>(), entry["c"].get<double>());
  EXPECT_EQ(entry["observer"]["seeds"], 2);
  fs::remove(out);
}

// The frame observer (renderer/metrics/frame_observer.h) on the study's own step, the jagged
// image against the straight one: its weber was set so that its threshold at a = 10 px equals the
// image observer's there (3.43 a, docs/results/frame-observer.md); at a = 5 it was not fitted and
// stays near (3.56 a). Fails if the observer's model or its calibration moves.
TEST(ObserverCurve, TheFrameObserverHoldsItsCalibrationOnTheStep) {
  const fs::path out = fresh("frame-observer.json");
  const std::string command = std::string(PENUMBRA_OBSERVER_CURVE_EXE) +
                              " --observer frame --pattern step --artifact-px 5,10 --ratio-min 2.5 --ratio-max 5"
                              " --ratio-step 1.08 --seeds 3 --json " + out.string() + " > /dev/null";
  ASSERT_EQ(std::system(command.c_str()), 0);
  const nlohmann::json entry = nlohmann::json::parse(bytes_of(out))["entries"][0];
  EXPECT_EQ(entry["observer"]["kind"], "frame");
  std::map<double, double> c;
  for (const auto& per : entry["per_condition"][0]["per_artifact"]) {
    ASSERT_TRUE(per["c"].is_number()) << per;
    c[per["artifact_px"].get<double>()] = per["c"].get<double>();
  }
  EXPECT_NEAR(c[10.0], 3.43, 0.1);
  EXPECT_NEAR(c[5.0], 3.56, 0.2);
  fs::remove(out);
}

std::string bytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// Issue 14.2: two resumes of one directory at once both exited 0 and interleaved their rows. The
// directory lock refuses the second before it reads or writes a byte, naming the holder's pid.
TEST(StudyRun, ASessionDirectoryIsOwnedByOneProcess) {
  const fs::path dir = fresh("locked");
  ASSERT_EQ(run({"run", "--config", kConfig, "--observer", kObserver, "--headless", "-o", dir.string(),
                 "--stop-after", "20"}),
            0);
  const std::string log = bytes(dir / "trials.csv"), json = bytes(dir / "session.json");
  std::string out;
  {
    const trial_log::DirectoryLock held(dir);
    EXPECT_EQ(run({"run", "--resume", dir.string(), "--observer", kObserver, "--headless"}, &out), 1);
    EXPECT_EQ(out, "penumbra-study: " + dir.string() + ": in use by another process (pid " +
                       std::to_string(::getpid()) + "); refusing to touch it\n");
    EXPECT_EQ(bytes(dir / "trials.csv"), log);
    EXPECT_EQ(bytes(dir / "session.json"), json);
  }
  // A real second process: the first resume holds the directory while it runs.
  const fs::path cap = fresh("locked-capture");
  const pid_t first = spawn({"run", "--resume", dir.string(), "--observer", kObserver, "--headless", "--pace-ms", "20"},
                            cap);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (bytes(dir / "trials.csv").size() == log.size() && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  EXPECT_EQ(run({"run", "--resume", dir.string(), "--observer", kObserver, "--headless"}, &out), 1);
  EXPECT_NE(out.find("(pid " + std::to_string(first) + ")"), std::string::npos) << out;
  EXPECT_EQ(run({"run", "--config", kConfig, "--headless", "-o", dir.string()}, &out), 1);
  EXPECT_NE(out.find("in use by another process"), std::string::npos) << out;
  ASSERT_EQ(kill(first, SIGKILL), 0);
  int status = 0;
  waitpid(first, &status, 0);
  // The kernel dropped the dead process's lock: resuming finishes the session, every trial once.
  ASSERT_EQ(run({"run", "--resume", dir.string(), "--observer", kObserver, "--headless"}, &out), 0) << out;
  const auto rows = trial_log::read(dir / "trials.csv").rows;
  for (std::size_t i = 0; i < rows.size(); ++i) ASSERT_EQ(rows[i].trial, static_cast<int>(i));
  fs::remove_all(dir);
  fs::remove(cap);
}

int lines_of(const std::string& s) { return static_cast<int>(std::count(s.begin(), s.end(), '\n')); }

// Issue 14.3 and 14.5: resume trusted session.json (an edited participant, display, seed or QUEST
// block was carried into the continued rows; a huge or deeply nested file made it allocate without
// bound), and a refused resume had already cut the torn tail of the log.
TEST(StudyRun, ResumeRefusesAnEditedSessionJsonAndLeavesEveryByte) {
  const fs::path dir = fresh("edited");
  ASSERT_EQ(run({"run", "--config", kConfig, "--observer", kObserver, "--headless", "-o", dir.string(),
                 "--stop-after", "30"}),
            0);
  { std::ofstream(dir / "trials.csv", std::ios::app) << "torn,half a ro"; }  // the trial on screen at a kill
  const std::string log = bytes(dir / "trials.csv"), original = bytes(dir / "session.json");
  const nlohmann::json j = nlohmann::json::parse(original);
  auto edited = [&](const std::function<void(nlohmann::json&)>& edit) {
    nlohmann::json e = j;
    edit(e);
    return e.dump(2);
  };
  const std::string deep = [&] {
    std::string nest(100000, '[');
    nest += std::string(100000, ']');
    std::string t = original;
    t.replace(t.find("\"resumed_utc\": []"), 17, "\"resumed_utc\": " + nest);
    return t;
  }();
  const std::string duplicate = [&] {
    std::string t = original;
    t.insert(t.find("\"participant\""), "\"participant\": \"other\",\n  ");
    return t;
  }();
  const std::vector<std::pair<std::string, std::string>> cases = {
      // Issue 16: the session's seed is derived from the participant id, so an edited participant
      // (or config seed) no longer matches the recorded seed.
      {edited([](nlohmann::json& e) { e["participant"] = "other"; }),
       "session.json: randomization.seed: not the seed of participant 'other' with the config's seed 1"},
      {edited([](nlohmann::json& e) {
         e["config"]["display"]["viewing_distance_mm"] = 650;
         e["display"]["viewing_distance_mm"] = 650;
       }),
       "column 'artifact_arcmin'"},
      // Issue 16: a display no lab has is refused as the config is read.
      {edited([](nlohmann::json& e) {
         e["config"]["display"]["width_mm"] = 52.7;
         e["display"]["width_mm"] = 52.7;
       }),
       "session.json (config): display.height_mm: pixels 9.98"},
      {edited([](nlohmann::json& e) {
         e["config"]["seed"] = 2;
         e["seed"] = 2;
       }),
       "session.json: randomization.seed: not the seed of participant 'sim' with the config's seed 2"},
      {edited([](nlohmann::json& e) {
         e["randomization"]["seed_from"] = "--seed";
         e["randomization"]["seed"] = 2;
       }),
       "trials.csv:2: column '"},
      {edited([](nlohmann::json& e) { e["randomization"]["round_order"] = {0, 0, 1, 2}; }),
       "session.json: randomization.round_order: expected each of the config's 4 rounds"},
      {edited([](nlohmann::json& e) {
         e["config"]["quest"]["beta"] = 2.5;
         e["quest"]["beta"] = 2.5;
       }),
       "column 'quest_mean'"},
      {edited([](nlohmann::json& e) { e["quest"]["beta"] = 2.5; }), "session.json: quest.beta: differs from the config's QUEST"},
      {edited([](nlohmann::json& e) { e["seed"] = 2; }), "session.json: seed: expected the config's seed (1)"},
      {edited([](nlohmann::json& e) { e["participant"] = std::string(300, 'p'); }), "session.json: participant: expected a string of at most 200 bytes, got 300"},
      {edited([](nlohmann::json& e) { e["participant"] = std::string(10 << 20, 'p'); }), "session.json: larger than"},
      {edited([](nlohmann::json& e) { e["ended_rounds"] = {{{"round", 9}, {"after_trial", 3}}}; }), "ended_rounds[0]"},
      {edited([](nlohmann::json& e) { e.erase("config"); }), "session.json: config: missing"},
      {deep, "session.json: resumed_utc[0][0][0][0][0][0][0]: nested deeper than 8 levels"},
      {duplicate, "session.json: participant: duplicate key"},
  };
  for (const auto& [text, expected] : cases) {
    { std::ofstream(dir / "session.json", std::ios::trunc) << text; }
    std::string out;
    EXPECT_EQ(run({"run", "--resume", dir.string(), "--headless"}, &out), 1) << expected;
    EXPECT_NE(out.find(expected), std::string::npos) << out.substr(0, 300);
    EXPECT_EQ(lines_of(out), 1) << out.substr(0, 300);
    EXPECT_LT(out.size(), 600u) << expected;
    EXPECT_EQ(bytes(dir / "trials.csv"), log) << expected;
    EXPECT_EQ(bytes(dir / "session.json"), text) << expected;
  }
  // The untouched session.json resumes: the torn tail is cut, and the session finishes.
  { std::ofstream(dir / "session.json", std::ios::trunc) << original; }
  std::string out;
  ASSERT_EQ(run({"run", "--resume", dir.string(), "--headless"}, &out), 0) << out;
  const auto rows = trial_log::read(dir / "trials.csv");
  EXPECT_FALSE(rows.torn_tail);
  EXPECT_GT(rows.rows.size(), 100u);
  fs::remove_all(dir);
}

// Issue 14.4 and the resume half of 14.8: a session started with c=8 and resumed without
// --observer went on with the default c=3. The observer and its seed come from session.json; an
// option that contradicts the recorded run is refused, and so is --config beside --resume.
TEST(StudyRun, ResumeRestoresTheRecordedObserverAndRefusesContradictions) {
  const std::string observer = "psychometric:c=8,beta=3.5,lapse=0.02";
  const fs::path whole = fresh("observer-whole"), dir = fresh("observer");
  ASSERT_EQ(run({"run", "--config", kConfig, "--observer", observer, "--observer-seed", "11", "--headless", "-o",
                 whole.string()}),
            0);
  ASSERT_EQ(run({"run", "--config", kConfig, "--observer", observer, "--observer-seed", "11", "--headless", "-o",
                 dir.string(), "--stop-after", "40"}),
            0);
  const std::string log = bytes(dir / "trials.csv"), json = bytes(dir / "session.json");
  const std::vector<std::pair<std::vector<std::string>, std::string>> refused = {
      {{"--observer", kObserver}, "--observer '" + kObserver + "': the session was run with '" + observer + "'"},
      {{"--observer-seed", "7"}, "--observer-seed 7: the session was run with 11"},
      {{"--config", kConfig}, "--config: not with --resume"},
      {{"--participant", "someone"}, "--participant 'someone': the session is 'sim'"},
  };
  for (const auto& [options, expected] : refused) {
    std::vector<std::string> args = {"run", "--resume", dir.string(), "--headless"};
    args.insert(args.end(), options.begin(), options.end());
    std::string out;
    EXPECT_EQ(run(args, &out), 2) << expected;  // an option that contradicts the session: the command line
    EXPECT_NE(out.find(expected), std::string::npos) << out;
    EXPECT_EQ(lines_of(out), 1) << out;
    EXPECT_EQ(bytes(dir / "trials.csv"), log);
    EXPECT_EQ(bytes(dir / "session.json"), json);
  }
  std::string out;
  ASSERT_EQ(run({"run", "--resume", dir.string(), "--headless"}, &out), 0) << out;
  EXPECT_EQ(comparable(trial_log::read(dir / "trials.csv").rows), comparable(trial_log::read(whole / "trials.csv").rows));
  fs::remove_all(whole);
  fs::remove_all(dir);
}

// Issue 44: a lab measures the kernel its engine filters with. `run --kernel grid` on the lab's
// config (drawn with disk) draws grid: session.json's config and the log's kernel column say so, a
// resume keeps it (and takes the same --kernel), a different one is refused in one line (exit 2)
// leaving every byte, and so is --kernel for a technique without kernels or a kernel with no name.
TEST(StudyRun, TheKernelOptionIsTheSessionsKernelThroughResume) {
  const fs::path dir = fresh("kernel");
  const std::string lab = PENUMBRA_DATA_DIR "/studies/default-lab.json";
  std::string out;
  ASSERT_EQ(run({"run", "--config", lab, "--kernel", "grid", "--headless", "--stop-after", "30", "-o", dir.string()}, &out), 0) << out;
  auto kernel_of = [&] { return nlohmann::json::parse(bytes(dir / "session.json"))["config"]["stimulus"]["kernel"]; };
  EXPECT_EQ(kernel_of(), "grid");
  const auto first = trial_log::read(dir / "trials.csv").rows;
  ASSERT_EQ(first.size(), 30u);
  for (const auto& r : first) EXPECT_EQ(r.kernel, "grid") << r.trial;

  const std::string log = bytes(dir / "trials.csv"), json = bytes(dir / "session.json");
  ASSERT_EQ(run({"run", "--resume", dir.string(), "--headless", "--kernel", "disk"}, &out), 2) << out;
  EXPECT_NE(out.find("--kernel disk: the session was run with the grid kernel (session.json)"), std::string::npos) << out;
  EXPECT_EQ(lines_of(out), 1) << out;
  EXPECT_EQ(bytes(dir / "trials.csv"), log);
  EXPECT_EQ(bytes(dir / "session.json"), json);

  ASSERT_EQ(run({"run", "--resume", dir.string(), "--headless", "--stop-after", "60"}, &out), 0) << out;
  ASSERT_EQ(run({"run", "--resume", dir.string(), "--headless", "--kernel", "grid"}, &out), 0) << out;
  EXPECT_EQ(kernel_of(), "grid");
  const auto rows = trial_log::read(dir / "trials.csv").rows;
  ASSERT_GT(rows.size(), 60u);
  for (const auto& r : rows) EXPECT_EQ(r.kernel, "grid") << r.trial;

  // A config drawn by the renderer's PCF: its pcf.kernel setting is replaced.
  const fs::path drawn = fresh("kernel-drawn");
  ASSERT_EQ(run({"run", "--config", PENUMBRA_DATA_DIR "/studies/pcf-poisson.json", "--kernel", "grid", "--headless", "--stop-after", "5", "-o", drawn.string()}, &out), 0)
      << out;
  const nlohmann::json stimulus = nlohmann::json::parse(bytes(drawn / "session.json"))["config"]["stimulus"];
  EXPECT_EQ(stimulus["technique"], "pcf");
  EXPECT_EQ(stimulus["settings"]["pcf.kernel"], "grid");
  for (const auto& r : trial_log::read(drawn / "trials.csv").rows) EXPECT_EQ(r.kernel, "grid") << r.trial;

  for (const auto& [args, says] : std::vector<std::pair<std::vector<std::string>, std::string>>{
           {{"--config", PENUMBRA_DATA_DIR "/studies/vsm.json", "--kernel", "grid"}, "penumbra-study: --kernel grid: the stimuli are drawn by vsm, which has no kernel"},
           {{"--config", lab, "--kernel", "box"}, "penumbra-study: --kernel: kernel 'box': expected disk, grid or poisson"}}) {
    const fs::path never = fresh("kernel-never");
    std::vector<std::string> full = {"run", "--headless", "-o", never.string()};
    full.insert(full.end(), args.begin(), args.end());
    EXPECT_EQ(run(full, &out), 2) << out;
    EXPECT_EQ(out.rfind(says, 0), 0u) << out;
    EXPECT_EQ(lines_of(out), 1) << out;
    EXPECT_FALSE(fs::exists(never));
  }
  // A resumed session drawn by a technique without kernels refuses it as well.
  const fs::path boxed = fresh("kernel-boxed");
  ASSERT_EQ(run({"run", "--config", PENUMBRA_DATA_DIR "/studies/rpcf.json", "--headless", "--stop-after", "2", "-o", boxed.string()}, &out), 0) << out;
  EXPECT_EQ(run({"run", "--resume", boxed.string(), "--headless", "--kernel", "grid"}, &out), 2) << out;
  EXPECT_EQ(out.rfind("penumbra-study: --kernel grid: the stimuli are drawn by rpcf, which has no kernel", 0), 0u) << out;
  fs::remove_all(dir);
  fs::remove_all(drawn);
  fs::remove_all(boxed);
}

// Issue 14.6: a rejected --observer created the session directory (session.json and a header-only
// log), so the same -o was refused afterwards.
TEST(StudyRun, ARejectedObserverCreatesNothing) {
  const fs::path dir = fresh("rejected-observer");
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"psychometric:c=-1", "--observer: c_true must be positive"},
      {"psychometric:c=nan", "--observer: 'c=nan': expected a finite number"},
      {"psychometric:c=3x", "--observer: 'c=3x': expected a finite number"},
      {"psychometric:lapse=0.7", "--observer: lapse: expected a rate in [0, 1 - guess)"},
      {"psychometric:fa=0.9", "--observer: fa: expected a rate in (0, 0.5)"},
      {"psychometric:gain=2", "--observer: unknown parameter 'gain'"},
      {"image:noise=-1", "--observer: noise: expected a number >= 0"},
      {"bogus", "--observer 'bogus': expected psychometric"},
  };
  for (const auto& [observer, expected] : cases) {
    std::string out;
    EXPECT_EQ(run({"run", "--config", kConfig, "--observer", observer, "--headless", "-o", dir.string()}, &out), 2)
        << observer;
    EXPECT_NE(out.find("penumbra-study: " + expected), std::string::npos) << out;
    EXPECT_EQ(lines_of(out), 1) << out;
    EXPECT_FALSE(fs::exists(dir)) << observer;
  }
  EXPECT_EQ(run({"run", "--config", kConfig, "--observer", kObserver, "--headless", "-o", dir.string(), "--stop-after",
                 "5"}),
            0);
  fs::remove_all(dir);
}

// Issue 14.8: NaN passed range checks and negative seeds, paces and stop counts were taken (a
// seed of -1 became 2^64 - 1). Each is refused before anything is created.
TEST(StudyRun, NaNAndNegativeOptionsAreRefusedBeforeAnythingIsCreated) {
  const fs::path dir = fresh("negative");
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{"run", "--config", kConfig, "--headless", "-o", dir.string(), "--observer-seed", "-1"}, "--observer-seed"},
      {{"run", "--config", kConfig, "--headless", "-o", dir.string(), "--pace-ms", "-5"}, "--pace-ms"},
      {{"run", "--config", kConfig, "--headless", "-o", dir.string(), "--stop-after", "-3"}, "--stop-after"},
      {{"stimulus", "--artifact-px", "10", "--filter-radius-px", "nan", "-o", dir.string()}, "--filter-radius-px"},
      {{"stimulus", "--artifact-px", "10", "--filter-radius-px", "20", "--seed", "-2", "-o", dir.string()}, "--seed"},
  };
  for (const auto& [args, option] : cases) {
    std::string out;
    EXPECT_NE(run(args, &out), 0) << option;
    EXPECT_NE(out.find(option), std::string::npos) << out;
    EXPECT_FALSE(fs::exists(dir)) << option;
  }
}

// Issue 27: values that saturated or where the last one won are refused.
TEST(StudyRun, SeedsBeyondSixtyFourBitsAndRepeatedObserverKeysAreRefused) {
  const fs::path dir = fresh("saturate");
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{"run", "--config", kConfig, "--headless", "-o", dir.string(), "--seed", "18446744073709551616"},
       "--seed: expected a non-negative integer of at most 18446744073709551615 (2^64 - 1)"},
      {{"run", "--config", kConfig, "--headless", "-o", dir.string(), "--observer-seed", "99999999999999999999999"},
       "--observer-seed: expected a non-negative integer of at most"},
      {{"stimulus", "--artifact-px", "10", "--filter-radius-px", "20", "--seed", "18446744073709551616", "-o", dir.string()},
       "--seed: expected a non-negative integer of at most"},
      {{"run", "--config", kConfig, "--headless", "-o", dir.string(), "--observer", "psychometric:c=3,c=5"}, "--observer: c given twice"},
      {{"reference", "--seeds", "", "-o", (dir / "ref.json").string()}, "--seeds: expected a non-negative integer"},
  };
  for (const auto& [args, expected] : cases) {
    std::string out;
    EXPECT_EQ(run(args, &out), 2) << expected;
    EXPECT_NE(out.find(expected), std::string::npos) << out;
    EXPECT_EQ(lines_of(out), 1) << out;
    EXPECT_FALSE(fs::exists(dir)) << expected;
  }
  // 2^64 - 1 itself is a seed.
  EXPECT_EQ(run({"run", "--config", kConfig, "--headless", "-o", dir.string(), "--seed", "18446744073709551615", "--stop-after", "2"}), 0);
  fs::remove_all(dir);
}

// Issue 27: a session directory is data another machine may hand us. A symbolic link in it is
// refused, never followed: with session.lock a link, --resume truncated the file it pointed at and
// wrote its pid there; with trials.csv a link, rows were appended to the other file.
TEST(StudyRun, LinksInASessionDirectoryAreRefusedAndTheirTargetsUntouched) {
  const fs::path dir = fresh("links"), victim = fresh("links-victim.txt");
  ASSERT_EQ(run({"run", "--config", kConfig, "--observer", kObserver, "--headless", "-o", dir.string(), "--stop-after", "5"}), 0);
  EXPECT_FALSE(fs::exists(dir / "session.lock")) << "released: the lock file goes with the lock";
  const std::string victim_text = "precious\n";
  for (const char* name : {"session.lock", "trials.csv", "session.json"}) {
    SCOPED_TRACE(name);
    std::ofstream(victim) << victim_text;
    const fs::path kept = dir.string() + "-kept";
    fs::remove_all(kept);
    fs::copy(dir, kept);
    fs::remove(dir / name);
    if (std::string(name) != "session.lock") fs::copy_file(kept / name, victim, fs::copy_options::overwrite_existing);
    const std::string target_before = bytes(victim);
    fs::create_symlink(victim, dir / name);
    std::string out;
    EXPECT_EQ(run({"run", "--resume", dir.string(), "--headless"}, &out), 1) << out;
    EXPECT_NE(out.find((dir / name).string() + ": is a symbolic link; refusing to follow it"), std::string::npos) << out;
    EXPECT_EQ(lines_of(out), 1) << out;
    EXPECT_EQ(bytes(victim), target_before) << "the link's target was written";
    EXPECT_TRUE(fs::is_symlink(dir / name));
    fs::remove_all(dir);
    fs::rename(kept, dir);
  }
  // -o that is a link is refused too, before anything is written.
  const fs::path real = fresh("links-real"), link = fresh("links-link");
  fs::create_directories(real);
  fs::create_symlink(real, link);
  std::string out;
  EXPECT_EQ(run({"run", "--config", kConfig, "--headless", "-o", link.string()}, &out), 1) << out;
  EXPECT_NE(out.find(link.string() + ": is a symbolic link"), std::string::npos) << out;
  EXPECT_TRUE(fs::is_empty(real));
  fs::remove(link);
  fs::remove_all(real);
  fs::remove_all(dir);
  fs::remove(victim);
}

// Issue 27: every program's output path follows one rule (io::check_output): a folder that exists,
// no link, and a directory that is new, empty or a previous output of the same kind. `run -o` and
// `stimulus -o` wrote into directories of unrelated files; `reference -o a/b/c/ref.json` created
// every missing folder (one at the filesystem root when run as root). A refused run leaves no
// session.lock; a kill's temporary beside session.json is removed by the next run.
TEST(StudyRun, OutputsFollowOneRuleAndRefusalsLeaveNothing) {
  const fs::path foreign = fresh("foreign"), missing = fresh("missing");
  fs::create_directories(foreign);
  std::ofstream(foreign / "thesis.tex") << "not ours\n";
  struct Case {
    std::vector<std::string> args;
    std::string expected;
  };
  const std::vector<Case> cases = {
      {{"run", "--config", kConfig, "--headless", "-o", foreign.string()}, foreign.string() + ": exists and is not empty"},
      {{"stimulus", "--artifact-px", "10", "--filter-radius-px", "20", "-o", foreign.string()},
       foreign.string() + ": exists and is not a previous output (no stimulus.json)"},
      {{"reference", "--artifact-px", "10", "-o", (missing / "a" / "b" / "ref.json").string()},
       (missing / "a" / "b" / "ref.json").string() + ": the folder " + (missing / "a" / "b").string() + " does not exist"},
      {{"run", "--config", kConfig, "--headless", "-o", (foreign / "thesis.tex" / "s").string()},
       (foreign / "thesis.tex" / "s").string() + ": " + (foreign / "thesis.tex").string() + " is not a folder"},
  };
  for (const Case& c : cases) {
    std::string out;
    EXPECT_EQ(run(c.args, &out), 1) << c.expected;
    EXPECT_NE(out.find(c.expected), std::string::npos) << out;
    EXPECT_EQ(lines_of(out), 1) << out;
  }
  EXPECT_FALSE(fs::exists(missing));
  std::vector<std::string> listing;
  for (const auto& e : fs::directory_iterator(foreign)) listing.push_back(e.path().filename().string());
  EXPECT_EQ(listing, std::vector<std::string>{"thesis.tex"});

  // A stimulus directory is replaced whole, and a new one appears whole.
  const fs::path stim = fresh("stim");
  ASSERT_EQ(run({"stimulus", "--artifact-px", "10", "--filter-radius-px", "20", "--size-px", "64", "-o", stim.string()}), 0);
  ASSERT_EQ(run({"stimulus", "--artifact-px", "5", "--filter-radius-px", "20", "--size-px", "64", "-o", stim.string()}), 0);
  EXPECT_NE(bytes(stim / "stimulus.json").find("\"artifact_px\": 5"), std::string::npos);

  // Refused runs leave no lock file; a kill's temporary is removed by the next write of session.json.
  const fs::path dir = fresh("no-lock");
  ASSERT_EQ(run({"run", "--config", kConfig, "--observer", kObserver, "--headless", "-o", dir.string(), "--stop-after", "3"}), 0);
  std::string out;
  EXPECT_EQ(run({"run", "--config", kConfig, "--headless", "-o", dir.string()}, &out), 1) << out;  // holds a session
  EXPECT_EQ(run({"run", "--resume", dir.string(), "--headless", "--seed", "1"}, &out), 2) << out;  // contradicts it
  EXPECT_FALSE(fs::exists(dir / "session.lock"));
  const fs::path abandoned = dir / ".session.json.partial-999999999";  // above any pid_max: its process is gone
  std::ofstream(abandoned) << "{";
  ASSERT_EQ(run({"run", "--resume", dir.string(), "--headless", "--stop-after", "4"}, &out), 0) << out;
  EXPECT_FALSE(fs::exists(abandoned));
  EXPECT_FALSE(fs::exists(dir / "session.lock"));
  fs::remove_all(dir);
  fs::remove_all(stim);
  fs::remove_all(foreign);
}

// Issue 27: a bad observer in session.json was reported as the --observer option nobody passed.
TEST(StudyRun, ABadObserverInSessionJsonIsBlamedOnTheFile) {
  const fs::path dir = fresh("bad-observer");
  ASSERT_EQ(run({"run", "--config", kConfig, "--observer", kObserver, "--headless", "-o", dir.string(), "--stop-after", "3"}), 0);
  nlohmann::json j = nlohmann::json::parse(bytes(dir / "session.json"));
  j["observer"] = "psychometric:c=-4";
  std::ofstream(dir / "session.json") << j.dump(2);
  std::string out;
  EXPECT_EQ(run({"run", "--resume", dir.string(), "--headless"}, &out), 1) << out;
  EXPECT_NE(out.find("penumbra-study: " + (dir / "session.json").string() + ": observer: c_true must be positive"), std::string::npos)
      << out;
  fs::remove_all(dir);
}

}  // namespace
