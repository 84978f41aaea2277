// io::StagedDirectory: an output directory appears whole or not at all, and the staging
// directories of killed runs do not pile up beside it.
#include <gtest/gtest.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <thread>

#include <sys/wait.h>
#include <unistd.h>

#include "io/staged_dir.h"

namespace fs = std::filesystem;

namespace penumbra::io {
namespace {

std::set<std::string> listing(const fs::path& dir) {
  std::set<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.insert(e.path().filename().string());
  return names;
}

// The pid of a child that has exited and been reaped: no process has it (until the kernel reuses it).
pid_t dead_pid() {
  const pid_t pid = ::fork();
  if (pid == 0) ::_exit(0);
  int status = 0;
  ::waitpid(pid, &status, 0);
  return pid;
}

class StagedDir : public ::testing::Test {
 protected:
  void SetUp() override {
    work_ = fs::temp_directory_path() / ("penumbra-staged-" + std::to_string(::getpid()));
    fs::remove_all(work_);
    fs::create_directories(work_);
  }
  void TearDown() override { fs::remove_all(work_); }
  fs::path work_;
};

TEST_F(StagedDir, CommitReplacesAPreviousOutputAndNothingElseRemains) {
  {
    StagedDirectory out((work_ / "out").string(), "report.json");
    std::ofstream(out.path() / "report.json") << "1\n";
    out.commit();
  }
  {
    StagedDirectory out((work_ / "out").string() + "/", "report.json");  // a trailing '/' names the same directory
    std::ofstream(out.path() / "report.json") << "2\n";
    std::ofstream(out.path() / "more.csv") << "x\n";
    out.commit();
  }
  EXPECT_EQ(listing(work_), std::set<std::string>{"out"});
  EXPECT_EQ(listing(work_ / "out"), (std::set<std::string>{"report.json", "more.csv"}));
}

// Issue 14.7: commit() removed the previous output before renaming the new one in, so a kill in
// between left no output at all. A reader watching the target must always find a whole output.
TEST_F(StagedDir, AtEveryInstantTheOldOrTheNewOutputExists) {
  const fs::path target = work_ / "out";
  {
    StagedDirectory out(target.string(), "report.json");
    std::ofstream(out.path() / "report.json") << "0\n";
    out.commit();
  }
  std::atomic<bool> done = false;
  std::atomic<long> looks = 0, missing = 0;
  std::thread watcher([&] {
    while (!done) {
      std::error_code ec;
      if (!fs::exists(target / "report.json", ec)) ++missing;
      ++looks;
    }
  });
  for (int i = 1; i <= 300; ++i) {
    StagedDirectory out(target.string(), "report.json");
    std::ofstream(out.path() / "report.json") << i << "\n";
    out.commit();
  }
  done = true;
  watcher.join();
  EXPECT_GT(looks, 300);
  EXPECT_EQ(missing, 0) << "the output was missing in " << missing << " of " << looks << " looks";
  EXPECT_EQ(listing(work_), std::set<std::string>{"out"});
  std::ifstream in(target / "report.json");
  std::string text;
  std::getline(in, text);
  EXPECT_EQ(text, "300");
}

TEST_F(StagedDir, WithoutCommitThePreviousOutputIsUntouched) {
  fs::create_directories(work_ / "out");
  std::ofstream(work_ / "out" / "report.json") << "old\n";
  {
    StagedDirectory out((work_ / "out").string(), "report.json");
    std::ofstream(out.path() / "report.json") << "new\n";
  }
  EXPECT_EQ(listing(work_), std::set<std::string>{"out"});
  std::ifstream in(work_ / "out" / "report.json");
  std::string text;
  std::getline(in, text);
  EXPECT_EQ(text, "old");
}

TEST_F(StagedDir, StagingOfKilledRunsIsRemovedAndEverythingElseKept) {
  const std::string dead = "out.partial-" + std::to_string(dead_pid());
  const std::string alive = "out.partial-1";          // init: always running
  const std::string not_a_pid = "out.partial-abc";
  const std::string other_target = "other.partial-" + std::to_string(dead_pid());
  for (const auto& d : {dead, alive, not_a_pid, other_target}) {
    fs::create_directories(work_ / d);
    std::ofstream(work_ / d / "report.json") << "half\n";
  }
  StagedDirectory out((work_ / "out").string(), "report.json");
  const std::string mine = out.path().filename().string();
  EXPECT_EQ(listing(work_), (std::set<std::string>{alive, not_a_pid, other_target, mine}));
}

TEST_F(StagedDir, ForeignDirectoryIsRefused) {
  fs::create_directories(work_ / "out");
  std::ofstream(work_ / "out" / "thesis.tex") << "precious\n";
  EXPECT_THROW(StagedDirectory((work_ / "out").string(), "report.json"), std::runtime_error);
  EXPECT_EQ(listing(work_ / "out"), std::set<std::string>{"thesis.tex"});
  EXPECT_EQ(listing(work_), std::set<std::string>{"out"});
}

}  // namespace
}  // namespace penumbra::io
