// penumbra-demo --headless --shard I/N --part FILE and `penumbra-demo merge` (docs/cluster.md): a
// tiny sweep of three techniques in two shards (shard 0 walks the first and the third) merges into
// what the unsharded run prints and writes, the frame times and what is read from them apart; a
// missing, repeated or foreign part is refused in one line with nothing written; a bad --shard is
// refused naming the option.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "sharded_tool.h"
#include "subprocess.h"

namespace fs = std::filesystem;
using ::testing::HasSubstr;

namespace penumbra {
namespace {

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

class DemoShards : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("penumbra-demo-shards-" + std::to_string(::getpid()) + "-" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(work());
    fs::create_directories(dir_ / "scratch");
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path work() const { return dir_ / "work"; }  // the parts and outputs; the captured stdout and stderr go elsewhere
  test::Result demo(std::vector<std::string> args) {
    args.insert(args.begin(), run_.begin(), run_.end());
    return test::run_exe(PENUMBRA_DEMO_EXE, args, dir_ / "scratch");
  }
  test::Result merge(std::vector<std::string> args) { return test::run_merge(PENUMBRA_DEMO_EXE, std::move(args), dir_ / "scratch"); }
  // Shard i of n of the run into work()/part-i-of-n.json.
  fs::path part(int i, int n, std::vector<std::string> extra = {}) {
    return test::make_part([this](std::vector<std::string> args) { return demo(std::move(args)); }, work(), i, n, std::move(extra));
  }
  void expect_refused(const std::vector<fs::path>& parts, const std::string& needle) {
    test::expect_merge_refused(PENUMBRA_DEMO_EXE, dir_ / "scratch", work(), parts, needle);
  }
  fs::path dir_;
  // The smallest sweep the demo runs: the demo scene's one-frame orbit at 64x36, every engine
  // configuration, the reference, FLIP and the images (crops, montages) at that frame.
  std::vector<std::string> run_ = {"--headless", "--scene", "demo", "--frames", "1", "--width", "64", "--height", "36",
                                   "--techniques", "pcf,pcss,hard", "--sweep", "--no-plot"};
};

// The fields penumbra-demo merge --help names as measured: the frame times and what is read from
// them (the fronts on time and shadow cost, the speedups, the headlines, the observer's cheapest
// by time); everything else is the same text.
void erase_timing(nlohmann::json& j) {
  if (j.is_array()) {
    for (auto& x : j) erase_timing(x);
    return;
  }
  if (!j.is_object()) return;
  std::vector<std::string> timing;
  for (const auto& [key, value] : j.items()) {
    const bool ms = key.ends_with("_ms") || key.ends_with("_ms_mean");
    if (ms || key == "time" || key == "shadow_cost" || key == "headline" || key == "line" || key == "cheapest_by_time" ||
        key.starts_with("speedup"))
      timing.push_back(key);
  }
  for (const std::string& key : timing) j.erase(key);
  for (auto& [key, value] : j.items()) erase_timing(value);
}

// frames.csv less its frame_ms column (printed with 4 decimals; the names may hold commas).
std::string csv_without_times(const std::string& csv) { return std::regex_replace(csv, std::regex(",[0-9]+\\.[0-9]{4},"), ",T,"); }

// The printed lines that hold no time: the settings, the references, FLIP's and the thin casters'
// notes, the tables' headers.
bool timeless(const std::string& line) {
  for (const char* prefix : {"demo at ", "c for ", "adaptive: ", "frame time: ", "single map: ", "tech ", "  configuration", "  FLIP: ",
                             "  reference: ", "  thin casters", "  PCSS: ", "  flicker along"})
    if (line.starts_with(prefix)) return true;
  return false;
}

TEST_F(DemoShards, TwoShardsOfThreeTechniquesMergeToTheUnshardedRunApartFromTimes) {
  const fs::path full = work() / "full", merged = work() / "merged";
  const test::Result whole = demo({"-o", full.string()});
  ASSERT_EQ(whole.exit_code, 0) << whole.err;
  const fs::path p0 = part(0, 2), p1 = part(1, 2);
  EXPECT_FALSE(fs::exists(work() / "out")) << "a shard writes its part alone";
  // The rule: the technique at position k of --techniques is shard k mod 2's.
  const auto techniques_of = [](const fs::path& p) {
    const nlohmann::json j = nlohmann::json::parse(test::read_file(p));
    std::vector<std::string> names;
    for (const auto& t : j.at("payload").at("techniques")) names.push_back(t.at("technique"));
    return names;
  };
  EXPECT_EQ(techniques_of(p0), (std::vector<std::string>{"pcf", "hard"}));
  EXPECT_EQ(techniques_of(p1), (std::vector<std::string>{"pcss"}));

  const test::Result m = merge({p1.string(), p0.string(), "-o", merged.string()});
  ASSERT_EQ(m.exit_code, 0) << m.err;
  EXPECT_THAT(m.out, HasSubstr("wrote " + merged.string() + "/"));

  // The same files; the images byte for byte.
  std::vector<std::string> files_full, files_merged;
  for (const auto& e : fs::directory_iterator(full)) files_full.push_back(e.path().filename().string());
  for (const auto& e : fs::directory_iterator(merged)) files_merged.push_back(e.path().filename().string());
  std::sort(files_full.begin(), files_full.end());
  std::sort(files_merged.begin(), files_merged.end());
  EXPECT_EQ(files_merged, files_full);
  int images = 0;
  for (const std::string& f : files_full)
    if (f.ends_with(".png")) {
      ++images;
      EXPECT_TRUE(test::read_file(merged / f) == test::read_file(full / f)) << f << " differs";
    }
  EXPECT_EQ(images, 12) << "side by side, crops, gain crops and the FLIP montage of each technique";

  // report.json: every field but the timing ones; the techniques in --techniques order.
  nlohmann::json report_full = nlohmann::json::parse(test::read_file(full / "report.json"));
  nlohmann::json report_merged = nlohmann::json::parse(test::read_file(merged / "report.json"));
  ASSERT_EQ(report_merged.at("techniques").size(), 3u);
  EXPECT_EQ(report_merged.at("techniques").at(1).at("technique"), "pcss");
  EXPECT_TRUE(report_merged.at("techniques").at(0).at("adaptive").contains("frame_ms")) << "the parts' own times are kept";
  erase_timing(report_full);
  erase_timing(report_merged);
  EXPECT_EQ(report_merged.dump(1), report_full.dump(1));

  EXPECT_EQ(csv_without_times(test::read_file(merged / "frames.csv")), csv_without_times(test::read_file(full / "frames.csv")));
  EXPECT_NE(csv_without_times(test::read_file(full / "frames.csv")), test::read_file(full / "frames.csv")) << "the times are masked";
  // Eight fields a row: the names that hold a comma are quoted.
  EXPECT_THAT(test::read_file(full / "frames.csv"), HasSubstr(",\"adaptive, no hysteresis\","));
  for (const std::string& row : lines_of(test::read_file(merged / "frames.csv")))
    EXPECT_EQ(std::count(row.begin(), row.end(), ','), 7 + (row.find('"') != std::string::npos ? 1 : 0)) << row;

  // The printed results: as many lines, and those without a time the same, in the same places.
  const std::vector<std::string> out_full = lines_of(whole.out), out_merged = lines_of(m.out);
  ASSERT_EQ(out_merged.size(), out_full.size()) << m.out;
  int compared = 0;
  for (std::size_t k = 0; k + 1 < out_full.size(); ++k)  // the last line names the output
    if (timeless(out_full[k])) {
      ++compared;
      EXPECT_EQ(out_merged[k], out_full[k]) << "line " << k;
    }
  EXPECT_GE(compared, 15);
}

TEST_F(DemoShards, AMergeOfMissingTwiceOrForeignPartsIsRefusedWithNothingWritten) {
  // The cheapest run that still has a part per technique: no engine family, no reference.
  run_ = {"--headless", "--scene", "demo", "--frames", "1", "--width", "32", "--height", "18", "--techniques", "pcf,pcss",
          "--no-baselines", "--no-reference", "--no-virtual", "--no-plot"};
  // Other settings (two renders per frame), made first: the part's name is the shard's.
  const fs::path other = work() / "other.json";
  fs::rename(part(1, 2, {"--repeats", "2"}), other);
  const fs::path p0 = part(0, 2), p1 = part(1, 2);
  expect_refused({p0}, "shard 1/2 missing");
  expect_refused({p0, p1, p1}, p1.string() + ": shard 1/2 again");
  const fs::path copy = work() / "copy-of-1.json";
  fs::copy_file(p1, copy);
  expect_refused({p0, p1, copy}, copy.string() + ": shard 1/2 again");
  expect_refused({p0, other}, other.string() + ": made with other settings");
  // Another shard count: the whole run as shard 0/1.
  const fs::path one = part(0, 1);
  expect_refused({p0, one}, one.string() + ": shard 0/1, but");
  // Edited after it was written: its settings, then what it carries.
  nlohmann::json j = nlohmann::json::parse(test::read_file(p1));
  const auto write = [&](const std::string& name, const nlohmann::json& content) {
    const fs::path p = work() / name;
    std::ofstream(p) << content.dump() << "\n";
    return p;
  };
  nlohmann::json edited = j;
  edited["settings"]["args"].push_back("--repeats");
  expect_refused({p0, write("edited.json", edited)}, "edited.json: its settings do not match its fingerprint");
  nlohmann::json short_part = j;
  short_part["payload"]["techniques"] = nlohmann::json::array();
  expect_refused({p0, write("short.json", short_part)}, "short.json: payload.techniques: pcss (shard 1/2's) missing");
  nlohmann::json elsewhere = j;
  elsewhere["payload"]["device"]["renderer"] = "another GPU";
  expect_refused({p0, write("elsewhere.json", elsewhere)}, "elsewhere.json: measured on another device than");
  nlohmann::json moved = j;
  moved["payload"]["head"]["report"]["scene"] = "outdoor";
  expect_refused({p0, write("moved.json", moved)}, "moved.json: its run's scene, path, calibration or display differ");
  nlohmann::json escaping = j;
  escaping["payload"]["techniques"][0]["images"][0]["file"] = "../pcss-escape.png";
  expect_refused({p0, write("escaping.json", escaping)}, "is not one of pcss's images");
  // And the parts as made merge.
  const test::Result m = merge({p0.string(), p1.string(), "-o", (work() / "fine").string()});
  EXPECT_EQ(m.exit_code, 0) << m.err;
  EXPECT_TRUE(fs::exists(work() / "fine" / "report.json"));
}

TEST_F(DemoShards, BadShardOptionsAreRefusedNamingTheOption) {
  const std::string part_file = (work() / "p.json").string();
  const test::ToolRun run = [this](std::vector<std::string> args) { return demo(std::move(args)); };
  for (const std::string shard : {"0/0", "3/2", "junk", "1/", "-1/2", "0/4"})
    test::expect_usage_refused(run, {"--shard", shard, "--part", part_file}, "--shard");
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{"--shard", "0/4", "--part", part_file}, "above the 3 techniques"},
      {{"--shard", "0/2"}, "--shard: needs --part"},
      {{"--part", part_file, "-o", (work() / "out").string()}, "--part: only with --shard"},
      {{"--shard", "0/2", "--part", part_file, "-o", (work() / "out").string()}, "--output: a shard writes a part"}};
  for (const auto& [args, needle] : cases) test::expect_usage_refused(run, args, needle);
  // Not the headless comparison: --pages.
  const test::Result pages = test::run_exe(PENUMBRA_DEMO_EXE, {"--pages", "--shard", "0/2", "--part", part_file}, dir_ / "scratch");
  EXPECT_EQ(pages.exit_code, 2) << pages.err;
  EXPECT_THAT(pages.err, HasSubstr("--shard: only with --headless"));
  EXPECT_TRUE(fs::is_empty(work())) << "a refused shard wrote something";
}

}  // namespace
}  // namespace penumbra
