// penumbra-quest end to end: the JSON it prints and its one-line errors.

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

namespace {

struct CliRun {
  int status;
  std::string out;
  std::string err;
};

std::string slurp(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream buffer;
  buffer << in.rdbuf();
  return buffer.str();
}

CliRun run(const std::string& arguments) {
  const auto dir = std::filesystem::temp_directory_path();
  const std::string stem = "penumbra_quest_cli_" + std::to_string(::getpid());
  const auto out = dir / (stem + ".out");
  const auto err = dir / (stem + ".err");
  const std::string command = std::string("'") + PENUMBRA_QUEST_EXE + "' " + arguments + " >'" + out.string() +
                              "' 2>'" + err.string() + "'";
  const int raw = std::system(command.c_str());
  CliRun result{WIFEXITED(raw) ? WEXITSTATUS(raw) : -1, slurp(out), slurp(err)};
  std::filesystem::remove(out);
  std::filesystem::remove(err);
  return result;
}

const std::string kPsychoPy =
    "replay --tguess 50 --tguess-sd 50 --pthreshold .82 --beta 3.5 --delta .01 --gamma .5 --grain .01 --range 100 ";

TEST(PenumbraQuestCli, ReplayPrintsThePsychoPyReference) {
  const CliRun r = run(kPsychoPy + "--first 50 --responses 1,1,0,0,1,1,0,0,1,1");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(r.err, "");
  const auto json = nlohmann::ordered_json::parse(r.out);
  std::vector<std::string> keys;
  for (const auto& item : json.items()) keys.push_back(item.key());
  EXPECT_EQ(keys, (std::vector<std::string>{"intensities", "mean", "sd", "mode", "quantile", "x_threshold",
                                            "quantile_order"}));
  ASSERT_EQ(json["intensities"].size(), 10u);
  EXPECT_NEAR(json["intensities"][1].get<double>(), 45.139710407074872, 1e-9);
  EXPECT_NEAR(json["intensities"][9].get<double>(), 88.265808957695796, 1e-9);
  EXPECT_NEAR(json["mean"].get<double>(), 86.0772169427, 1e-9);
  EXPECT_NEAR(json["mode"].get<double>(), 80.11, 1e-9);
  EXPECT_NEAR(json["quantile"].get<double>(), 86.3849031085, 1e-9);
}

TEST(PenumbraQuestCli, ReplayWithIntensitiesAndBetaAnalysis) {
  const CliRun r = run(kPsychoPy +
                    "--intensities 50,45.139710407074872,37.291086503930742,58.297413127139947,80.182967131096547,"
                    "75.295251409003527,71.57627192423783,79.881680484036906,90.712313302815517,88.265808957695796 "
                    "--responses 1,1,0,0,1,1,0,0,1,1 --beta-analysis");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto json = nlohmann::ordered_json::parse(r.out);
  EXPECT_NEAR(json["mean"].get<double>(), 86.0772169427, 1e-9);
  // Psychtoolbox 3.0.18's QuestBetaAnalysis on this staircase (fixtures/quest_psychtoolbox.json).
  EXPECT_NEAR(json["beta_analysis"]["t"].get<double>(), 52.431660453472226, 1e-9);
  EXPECT_NEAR(json["beta_analysis"]["sd"].get<double>(), 0.1988892505757626, 1e-9);
  EXPECT_NEAR(json["beta_analysis"]["beta"].get<double>(), 2.1843440131603558, 1e-9);
  EXPECT_NEAR(json["beta_analysis"]["beta_sd"].get<double>(), 1.6916908647211544, 1e-9);
}

TEST(PenumbraQuestCli, OutOfRangeIntensityWarnsOnStderr) {
  const CliRun r = run(
      "replay --tguess 0 --tguess-sd 1 --pthreshold .82 --beta 3.5 --delta .01 --gamma .5 --range 1 "
      "--intensities 0,3 --responses 1,0");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("warning: QuestUpdate: intensity 3.000 out of range -0.50 to 0.50"), std::string::npos)
      << r.err;
  EXPECT_TRUE(nlohmann::json::accept(r.out));
}

TEST(PenumbraQuestCli, BadInputGetsOneLineErrorAndNonZeroExit) {
  const std::string base = "replay --tguess 0 --tguess-sd 1 --pthreshold .82 --beta 3.5 --delta .01 --gamma .5 ";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {base + "--responses 1,2", "--responses: item 2 is '2'"},
      {base + "--responses 1,,0", "empty item 2"},
      {base + "--responses 1,0 --intensities 0.1", "--intensities has 1 values but --responses has 2"},
      {base + "--responses 1 --intensities abc", "--intensities: item 1 is 'abc'"},
      {base + "--responses 1 --placement median", "--placement: 'median'"},
      {base + "--responses 1 --range 0", "\"range\" must be greater than zero"},
      {base + "--responses 1 --range -3", "\"range\" must be greater than zero"},
      {"replay --tguess 0 --tguess-sd 1 --pthreshold .999 --beta 3.5 --delta .01 --gamma .5 --responses 1", "omits"},
      {"replay --tguess nan --tguess-sd 1 --pthreshold .82 --beta 3.5 --delta .01 --gamma .5 --responses 1",
       "\"tGuess\" must be real and finite"},
      {"replay --tguess 0 --responses 1", "required"},
      {"simulate --trials 5", "--c-true is required"},
      {"simulate --c-true 3 --trials 0", "trials must be at least 1"},
      {"simulate --c-true 3 --method staircase", "--method: 'staircase'"},
      {"simulate --c-true 3 --sd-target nan", "--sd-target: expected a finite number"},  // issue 14.8
      {"simulate --c-true 3 --seed -1", "--seed: expected a non-negative integer"},
      {"frobnicate", ""},
      {"", ""},
  };
  for (const auto& [arguments, fragment] : cases) {
    const CliRun r = run(arguments);
    EXPECT_NE(r.status, 0) << arguments;
    EXPECT_EQ(r.out, "") << arguments;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << arguments << ": " << r.err;
    EXPECT_EQ(r.err.rfind("penumbra-quest: error: ", 0), 0u) << r.err;
    EXPECT_NE(r.err.find(fragment), std::string::npos) << arguments << ": " << r.err;
  }
}

TEST(PenumbraQuestCli, SimulateSummarisesTheRuns) {
  const CliRun r = run("simulate --c-true 5 --trials 40 --runs 50 --seed 3 --no-progress");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(r.err, "");
  const auto json = nlohmann::json::parse(r.out);
  EXPECT_EQ(json["runs"], 50);
  EXPECT_EQ(json["trials"], 40);
  EXPECT_NEAR(json["planted_threshold"].get<double>(), -std::log10(5.0), 1e-12);
  EXPECT_LT(json["final_mean"]["median_abs_error"].get<double>(), 0.08);
  EXPECT_NEAR(json["c_estimate_median"].get<double>(), 5.0, 1.0);
  EXPECT_TRUE(json["trials_to_sd"].contains("median"));
}

TEST(PenumbraQuestCli, HelpExitsZero) {
  const CliRun r = run("--help");
  EXPECT_EQ(r.status, 0);
  EXPECT_NE(r.out.find("replay"), std::string::npos);
}

}  // namespace
