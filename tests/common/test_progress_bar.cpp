// cli/progress_bar.h: whole lines in a log, one redrawn line on a terminal, nothing when disabled.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <stdlib.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <thread>

#include "cli/progress_bar.h"

namespace penumbra {
namespace {

std::string read_all(std::FILE* f) {
  std::fflush(f);
  std::rewind(f);
  std::string s;
  for (int c; (c = std::fgetc(f)) != EOF;) s += static_cast<char>(c);
  return s;
}

TEST(ProgressBar, ALogGetsWholeLinesAndTheLastOneAlways) {
  std::FILE* log = std::tmpfile();
  ASSERT_NE(log, nullptr);
  {
    ProgressBar bar("work", true, " items", log);
    for (int i = 1; i <= 1000; ++i) bar(i, 1000, "item " + std::to_string(i));
  }
  const std::string out = read_all(log);
  EXPECT_EQ(out.find('\r'), std::string::npos) << "no carriage returns in a log";
  EXPECT_EQ(out, "work [########################################] 1000/1000 items, 0 s left  item 1000\n")
      << "a quick job: only its final line";
  std::fclose(log);

  log = std::tmpfile();
  {
    ProgressBar bar("slow", true, "", log);
    bar(1, 4);
    std::this_thread::sleep_for(std::chrono::milliseconds(600));
    bar(2, 4);  // past half a second: drawn
    bar(3, 4);  // within ten seconds of the last line: not
    bar(4, 4);
    bar(4, 4);  // the end is written once
  }
  const std::string slow = read_all(log);
  EXPECT_EQ(slow.substr(0, slow.find(',')), "slow [####################....................] 2/4") << slow;
  EXPECT_NE(slow.find("] 4/4, 0 s left\n"), std::string::npos);
  EXPECT_EQ(std::count(slow.begin(), slow.end(), '\n'), 2);
  std::fclose(log);
}

TEST(ProgressBar, DisabledOrEmptyWorkWritesNothing) {
  std::FILE* log = std::tmpfile();
  {
    ProgressBar off("work", false, "", log);
    off(5, 5);
    ProgressBar none("work", true, "", log);
    none(0, 0);
  }
  EXPECT_EQ(read_all(log), "");
  std::fclose(log);
}

TEST(ProgressBar, ATerminalGetsOneLineRedrawnInPlace) {
  const int master = posix_openpt(O_RDWR | O_NOCTTY);
  if (master < 0 || grantpt(master) != 0 || unlockpt(master) != 0) GTEST_SKIP() << "no pseudo-terminal here";
  const int slave = open(ptsname(master), O_RDWR | O_NOCTTY);
  ASSERT_GE(slave, 0);
  std::FILE* tty = fdopen(slave, "w");
  {
    ProgressBar bar("tty", true, "", tty);
    bar(1, 2);
    std::this_thread::sleep_for(std::chrono::milliseconds(600));
    bar(1, 2, "first");
    bar(2, 2, "second");
    bar.clear();
  }
  std::fclose(tty);
  std::string out;
  char buf[512];
  fcntl(master, F_SETFL, O_NONBLOCK);
  for (ssize_t n; (n = read(master, buf, sizeof buf)) > 0;) out.append(buf, static_cast<std::size_t>(n));
  close(master);
  EXPECT_EQ(out.find('\n'), std::string::npos) << "one line, redrawn: " << out;
  EXPECT_NE(out.find("\rtty [####################....................] 1/2, "), std::string::npos) << out;
  EXPECT_NE(out.find(" s left  first\033[K"), std::string::npos) << out;
  EXPECT_NE(out.find("] 2/2, 0 s left  second\033[K"), std::string::npos) << out;
  EXPECT_EQ(out.substr(out.size() - 4), "\r\033[K") << "cleared for what follows";
}

}  // namespace
}  // namespace penumbra
