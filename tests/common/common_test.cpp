// common/: error-line text (text::one_line, printable), the shared CLI parse (one line, exit 2)
// and write_file_atomic (whole or nothing, errno of the failing call, no device replaced).
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "cli/checks.h"
#include "cli/list_option.h"
#include "cli/main.h"
#include "io/atomic_file.h"
#include "io/safe_path.h"
#include "io/staged_dir.h"
#include "text/printable.h"

namespace {

namespace fs = std::filesystem;
using namespace penumbra;

std::string read(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

fs::path scratch(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("penumbra-common-" + name + "-" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

TEST(Text, OneLineKeepsUtf8AndEscapesControlBytes) {
  EXPECT_EQ(text::one_line("size_px: expected 16..4096 (r \xe2\x89\xa4 160 px)"),
            "size_px: expected 16..4096 (r \xe2\x89\xa4 160 px)");
  EXPECT_EQ(text::one_line("\n two  spaces\n"), "two spaces");
  // Issue 45: a newline or tab inside is escaped, not turned into a space that names another path.
  EXPECT_EQ(text::one_line("a\nb.json: cannot read"), "a\\x0ab.json: cannot read");
  EXPECT_EQ(text::one_line("two\nlines\r\n  and\ttabs "), "two\\x0alines\\x0d\\x0a and\\x09tabs");
  EXPECT_EQ(text::one_line("--format 'a\x01\x1b[31mred'"), "--format 'a\\x01\\x1b[31mred'");
  EXPECT_EQ(text::one_line("bad \xff byte"), "bad \\xff byte");
}

TEST(Text, OneLineCutsLongWordsAndLongLines) {
  const std::string word(1 << 20, 'x');
  const std::string line = text::one_line("--family '" + word + "': expected log-weibull");
  EXPECT_LT(line.size(), 200u);
  EXPECT_NE(line.find("... (1048577 bytes)': expected log-weibull"), std::string::npos) << line;
  std::string many;
  for (int i = 0; i < 100000; ++i) many += "a ";
  const std::string cut = text::one_line(many);
  EXPECT_LT(cut.size(), 1100u);
  EXPECT_NE(cut.find("... (200000 bytes)"), std::string::npos);
}

TEST(Text, ValidUtf8) {
  EXPECT_TRUE(text::valid_utf8("plain \xe2\x89\xa4 \xf0\x9f\x99\x82"));
  EXPECT_FALSE(text::valid_utf8("\xff"));
  EXPECT_FALSE(text::valid_utf8("\xc0\xaf"));          // overlong '/'
  EXPECT_FALSE(text::valid_utf8("\xed\xa0\x80"));      // surrogate
  EXPECT_FALSE(text::valid_utf8("\xe2\x89"));          // cut short
}

TEST(Cli, ParseErrorsAreOneLineAndExit2) {
  CLI::App app{"test"};
  std::string out;
  int n = 0;
  app.add_option("-o", out)->check(cli::path_given());
  app.add_option("-n", n)->check(CLI::Range(0, 10));
  std::vector<std::string> args = {"tool", "-n", "11"};
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  std::stringstream captured;
  auto* old = std::cerr.rdbuf(captured.rdbuf());
  const auto status = cli::parse(app, static_cast<int>(argv.size()), argv.data(), "tool");
  std::cerr.rdbuf(old);
  ASSERT_TRUE(status.has_value());
  EXPECT_EQ(*status, 2);
  EXPECT_EQ(captured.str(), "tool: -n: Value 11 not in range 0 to 10\n");

  CLI::App again{"test"};
  again.add_option("-o", out)->check(cli::path_given());
  args = {"tool", "-o", ""};
  argv.clear();
  for (auto& a : args) argv.push_back(a.data());
  captured.str("");
  old = std::cerr.rdbuf(captured.rdbuf());
  const auto empty = cli::parse(again, static_cast<int>(argv.size()), argv.data(), "tool");
  std::cerr.rdbuf(old);
  EXPECT_EQ(empty, 2);
  EXPECT_NE(captured.str().find("expected a path, got ''"), std::string::npos) << captured.str();
}

// The one comma list: every refusal in one wording naming the option and the text as given.
template <class T>
std::string list_error(std::vector<T>& values, cli::ListItem<T> item, std::vector<std::string> args) {
  CLI::App app;
  cli::add_list_option(app, "-l,--list", values, "a list", std::move(item));
  args.insert(args.begin(), "tool");
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  try {
    app.parse(static_cast<int>(argv.size()), argv.data());
  } catch (const CLI::ParseError& e) {
    return e.what();
  }
  return {};
}

TEST(Cli, CommaListsReadEveryItemOrRefuseTheWholeList) {
  std::vector<int> ints{7, 8};
  EXPECT_EQ(list_error(ints, cli::integers_in(1, 100), {}), "");
  EXPECT_EQ(ints, (std::vector<int>{7, 8})) << "not given: the defaults stay";
  EXPECT_EQ(list_error(ints, cli::integers_in(1, 100), {"--list", "1,100"}), "");
  EXPECT_EQ(ints, (std::vector<int>{1, 100}));
  EXPECT_EQ(list_error(ints, cli::integers_in(1, 100), {"--list", "3", "-l", "4,5"}), "");
  EXPECT_EQ(ints, (std::vector<int>{3, 4, 5})) << "a repeated option adds to the list";
  const std::string wording = "--list: expected an integer in [1, 100], or at most 64 separated by commas, got '";
  for (const std::string bad : {"", "1,,2", "1,", ",1", "0", "101", "2.5", "1e2", "abc", " 1", "+1", "-0x1", "99999999999999999999"}) {
    std::vector<int> v{7};
    EXPECT_EQ(list_error(v, cli::integers_in(1, 100), {"--list", bad}), wording + bad + "'") << bad;
    EXPECT_EQ(v, std::vector<int>{7}) << bad << ": nothing is half-read";
  }
  std::string sixty_five;
  for (int i = 0; i < 65; ++i) sixty_five += (i ? "," : "") + std::to_string(i + 1);
  EXPECT_NE(list_error(ints, cli::integers_in(1, 100), {"--list", sixty_five}).find("at most 64"), std::string::npos);
  const std::string sixty_four = sixty_five.substr(0, sixty_five.rfind(','));
  EXPECT_EQ(list_error(ints, cli::integers_in(1, 100), {"--list", sixty_four}), "");
  EXPECT_EQ(ints.size(), 64u);
  EXPECT_NE(list_error(ints, cli::integers_in(1, 100), {"--list", sixty_four, "--list", "99"}).find("at most 64"), std::string::npos)
      << "the cap counts every occurrence";
}

// Issue 45: `--resolution 64,64` rendered hard-64 twice into one directory, the second over the
// first. An item given twice is refused in every list, by value ("64" and "064", "0.5" and "5e-1"
// are the same render), over all occurrences of the option.
TEST(Cli, CommaListsRefuseAnItemGivenTwice) {
  std::vector<int> ints{7};
  for (const std::vector<std::string>& args : std::vector<std::vector<std::string>>{
           {"--list", "64,64"}, {"--list", "64,064"}, {"--list", "64,1,64"}, {"--list", "64", "--list", "64"}}) {
    SCOPED_TRACE(args[1]);
    const std::string e = list_error(ints, cli::integers_in(1, 100), args);
    EXPECT_EQ(e.rfind("--list: '", 0), 0u) << e;
    EXPECT_NE(e.find("' is given twice (each item once), got '"), std::string::npos) << e;
    EXPECT_EQ(ints, std::vector<int>{7}) << "nothing is half-read";
  }
  EXPECT_EQ(list_error(ints, cli::integers_in(1, 100), {"--list", "64,064"}),
            "--list: '064' is given twice (each item once), got '64,064'");
  std::vector<double> numbers;
  EXPECT_EQ(list_error(numbers, cli::numbers_in(0, 1), {"--list", "0.5,5e-1"}),
            "--list: '5e-1' is given twice (each item once), got '0.5,5e-1'");
  EXPECT_EQ(list_error(numbers, cli::numbers_in(0, 1), {"--list", "0.5,0.25"}), "");
  std::vector<std::uint64_t> seeds;
  EXPECT_NE(list_error(seeds, cli::non_negative_integers(), {"--list", "3,3"}).find("given twice"), std::string::npos);
  std::vector<std::string> names;
  EXPECT_NE(list_error(names, cli::names("a scene"), {"--list", "demo,demo"}).find("'demo' is given twice"), std::string::npos);
  EXPECT_NE(list_error(names, cli::one_of({"stair", "step"}), {"--list", "step", "--list", "step"}).find("'step' is given twice"),
            std::string::npos);
  EXPECT_EQ(list_error(names, cli::one_of({"stair", "step"}), {"--list", "step,stair"}), "");
}

// Issue 45: one number grammar for every list. strtod took ' 0.05' and '0x1p-4' where the integer
// lists refused ' 64', and read '1e-400' as 0.
TEST(Cli, OneNumberGrammarForEveryList) {
  for (const std::string good : {"0.05", "-1", "+2.5", "1e6", "1E-6", "2.5e+3", ".5", "5.", "0", "-0.0", "007"}) {
    const std::optional<double> v = cli::decimal(good);
    ASSERT_TRUE(v) << good;
    EXPECT_EQ(*v, std::strtod(good.c_str(), nullptr)) << good;
  }
  for (const std::string bad : {"", " 0.05", "0.05 ", "\t1", "0x1p-4", "0x10", "inf", "-inf", "nan", "infinity", "1e", "1e+",
                                "e5", ".", "-", "+", "--1", "+-1", "1.2.3", "1,5", "1e-400", "1e999", "-1e999", "1_000",
                                "\xd9\xa1"})
    EXPECT_FALSE(cli::decimal(bad)) << "'" << bad << "'";
  std::vector<double> numbers;
  for (const std::string bad : {" 0.05", "0x1p-4", "1e-400"})
    EXPECT_EQ(list_error(numbers, cli::numbers_in(0, 1), {"--list", bad}),
              "--list: expected a decimal number in [0, 1], or at most 64 separated by commas, got '" + bad + "'");
  EXPECT_EQ(list_error(numbers, cli::numbers_in(0, 1, cli::Bound::open), {"--list", "0"}),
            "--list: expected a decimal number in (0, 1], or at most 64 separated by commas, got '0'");
  EXPECT_EQ(list_error(numbers, cli::numbers_in(0, 1, cli::Bound::open), {"--list", "1,1e-300"}), "");
}

TEST(Cli, CommaListsOfNumbersNamesAndSeeds) {
  std::vector<double> numbers;
  EXPECT_EQ(list_error(numbers, cli::numbers_in(1e-6, 1e6), {"--list", "0.05,1e6,1e-6"}), "");
  EXPECT_EQ(numbers, (std::vector<double>{0.05, 1e6, 1e-6}));
  for (const std::string bad : {"nan", "inf", "-1", "1e7", "0.05x", "0,05;"})
    EXPECT_EQ(list_error(numbers, cli::numbers_in(1e-6, 1e6), {"--list", bad}),
              "--list: expected a decimal number in [1e-06, 1e+06], or at most 64 separated by commas, got '" + bad + "'");
  std::vector<std::uint64_t> seeds;
  EXPECT_EQ(list_error(seeds, cli::non_negative_integers(), {"--list", "0,18446744073709551615"}), "");
  EXPECT_EQ(seeds, (std::vector<std::uint64_t>{0, 18446744073709551615u}));
  for (const std::string bad : {"-1", "18446744073709551616", "1.0", ""})
    EXPECT_NE(list_error(seeds, cli::non_negative_integers(), {"--list", bad}).find("expected a non-negative integer"), std::string::npos)
        << bad << ": never wraps or saturates";
  std::vector<std::string> names;
  EXPECT_EQ(list_error(names, cli::one_of({"stair", "step"}), {"--list", "STAIR"}),
            "--list: expected stair or step, or at most 64 separated by commas, got 'STAIR'");
  EXPECT_EQ(list_error(names, cli::names("a pattern"), {"--list", "stair,step"}), "");
  EXPECT_EQ(names, (std::vector<std::string>{"stair", "step"}));
  EXPECT_EQ(list_error(names, cli::names("a pattern"), {"--list", "stair,"}),
            "--list: expected a pattern, or at most 64 separated by commas, got 'stair,'");
  const std::string control = std::string("a") + '\x01';
  EXPECT_NE(list_error(names, cli::names("a pattern"), {"--list", control + ",,"}).find("\\x01"), std::string::npos)
      << "a control byte is escaped in the error line";
}

TEST(AtomicFile, WritesWholeAndReplaces) {
  const fs::path dir = scratch("atomic");
  io::write_file_atomic(dir / "a.txt", "old");
  io::write_file_atomic(dir / "a.txt", "new text");
  EXPECT_EQ(read(dir / "a.txt"), "new text");
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 1);
  fs::remove_all(dir);
}

TEST(AtomicFile, RefusesToReplaceADirectoryOrADevice) {
  const fs::path dir = scratch("atomic-refuse");
  fs::create_directories(dir / "d");
  EXPECT_THROW(
      {
        try {
          io::write_file_atomic(dir / "d", "x");
        } catch (const std::runtime_error& e) {
          EXPECT_NE(std::string(e.what()).find("d: cannot write: exists and is not a regular file"), std::string::npos);
          throw;
        }
      },
      std::runtime_error);
  EXPECT_THROW(io::write_file_atomic("/dev/null", "x"), std::runtime_error);
  EXPECT_TRUE(fs::is_character_file("/dev/null"));
  EXPECT_THROW(io::write_file_atomic(dir / "missing" / "a.txt", "x"), std::runtime_error);
  fs::remove_all(dir);
}

// A full disk as write(2) sees it (a file-size limit): the errno of the write, not "Success" or a
// value left over from elsewhere, and the previous file untouched, no temporary left.
TEST(AtomicFile, AFailedWriteNamesItsReasonAndKeepsTheOldFile) {
  const fs::path dir = scratch("atomic-full");
  io::write_file_atomic(dir / "a.txt", "old");
  int pipe_fd[2];
  ASSERT_EQ(::pipe(pipe_fd), 0);
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::signal(SIGXFSZ, SIG_IGN);
    const rlimit limit{4096, 4096};
    ::setrlimit(RLIMIT_FSIZE, &limit);
    errno = ERANGE;  // a stale errno must not show
    std::string message = "no error";
    try {
      io::write_file_atomic(dir / "a.txt", std::string(100000, 'x'));
    } catch (const std::exception& e) {
      message = e.what();
    }
    (void)!::write(pipe_fd[1], message.data(), message.size());
    ::_exit(0);
  }
  ::close(pipe_fd[1]);
  std::string message;
  char buf[512];
  for (ssize_t n; (n = ::read(pipe_fd[0], buf, sizeof buf)) > 0;) message.append(buf, static_cast<std::size_t>(n));
  ::close(pipe_fd[0]);
  ::waitpid(pid, nullptr, 0);
  EXPECT_EQ(message, (dir / "a.txt").string() + ": cannot write: File too large");
  EXPECT_EQ(read(dir / "a.txt"), "old");
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 1);
  fs::remove_all(dir);
}

// Issue 27: one rule for every output path, and no file of ours reached through a link.
TEST(SafePath, OneRuleForEveryOutput) {
  const fs::path d = scratch("outputs");
  auto refusal = [](const fs::path& p, io::OutputKind kind, const std::string& marker = "") {
    try {
      io::check_output(p, kind, marker);
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_EQ(refusal(d / "new", io::OutputKind::directory), "accepted");
  EXPECT_EQ(refusal(d / "new.json", io::OutputKind::file), "accepted");
  EXPECT_EQ(refusal(d / "a" / "b" / "c.json", io::OutputKind::file),
            (d / "a" / "b" / "c.json").string() + ": the folder " + (d / "a" / "b").string() +
                " does not exist (create it first: an output never creates the folders above it)");
  EXPECT_FALSE(fs::exists(d / "a"));
  std::ofstream(d / "file") << "x";
  EXPECT_EQ(refusal(d / "file" / "out", io::OutputKind::directory), (d / "file" / "out").string() + ": " + (d / "file").string() + " is not a folder");
  EXPECT_EQ(refusal(d / "file", io::OutputKind::directory), (d / "file").string() + ": exists and is not a directory");
  EXPECT_EQ(refusal(d / "file", io::OutputKind::file), "accepted");
  fs::create_directories(d / "full");
  std::ofstream(d / "full" / "notes.txt") << "x";
  EXPECT_EQ(refusal(d / "full", io::OutputKind::directory), (d / "full").string() + ": exists and is not empty; choose a new output directory");
  EXPECT_EQ(refusal(d / "full", io::OutputKind::directory, "report.json"),
            (d / "full").string() + ": exists and is not a previous output (no report.json); choose another output directory");
  std::ofstream(d / "full" / "report.json") << "{}";
  EXPECT_EQ(refusal(d / "full", io::OutputKind::directory, "report.json"), "accepted");
  EXPECT_EQ(refusal(d / "full/", io::OutputKind::directory, "report.json"), "accepted");
  fs::create_symlink(d / "full", d / "link");
  EXPECT_EQ(refusal(d / "link", io::OutputKind::directory, "report.json"),
            (d / "link").string() + ": is a symbolic link; refusing to follow it (an output is written where it is named, not through a link)");
  fs::create_symlink(d / "file", d / "file-link");
  EXPECT_EQ(refusal(d / "file-link", io::OutputKind::file).rfind((d / "file-link").string() + ": is a symbolic link", 0), 0u);
  // The staged directory and the atomic file keep to it.
  EXPECT_THROW(io::StagedDirectory((d / "link").string(), "report.json"), std::runtime_error);
  EXPECT_THROW(io::StagedDirectory((d / "x" / "y").string(), "report.json"), std::runtime_error);
  EXPECT_FALSE(fs::exists(d / "x"));
  EXPECT_THROW(io::write_file_atomic(d / "file-link", "new"), std::runtime_error);
  EXPECT_EQ(read(d / "file"), "x");
  fs::remove_all(d);
}

TEST(SafePath, ReadingRefusesLinksAndNamesWhatIsNotAFile) {
  const fs::path d = scratch("reading");
  std::ofstream(d / "log.csv") << "a,b\n";
  fs::create_symlink(d / "log.csv", d / "link.csv");
  EXPECT_EQ(io::read_file(d / "log.csv", 100, io::Links::refuse), "a,b\n");
  EXPECT_EQ(io::read_file(d / "link.csv", 100, io::Links::follow), "a,b\n");
  auto message = [](auto&& f) {
    try {
      f();
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_EQ(message([&] { io::read_file(d / "link.csv", 100, io::Links::refuse); }),
            (d / "link.csv").string() + ": is a symbolic link; refusing to follow it (give the file itself)");
  EXPECT_EQ(message([&] { io::read_file("/dev/null", 100); }), "/dev/null: cannot read: not a regular file");
  EXPECT_EQ(message([&] { io::read_file(d, 100); }), d.string() + ": cannot read: not a regular file (a directory)");
  EXPECT_EQ(message([&] { io::read_file(d / "none", 100); }), (d / "none").string() + ": cannot read: no such file");
  EXPECT_EQ(message([&] { io::read_file(d / "log.csv", 2); }), (d / "log.csv").string() + ": larger than 2 bytes (4)");
  // A kill's temporaries (their process gone) are removed beside the target, a live one's kept.
  std::ofstream(d / ".session.json.partial-999999999") << "{";
  std::ofstream(d / (".session.json.partial-" + std::to_string(::getpid()))) << "{";
  fs::create_directories(d / "out.partial-999999998");
  io::remove_abandoned_partials(d / "session.json");
  io::remove_abandoned_partials(d / "out");
  EXPECT_FALSE(fs::exists(d / ".session.json.partial-999999999"));
  EXPECT_FALSE(fs::exists(d / "out.partial-999999998"));
  EXPECT_TRUE(fs::exists(d / (".session.json.partial-" + std::to_string(::getpid()))));
  fs::remove_all(d);
}

// Issue 27: one rule for exit codes. A UsageError or a line that begins with an option's name is
// the command line's fault (2); a line that begins with a file is the data's (1).
TEST(Cli, ExitCodesFollowOneRule) {
  EXPECT_EQ(cli::exit_code(std::invalid_argument("--seed 5: the session was run with seed 3")), cli::kExitUsage);
  EXPECT_EQ(cli::exit_code(std::runtime_error("-o: not with --resume")), cli::kExitUsage);
  EXPECT_EQ(cli::exit_code(cli::UsageError("two options that contradict each other")), cli::kExitUsage);
  EXPECT_EQ(cli::exit_code(std::runtime_error("study.json: stopping.min_trials: expected an integer")), cli::kExitError);
  EXPECT_EQ(cli::exit_code(std::runtime_error("-0.5 is not a luminance")), cli::kExitError);
  EXPECT_EQ(cli::exit_code(std::invalid_argument("--")), cli::kExitError);
}

}  // namespace
