#pragma once
// What the tests of penumbra-bench's and penumbra-demo's --shard I/N --part FILE and merge share
// (docs/cluster.md): a shard run into its part, a bad command line refused, and a merge refused
// with nothing written. The tool runs from a scratch folder (its stdout and stderr captured
// there); the parts and outputs go in a work folder.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "subprocess.h"

namespace penumbra::test {

// The tool with the test's own options before `args`.
using ToolRun = std::function<Result(std::vector<std::string> args)>;

// Shard i of n of `run` with `extra` into work/part-i-of-n.json: expects it to succeed and say it
// wrote the part. The part's path.
inline std::filesystem::path make_part(const ToolRun& run, const std::filesystem::path& work, int i, int n,
                                       std::vector<std::string> extra = {}) {
  const std::string shard = std::to_string(i) + "/" + std::to_string(n);
  const std::filesystem::path p = work / ("part-" + std::to_string(i) + "-of-" + std::to_string(n) + ".json");
  extra.insert(extra.end(), {"--shard", shard, "--part", p.string()});
  const Result r = run(extra);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, ::testing::HasSubstr("wrote " + p.string() + ": shard " + shard));
  return p;
}

// `run` with `args` refused as a bad command line: exit 2, one line naming `needle`.
inline void expect_usage_refused(const ToolRun& run, const std::vector<std::string>& args, const std::string& needle) {
  std::string given;
  for (const std::string& a : args) given += " " + a;
  const Result r = run(args);
  EXPECT_EQ(r.exit_code, 2) << given << ": " << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << given << ": " << r.err;
  EXPECT_THAT(r.err, ::testing::HasSubstr(needle)) << given;
}

// `exe merge ARGS...`.
inline Result run_merge(const std::string& exe, std::vector<std::string> args, const std::filesystem::path& scratch) {
  args.insert(args.begin(), "merge");
  return run_exe(exe, args, scratch);
}

// `exe merge PARTS... -o work/merged` refused: exit 1, one line naming `needle`, no output
// directory and no staging left in `work`.
inline void expect_merge_refused(const std::string& exe, const std::filesystem::path& scratch, const std::filesystem::path& work,
                                 const std::vector<std::filesystem::path>& parts, const std::string& needle) {
  std::vector<std::string> args;
  for (const auto& p : parts) args.push_back(p.string());
  const std::filesystem::path out = work / "merged";
  args.insert(args.end(), {"-o", out.string()});
  const Result r = run_merge(exe, args, scratch);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_THAT(r.err, ::testing::HasSubstr(needle));
  EXPECT_FALSE(std::filesystem::exists(out)) << "a refused merge wrote " << out;
  for (const auto& e : std::filesystem::directory_iterator(work))
    EXPECT_THAT(e.path().filename().string(), ::testing::Not(::testing::HasSubstr("merged"))) << "staging left behind";
}

}  // namespace penumbra::test
