// penumbra-observer-curve --shard I/N and merge (issue 50, docs/cluster.md): a small grid in three
// shards merged equals the unsharded run byte for byte (its calibration.json and its printed
// tables); a merge with a shard missing, twice, from other settings or another build is refused
// with one line naming the file, and writes nothing; a --shard that is not I/N with I < N is
// refused with one line naming the option.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "tool_run.h"

namespace {

namespace fs = std::filesystem;
using penumbra::test::bytes;
using penumbra::test::Ran;

const std::string kCurve = PENUMBRA_OBSERVER_CURVE_EXE;
// Two conditions, two sizes with different numbers of radii, two seeds: 24 renders, which three
// shards split 8/8/8 across every block boundary.
const std::string kGrid = "--pattern stair,step --artifact-px 5,10 --ratio-min 1 --ratio-max 3 --ratio-step 1.5 --seeds 2";

fs::path fresh(const std::string& name) { return penumbra::test::fresh_dir("penumbra-shard-", name); }

// penumbra-observer-curve `args` run in `dir` (relative paths: the recorded command names the same
// --json in both runs).
Ran run(const fs::path& dir, const std::string& args) { return penumbra::test::run_in(dir, kCurve, args); }

// The three parts of kGrid in `dir`: part-0.json, part-1.json, part-2.json.
void make_parts(const fs::path& dir) {
  for (int i = 0; i < 3; ++i) {
    const Ran ran = run(dir, kGrid + " --shard " + std::to_string(i) + "/3 --part part-" + std::to_string(i) + ".json");
    ASSERT_EQ(ran.status, 0) << ran.err;
  }
}

TEST(ObserverCurveShards, ThreeShardsMergedEqualTheUnshardedRun) {
  const fs::path whole = fresh("whole"), sharded = fresh("sharded");
  const Ran direct = run(whole, kGrid + " --json out.json");
  ASSERT_EQ(direct.status, 0) << direct.err;
  make_parts(sharded);
  // Each part holds its own third of the renders, numbered in the grid's loop order.
  std::size_t renders = 0;
  for (int i = 0; i < 3; ++i) {
    const nlohmann::json part = nlohmann::json::parse(bytes(sharded / ("part-" + std::to_string(i) + ".json")));
    EXPECT_EQ(part["shard"]["index"], i);
    EXPECT_EQ(part["shard"]["count"], 3);
    EXPECT_EQ(part["payload"]["items"], 24);
    for (const auto& point : part["payload"]["points"]) EXPECT_EQ(point[0].get<int>() % 3, i) << point;
    renders += part["payload"]["points"].size();
    EXPECT_NE(part["version"].get<std::string>().find("penumbra-observer-curve "), std::string::npos);
  }
  EXPECT_EQ(renders, 24u);
  const Ran merged = run(sharded, "merge part-2.json part-0.json part-1.json -o out.json");  // any order
  ASSERT_EQ(merged.status, 0) << merged.err;
  EXPECT_EQ(bytes(sharded / "out.json"), bytes(whole / "out.json"));
  EXPECT_EQ(merged.out, direct.out);  // the same tables, curves and intervals printed
  const nlohmann::json entry = nlohmann::json::parse(bytes(sharded / "out.json"))["entries"][0];
  EXPECT_TRUE(entry["c"].is_number()) << entry;
  EXPECT_EQ(entry["per_condition"].size(), 2u);
  // Issue 48: each condition carries the observer's own slope (null where too few points of its
  // curve lie inside F 0.02-0.98), and the entry's threshold block the one of its condition.
  for (const auto& c : entry["per_condition"]) EXPECT_TRUE(c.contains("beta")) << c;
  if (entry.contains("threshold")) {
    EXPECT_GT(entry["threshold"]["beta"].get<double>(), 0.1) << entry["threshold"];
    EXPECT_NEAR(entry["threshold"]["criterion_f"].get<double>(), 0.64, 1e-9) << entry["threshold"];
  }
  fs::remove_all(whole);
  fs::remove_all(sharded);
}

// A refused merge: exit 1, one line on stderr naming `names`, no out.json.
void expect_refused(const fs::path& dir, const std::string& args, const std::string& names) {
  const Ran ran = run(dir, args);
  EXPECT_EQ(ran.status, 1) << args << "\n" << ran.err;
  EXPECT_EQ(ran.err.rfind("penumbra-observer-curve merge: ", 0), 0u) << ran.err;
  EXPECT_EQ(std::count(ran.err.begin(), ran.err.end(), '\n'), 1) << ran.err;
  EXPECT_NE(ran.err.find(names), std::string::npos) << ran.err;
  EXPECT_FALSE(fs::exists(dir / "out.json")) << args;
}

TEST(ObserverCurveShards, AMergeOfTheWrongPartsIsRefusedAndWritesNothing) {
  const fs::path dir = fresh("refused");
  make_parts(dir);
  expect_refused(dir, "merge part-0.json part-2.json -o out.json", "shard 1/3 missing");
  expect_refused(dir, "merge part-0.json part-1.json part-1.json part-2.json -o out.json", "part-1.json: shard 1/3 again");
  // Other settings: one more seed. Another shard count of the same grid is as foreign.
  std::string three_seeds = kGrid;
  three_seeds.replace(three_seeds.find("--seeds 2"), 9, "--seeds 3");
  ASSERT_EQ(run(dir, three_seeds + " --shard 1/3 --part other-seeds.json").status, 0);
  expect_refused(dir, "merge part-0.json other-seeds.json part-2.json -o out.json", "other-seeds.json: made with other settings");
  ASSERT_EQ(run(dir, kGrid + " --shard 1/2 --part half.json").status, 0);
  expect_refused(dir, "merge part-0.json half.json part-2.json -o out.json", "half.json: shard 1/2, but part-0.json is one of 3");
  // Another build: the version line differs (a part carried from a machine with another install).
  nlohmann::json part = nlohmann::json::parse(bytes(dir / "part-1.json"));
  part["version"] = "penumbra-observer-curve 0.0.9 (git 0000000)";
  std::ofstream(dir / "old-build.json") << part.dump();
  expect_refused(dir, "merge part-0.json old-build.json part-2.json -o out.json", "old-build.json: made by penumbra-observer-curve 0.0.9");
  // Settings edited after the part was written no longer match its fingerprint.
  part = nlohmann::json::parse(bytes(dir / "part-1.json"));
  part["settings"]["args"][1] = "stair";
  std::ofstream(dir / "edited.json") << part.dump();
  expect_refused(dir, "merge part-0.json edited.json part-2.json -o out.json", "edited.json: its settings do not match its fingerprint");
  // A render dropped from a part.
  part = nlohmann::json::parse(bytes(dir / "part-1.json"));
  part["payload"]["points"].erase(part["payload"]["points"].size() - 1);
  std::ofstream(dir / "short.json") << part.dump();
  expect_refused(dir, "merge part-0.json short.json part-2.json -o out.json", "short.json: payload.points");
  expect_refused(dir, "merge part-0.json stdout.txt part-2.json -o out.json", "stdout.txt");
  // The right three still merge in the same folder.
  EXPECT_EQ(run(dir, "merge part-0.json part-1.json part-2.json -o out.json").status, 0);
  fs::remove_all(dir);
}

TEST(ObserverCurveShards, AShardThatIsNotIOfNIsRefusedNamingTheOption) {
  const fs::path dir = fresh("bad-shard");
  for (const std::string value : {"0/0", "3/2", "junk", "1/", "-1/2", "1/2/3"}) {
    const Ran ran = run(dir, kGrid + " --shard " + value + " --part p.json");
    EXPECT_EQ(ran.status, 2) << value << ": " << ran.err;
    EXPECT_EQ(ran.err.rfind("penumbra-observer-curve: --shard: ", 0), 0u) << ran.err;
    EXPECT_EQ(std::count(ran.err.begin(), ran.err.end(), '\n'), 1) << ran.err;
    EXPECT_TRUE(ran.out.empty()) << value << ": rendered before refusing";
    EXPECT_FALSE(fs::exists(dir / "p.json")) << value;
  }
  Ran ran = run(dir, kGrid + " --shard 0/2");
  EXPECT_EQ(ran.status, 2);
  EXPECT_EQ(ran.err, "penumbra-observer-curve: --shard: needs --part FILE, where the shard's part goes\n");
  ran = run(dir, kGrid + " --part p.json");
  EXPECT_EQ(ran.status, 2);
  EXPECT_EQ(ran.err, "penumbra-observer-curve: --part: only with --shard I/N\n");
  ran = run(dir, kGrid + " --shard 0/2 --part p.json --json out.json");
  EXPECT_EQ(ran.status, 2);
  EXPECT_EQ(ran.err.rfind("penumbra-observer-curve: --json: a shard writes a part", 0), 0u) << ran.err;
  fs::remove_all(dir);
}

}  // namespace
