// Issue 14.9: every app's error is one line "<tool>: ..." naming the file or option and what was
// expected, with exit 2 for a command line that cannot be parsed and 1 otherwise. Before: CLI11's
// two lines and exit codes 104-114, library text (json type_error.316 for a path with a byte
// that is not UTF-8, "filesystem error: cannot rename" after a whole render for -o ""), the wrong
// field blamed (--size-px 0 blamed filter_radius_px, --guess 1 blamed --lapse-max), a directory
// given as a file read as "no data rows" or "no header", megabyte values and control bytes echoed
// whole, and a write that failed on a full disk (simulated here by a file-size limit) named
// errno left over from elsewhere.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "data/simulate.h"
#include "log/trial_log.h"
#include "subprocess.h"

namespace {

namespace fs = std::filesystem;
using namespace penumbra;

const std::string kStudy = PENUMBRA_STUDY_EXE, kFit = PENUMBRA_FIT_EXE, kQuest = PENUMBRA_QUEST_EXE,
                  kRender = PENUMBRA_RENDER_EXE, kScene = PENUMBRA_SCENE_EXE, kBench = PENUMBRA_BENCH_EXE,
                  kCurve = PENUMBRA_OBSERVER_CURVE_EXE, kObserverFit = PENUMBRA_OBSERVER_FIT_EXE,
                  kDemo = PENUMBRA_DEMO_EXE;
const std::string kConfig = PENUMBRA_DATA_DIR "/studies/default.json";

// A scratch directory per test, removed at the end.
class Scratch {
 public:
  explicit Scratch(const std::string& name)
      : dir_(fs::temp_directory_path() / ("penumbra-errors-" + name + "-" + std::to_string(::getpid()))) {
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  ~Scratch() { fs::remove_all(dir_); }
  const fs::path& dir() const { return dir_; }
  fs::path operator/(const std::string& name) const { return dir_ / name; }

 private:
  fs::path dir_;
};

// The contract of an error: the status, one line on stderr starting with "<tool>: ", holding
// `expected`, short, with no control bytes and none of the libraries' own wording.
void expect_one_line(const test::Result& r, int status, const std::string& tool, const std::string& expected) {
  EXPECT_EQ(r.exit_code, status) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err.substr(0, 2000);
  EXPECT_EQ(r.err.rfind(tool + ": ", 0), 0u) << r.err.substr(0, 2000);
  EXPECT_NE(r.err.find(expected), std::string::npos) << "expected '" << expected << "' in: " << r.err.substr(0, 2000);
  EXPECT_LT(r.err.size(), 1200u) << r.err.substr(0, 2000);
  for (char c : r.err.substr(0, r.err.size() - 1))
    EXPECT_FALSE(static_cast<unsigned char>(c) < 0x20 || c == 0x7f) << "control byte in: " << r.err.substr(0, 2000);
  for (const char* leak : {"json.exception", "filesystem error", "basic_filebuf", "Run with --help", "(Success)",
                           "std::", "what():"})
    EXPECT_EQ(r.err.find(leak), std::string::npos) << leak << " in: " << r.err.substr(0, 2000);
}

test::Result run(const std::string& exe, const std::vector<std::string>& args, const Scratch& scratch) {
  return test::run_exe(exe, args, scratch.dir());
}

// `exe args...` with writes limited to `kib` KiB per file (RLIMIT_FSIZE, SIGXFSZ ignored): a
// full disk for every file the process writes, as far as write(2) can tell.
test::Result run_with_file_limit(int kib, const std::string& exe, std::vector<std::string> args, const Scratch& scratch) {
  args.insert(args.begin(), {"-c", "trap '' XFSZ; ulimit -f " + std::to_string(2 * kib) + "; exec \"$0\" \"$@\"", exe});
  return test::run_exe("/bin/sh", args, scratch.dir());
}

// `exe args...` in a child whose address space is limited to `bytes` (fork, setrlimit(RLIMIT_AS),
// exec): out of memory as `ulimit -v` makes it, for the CPU and, on software GL, the GPU.
test::Result run_with_address_limit(std::uint64_t bytes, const std::string& exe, const std::vector<std::string>& args,
                                    const Scratch& scratch) {
  const fs::path out_file = scratch / "stdout.txt", err_file = scratch / "stderr.txt";
  std::vector<std::string> argv_s = {exe};
  argv_s.insert(argv_s.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& a : argv_s) argv.push_back(a.data());
  argv.push_back(nullptr);
  const pid_t pid = ::fork();
  if (pid == 0) {
    const int in = ::open("/dev/null", O_RDONLY), out = ::open(out_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644),
              err = ::open(err_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    ::dup2(in, STDIN_FILENO);
    ::dup2(out, STDOUT_FILENO);
    ::dup2(err, STDERR_FILENO);
    const rlimit limit{bytes, bytes};
    if (::setrlimit(RLIMIT_AS, &limit) != 0) ::_exit(126);
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  test::Result r;
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0) {
  }
  if (WIFEXITED(status)) r.exit_code = WEXITSTATUS(status);
  else r.err = "killed by signal " + std::to_string(WTERMSIG(status)) + "\n";
  r.out = test::read_file(out_file);
  r.err += test::read_file(err_file);
  return r;
}

std::vector<fs::path> simulated_sessions(const fs::path& dir, int participants) {
  analysis::SimulatedStudy s;
  s.participants = participants;
  s.trials_per_staircase = 20;
  s.seed = 5;
  return analysis::write_sessions(s, analysis::simulate_study(s), dir);
}

std::string read(const fs::path& p) { return test::read_file(p); }

// The longest single argument Linux passes (MAX_ARG_STRLEN is 128 KiB); files carry longer ones.
const std::string kHuge(120000, 'x');

TEST(ErrorLines, CommandLinesThatCannotBeParsedAreOneLineAndExit2) {
  const Scratch s("usage");
  const std::vector<std::pair<std::string, std::vector<std::string>>> cases = {
      {kStudy, {"run", "--bogus"}},
      {kStudy, {}},
      {kStudy, {"run", "--pace-ms", "-5"}},
      {kStudy, {"run", "--headless", "--stop-after", kHuge}},
      {kFit, {"--bogus"}},
      {kFit, {"x", "-o"}},
      {kFit, {"psychometric"}},
      {kQuest, {"replay", "--bogus"}},
      {kRender, {"--width", "0", "-o", (s / "r").string()}},
      {kScene, {"--bogus"}},
      {kBench, {"--bogus", "-o", (s / "b").string()}},
      {kCurve, {"--bogus"}},
      {kObserverFit, {"--bogus"}},
      {kObserverFit, {"--human", "step/1=3.47"}},
  };
  for (const auto& [exe, args] : cases) {
    const std::string tool = fs::path(exe).filename().string();
    SCOPED_TRACE(tool + (args.empty() ? "" : " " + args[0].substr(0, 40)));
    const test::Result r = run(exe, args, s);
    expect_one_line(r, 2, tool == "penumbra-quest" ? "penumbra-quest: error" : tool, "");
  }
  // --help is not an error.
  EXPECT_EQ(run(kFit, {"--help"}, s).exit_code, 0);
  EXPECT_EQ(run(kStudy, {"run", "--help"}, s).exit_code, 0);
}

// -o "" ran the whole job and failed at the rename ("filesystem error: cannot rename ... []").
TEST(ErrorLines, AnEmptyOutputPathIsRefusedBeforeAnyWork) {
  const Scratch s("empty-output");
  const auto sessions = simulated_sessions(s / "sessions", 1);
  const std::vector<std::pair<std::string, std::vector<std::string>>> cases = {
      {kRender, {"--scene", "demo", "-o", ""}},
      {kScene, {"--scene", "demo", "-o", ""}},
      {kBench, {"--quick", "-o", ""}},
      {kFit, {sessions[0].string(), "-o", ""}},
      {kStudy, {"run", "--config", kConfig, "--headless", "-o", ""}},
      {kStudy, {"stimulus", "--artifact-px", "10", "--filter-radius-px", "20", "-o", ""}},
      {kStudy, {"reference", "-o", ""}},
  };
  for (const auto& [exe, args] : cases) {
    const std::string tool = fs::path(exe).filename().string();
    SCOPED_TRACE(tool);
    expect_one_line(run(exe, args, s), 2, tool, "expected a path, got ''");
  }
  std::vector<std::string> left;
  for (const auto& e : fs::directory_iterator(s.dir())) left.push_back(e.path().filename().string());
  EXPECT_EQ(left, std::vector<std::string>{"sessions"});
}

TEST(ErrorLines, TheFieldThatIsWrongIsTheOneBlamed) {
  const Scratch s("blame");
  std::ofstream(s / "counts.csv") << "level,n_correct,n_total\n-1,5,10\n0,9,10\n";
  expect_one_line(run(kStudy, {"stimulus", "--artifact-px", "10", "--filter-radius-px", "20", "--size-px", "0", "-o",
                               (s / "st").string()},
                      s),
                  2, "penumbra-study", "--size-px: expected 16..4096");  // the option to change, not the spec's field
  EXPECT_FALSE(fs::exists(s / "st"));
  expect_one_line(run(kFit, {"psychometric", "--input", (s / "counts.csv").string(), "--guess", "1"}, s), 2,
                  "penumbra-fit", "--guess: expected a rate in [0, 1)");
  const auto sessions = simulated_sessions(s / "sessions", 1);
  expect_one_line(run(kFit, {sessions[0].string(), "-o", (s / "out").string(), "--guess", "1"}, s), 2, "penumbra-fit",
                  "--guess: expected a rate in [0, 1)");
  // QUEST's own refusal of a session.json value, with the file and block named.
  nlohmann::json session = nlohmann::json::parse(read(sessions[0] / "session.json"));
  session["quest"]["grain"] = 0;
  std::ofstream(sessions[0] / "session.json", std::ios::trunc) << session.dump();
  expect_one_line(run(kFit, {sessions[0].string(), "-o", (s / "out").string()}, s), 1, "penumbra-fit",
                  "session.json: quest: grain must be positive");
  session["quest"]["dim"] = 1e12;
  std::ofstream(sessions[0] / "session.json", std::ios::trunc) << session.dump();
  expect_one_line(run(kFit, {sessions[0].string(), "-o", (s / "out").string()}, s), 1, "penumbra-fit",
                  "session.json: quest.dim: expected an integer in [2, 1e7]");
  EXPECT_FALSE(fs::exists(s / "out"));
}

TEST(ErrorLines, ADirectoryGivenAsAFileIsNamedAsOne) {
  const Scratch s("directory");
  fs::create_directories(s / "dir.json");
  const auto sessions = simulated_sessions(s / "sessions", 1);
  fs::remove(sessions[0] / "trials.csv");
  fs::create_directories(sessions[0] / "trials.csv");
  expect_one_line(run(kStudy, {"run", "--config", (s / "dir.json").string(), "--headless", "-o", (s / "p").string()}, s),
                  1, "penumbra-study", "dir.json: cannot read: not a regular file");
  EXPECT_FALSE(fs::exists(s / "p"));
  expect_one_line(run(kFit, {"psychometric", "--input", (s / "dir.json").string()}, s), 1, "penumbra-fit",
                  "dir.json: cannot read: not a regular file");
  expect_one_line(run(kFit, {sessions[0].string(), "-o", (s / "out").string()}, s), 1, "penumbra-fit",
                  "trials.csv: cannot read: not a regular file (a directory)");
  expect_one_line(run(kFit, {sessions[0].string(), "-o", (s / "out").string(), "--reference", (s / "dir.json").string()}, s),
                  1, "penumbra-fit", "dir.json: cannot read: not a regular file");
  expect_one_line(run(kRender, {"--scene", (s / "dir.json").string(), "-o", (s / "r").string()}, s), 1, "penumbra-render",
                  "dir.json: cannot read scene file: not a regular file");
  EXPECT_FALSE(fs::exists(s / "out"));
  EXPECT_FALSE(fs::exists(s / "r"));
}

// Names and paths that are not UTF-8: a path is recorded with U+FFFD in its place (the JSON
// library threw type_error.316 after the work was done); a participant name is refused.
TEST(ErrorLines, BytesThatAreNotUtf8) {
  const Scratch s("utf8");
  const auto sessions = simulated_sessions(s / "sessions", 1);
  const fs::path odd = s / "odd\xff-session";
  fs::rename(sessions[0], odd);
  test::Result r = run(kFit, {odd.string(), "-o", (s / "fit").string(), "--bootstrap", "0"}, s);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json report = nlohmann::json::parse(read(s / "fit" / "report.json"));
  EXPECT_NE(report["inputs"][0].get<std::string>().find("odd\xef\xbf\xbd-session"), std::string::npos);

  const fs::path config = s / "config\xff.json";
  fs::copy_file(kConfig, config);
  r = run(kStudy, {"run", "--config", config.string(), "--headless", "--stop-after", "3", "-o", (s / "p1").string()}, s);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NO_THROW(nlohmann::json::parse(read(s / "p1" / "session.json")));

  expect_one_line(run(kStudy, {"run", "--config", kConfig, "--headless", "--participant", "p\xff", "-o",
                               (s / "p2").string()},
                      s),
                  1, "penumbra-study", "participant 'p\\xff': expected a non-empty UTF-8 name");
  EXPECT_FALSE(fs::exists(s / "p2"));

  // A log field that is not UTF-8: refused naming line and column, nothing written.
  const auto more = simulated_sessions(s / "more", 1);
  std::string log = read(more[0] / "trials.csv");
  log.replace(log.find("p01,"), 4, "p0\xff,");
  log.replace(log.find("p01,"), 4, "p0\xff,");
  std::ofstream(more[0] / "trials.csv", std::ios::trunc) << log;
  fs::remove(more[0] / "session.json");
  expect_one_line(run(kFit, {more[0].string(), "-o", (s / "fit2").string()}, s), 1, "penumbra-fit",
                  "trials.csv:2: column 'participant': expected UTF-8 text");
  EXPECT_FALSE(fs::exists(s / "fit2"));
}

// A huge value or control bytes in an option or a file come back shortened and escaped.
TEST(ErrorLines, HugeValuesAndControlBytesAreNotEchoedWhole) {
  const Scratch s("echo");
  std::ofstream(s / "counts.csv") << "level,n_correct,n_total\n-1,5,10\n0,9,10\n";
  const std::string input = (s / "counts.csv").string();
  const std::string digits(100000, '1');
  nlohmann::json config = nlohmann::json::parse(read(kConfig));
  config["task"] = std::string(500000, 't');
  std::ofstream(s / "config.json") << config.dump();
  const std::vector<std::tuple<std::string, std::vector<std::string>, int, std::string>> cases = {
      {kFit, {"psychometric", "--input", input, "--family", kHuge}, 2, "--family 'xxxxx"},
      {kFit, {"psychometric", "--input", input, "--format", "a\x01\x1b[31mred"}, 2, "--format 'a\\x01\\x1b[31mred'"},
      {kFit, {"psychometric", "--input", input, "--family", std::string(5000, 'a') + " " + std::string(5000, 'b')}, 2,
       "--family"},
      {kStudy, {"stimulus", "--artifact-px", "10", "--filter-radius-px", "20", "--kernel", kHuge, "-o",
                (s / "st").string()}, 2, "--kernel: kernel 'xxxx"},
      {kStudy, {"run", "--config", kConfig, "--headless", "--observer", "psychometric:c=" + kHuge, "-o",
                (s / "p").string()}, 2, "--observer"},
      {kStudy, {"run", "--config", kConfig, "--headless", "--pace-ms", digits, "-o", (s / "p").string()}, 2, "--pace-ms"},
      {kStudy, {"run", "--config", (s / "config.json").string(), "--headless", "-o", (s / "p").string()}, 1,
       "config.json: task"},
      {kQuest, {"replay", "--tguess", "-1", "--tguess-sd", "2", "--pthreshold", "0.82", "--beta", "3.5", "--delta",
                "0.01", "--gamma", "0.5", "--responses", "0,1," + digits}, 2, "--responses: item 3 is '1111"},
      {kRender, {"--scene", kHuge, "-o", (s / "r").string()}, 1, "unknown built-in scene 'xxxx"},
      {kRender, {"--pcf.radius", "\x07" + kHuge, "-o", (s / "r").string()}, 2, "--pcf.radius"},
  };
  for (const auto& [exe, args, status, expected] : cases) {
    std::string tool = fs::path(exe).filename().string();
    SCOPED_TRACE(tool + " " + expected);
    if (tool == "penumbra-quest") tool += ": error";
    expect_one_line(run(exe, args, s), status, tool, expected);
  }
  EXPECT_FALSE(fs::exists(s / "p"));
  EXPECT_FALSE(fs::exists(s / "st"));
}

// A full disk, simulated by a file-size limit: one line naming the file and the system's reason,
// exit 1, the previous output untouched, nothing half-written (no staging directory, no
// temporary file). A session stops with a torn last line at most, and --resume finishes it.
TEST(ErrorLines, AFullDiskIsOneLineAndLeavesThePreviousOutput) {
  const Scratch s("full");
  const auto sessions = simulated_sessions(s / "sessions", 2);
  // --no-progress: the fit's progress lines (written to a log as whole lines) are not the error line.
  const std::vector<std::string> fit = {sessions[0].string(), sessions[1].string(), "-o", (s / "fit").string(),
                                        "--bootstrap", "0", "--no-progress"};
  ASSERT_EQ(run(kFit, fit, s).exit_code, 0);
  const std::string report = read(s / "fit" / "report.json"), calibration = read(s / "fit" / "calibration.json");
  expect_one_line(run_with_file_limit(4, kFit, fit, s), 1, "penumbra-fit", "report.json: cannot write: File too large");
  EXPECT_EQ(read(s / "fit" / "report.json"), report);
  EXPECT_EQ(read(s / "fit" / "calibration.json"), calibration);

  const std::vector<std::string> session = {"run", "--config", kConfig, "--headless", "-o", (s / "p").string()};
  expect_one_line(run_with_file_limit(8, kStudy, session, s), 1, "penumbra-study", "trials.csv: cannot append trial");
  const trial_log::ReadResult cut = trial_log::read(s / "p" / "trials.csv");
  EXPECT_GT(cut.rows.size(), 10u);
  const test::Result resumed = run(kStudy, {"run", "--resume", (s / "p").string(), "--headless"}, s);
  ASSERT_EQ(resumed.exit_code, 0) << resumed.err;
  EXPECT_GT(trial_log::read(s / "p" / "trials.csv").rows.size(), cut.rows.size());

  // No session at all when session.json cannot be written: the next try is not refused.
  expect_one_line(run_with_file_limit(1, kStudy, {"run", "--config", kConfig, "--headless", "-o", (s / "q").string()}, s),
                  1, "penumbra-study", "session.json: cannot write: File too large");
  EXPECT_FALSE(fs::exists(s / "q"));

  // The image writers ignored a failed write; the encoded image now goes through write(2).
  expect_one_line(run_with_file_limit(1, kRender, {"--scene", "box", "--technique", "hard", "--resolution", "256",
                                                    "--width", "320", "--height", "240", "--frames", "1", "-o",
                                                    (s / "render").string()},
                                      s),
                  1, "penumbra-render", "lit.png: cannot write: File too large");
  // Issue 27: a stimulus directory is committed whole: a full disk left the new artifact.png beside
  // the old line.png and stimulus.json (and, for a new directory, an empty one).
  const std::vector<std::string> stimulus = {"stimulus", "--artifact-px", "10", "--filter-radius-px", "20", "--size-px", "1024",
                                             "-o", (s / "stim").string()};
  ASSERT_EQ(run(kStudy, stimulus, s).exit_code, 0);
  const std::string line_png = read(s / "stim" / "line.png"), artifact_png = read(s / "stim" / "artifact.png");
  std::vector<std::string> other = stimulus;
  other[2] = "5";  // another artifact size: other images
  expect_one_line(run_with_file_limit(1, kStudy, other, s), 1, "penumbra-study", "artifact.png: cannot write: File too large");
  EXPECT_EQ(read(s / "stim" / "artifact.png"), artifact_png);
  EXPECT_EQ(read(s / "stim" / "line.png"), line_png);
  other.back() = (s / "stim-new").string();
  expect_one_line(run_with_file_limit(1, kStudy, other, s), 1, "penumbra-study", "artifact.png: cannot write: File too large");
  std::vector<std::string> left;
  for (const auto& e : fs::directory_iterator(s.dir())) left.push_back(e.path().filename().string());
  std::sort(left.begin(), left.end());
  EXPECT_EQ(left, (std::vector<std::string>{"fit", "p", "sessions", "stim"}));
  for (const auto& e : fs::recursive_directory_iterator(s / "fit"))
    EXPECT_EQ(e.path().filename().string().find("partial"), std::string::npos) << e.path();
}

// Issue 27: errors that were unclear, each with the line it must print now.
TEST(ErrorLines, UnclearErrorsOfTheSecondCampaignNameTheirCause) {
  const Scratch s("unclear");
  std::ofstream(s / "file.txt") << "x\n";
  std::ofstream(s / "readings.csv") << "level,luminance_cd_m2\n0,0.5\n64,8.4\n128,26.6\n191,61\n255,120.5\n";
  const auto sessions = simulated_sessions(s / "sessions", 1);
  {
    std::string log = read(sessions[0] / "trials.csv");
    for (std::size_t at = log.find('\n'); at != std::string::npos; at = log.find('\n', at + 2)) log.insert(at, "\r");
    std::ofstream(s / "crlf.csv", std::ios::binary) << log;
    std::ofstream(s / "header-only.csv") << trial_log::header_line();
  }
  std::ofstream(s / "bad.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n";
  std::ofstream(s / "obj.json") << R"({"objects": [{"shape": "model", "path": "bad.obj"}]})" << "\n";
  struct Case {
    std::string exe;
    std::vector<std::string> args;
    int status;
    std::string line;
  };
  const std::vector<Case> cases = {
      // was: filesystem error: cannot create directories: Not a directory [...]
      {kStudy, {"run", "--config", kConfig, "--headless", "-o", (s / "file.txt" / "p").string()}, 1,
       (s / "file.txt" / "p").string() + ": " + (s / "file.txt").string() + " is not a folder"},
      // was: the valid CSV blamed for another option
      {kStudy, {"calibrate-display", "--luminances", (s / "readings.csv").string(), "--levels", "9", "-o", (s / "cal.json").string()}, 2,
       "--levels: not with --luminances (the readings are in the file; --levels is for the window)"},
      // was: "/dev/null" called missing
      {kStudy, {"display-check", "--config", "/dev/null"}, 1, "/dev/null: cannot read: not a regular file"},
      // was: a header mismatch without the cause
      {kFit, {(s / "crlf.csv").string(), "-o", (s / "fit").string()}, 1,
       (s / "crlf.csv").string() + ":1: lines end with \\r\\n (saved on Windows?); the log ends its lines with \\n only"},
      // was: "no trials to fit" without a file
      {kFit, {(s / "header-only.csv").string(), "-o", (s / "fit").string()}, 1,
       (s / "header-only.csv").string() + ": no trials to fit (only headers, practice rows or catch trials)"},
      // was: Assimp's own text without a line ("OBJ: vertex index out of range")
      {kRender, {"--scene", (s / "obj.json").string(), "-o", (s / "r").string()}, 1,
       (s / "obj.json").string() + ": objects[0].path: cannot read model bad.obj:4: face index 7 is out of range (3 vertices before this line)"},
      // was: exit 1 where -o "" exits 2
      {kRender, {"--calibration", "", "-o", (s / "r").string()}, 2, "--calibration: expected a path, got ''"},
      // was: checked only after the whole run
      {kBench, {"--quick", "--python", (s / "no-python").string(), "-o", (s / "b").string()}, 2,
       "--python " + (s / "no-python").string() + ": not an executable file (give its path, or --no-plot to skip the plots)"},
      // was: taken and ignored
      {kRender, {"--technique", "hard", "--vsm.radius", "3", "-o", (s / "r").string()}, 2,
       "--vsm.radius: a parameter of vsm, which --technique hard does not render"},
      {kCurve, {"--technique", "pcf", "--set", "pcf.kernel=grid", "--set", "pcf.kernel=disk", "--json", (s / "c.json").string()}, 2,
       "--set pcf.kernel: given twice"},
  };
  for (const Case& c : cases) {
    std::string tool = fs::path(c.exe).filename().string();
    SCOPED_TRACE(tool + " " + c.line);
    expect_one_line(run(c.exe, c.args, s), c.status, tool, c.line);
  }
  EXPECT_FALSE(fs::exists(s / "fit"));
  EXPECT_FALSE(fs::exists(s / "cal.json"));
  EXPECT_FALSE(fs::exists(s / "r"));
  EXPECT_FALSE(fs::exists(s / "b"));
  EXPECT_FALSE(fs::exists(s / "c.json"));
}

// Issue 45: every comma list refuses an item given twice (`--resolution 64,64` rendered hard-64
// twice into one directory, the second over the first), by the one number grammar (strtod took
// ' 0.05' and '0x1p-4'), and a name it does not know while parsing: the option named, exit 2
// (`--scenes nope`, `--techniques nope`, `--pattern STAIR`, `--contrast 1e-400` exited 1 naming none).
TEST(ErrorLines, CommaListsRefuseRepeatsBadNumbersAndUnknownNamesNamingTheOption) {
  const Scratch s("lists");
  const std::string out = (s / "out").string(), json = (s / "c.json").string();
  struct Case {
    std::string exe;
    std::vector<std::string> args;
    std::string line;
  };
  const std::vector<Case> cases = {
      // An item given twice, in each of the twelve lists.
      {kRender, {"--resolution", "64,64", "-o", out}, "--resolution: '64' is given twice (each item once), got '64,64'"},
      {kBench, {"--scenes", "demo,box,demo", "-o", out}, "--scenes: 'demo' is given twice"},
      {kBench, {"--techniques", "pcf,pcf", "-o", out}, "--techniques: 'pcf' is given twice"},
      {kBench, {"--resolutions", "64,128", "--resolutions", "64", "-o", out}, "--resolutions: '64' is given twice"},
      {kBench, {"--radii", "0.05,5e-2", "-o", out}, "--radii: '5e-2' is given twice"},
      {kDemo, {"--headless", "--techniques", "pcss,pcss", "-o", out}, "--techniques: 'pcss' is given twice"},
      {kStudy, {"reference", "--pattern", "stair,stair", "-o", json}, "--pattern: 'stair' is given twice"},
      {kStudy, {"reference", "--contrast", "1,1.0", "-o", json}, "--contrast: '1.0' is given twice"},
      {kStudy, {"reference", "--artifact-px", "5,5", "-o", json}, "--artifact-px: '5' is given twice"},
      {kStudy, {"reference", "--seeds", "1,2,1", "-o", json}, "--seeds: '1' is given twice"},
      {kCurve, {"--pattern", "step,step", "--json", json}, "--pattern: 'step' is given twice"},
      {kCurve, {"--artifact-px", "10,10", "--json", json}, "--artifact-px: '10' is given twice"},
      {kCurve, {"--contrast", "0.5,0.5", "--json", json}, "--contrast: '0.5' is given twice"},
      // One number grammar: no whitespace, hexadecimal, or values strtod rounds to 0.
      {kRender, {"--resolution", " 64", "-o", out}, "--resolution: expected an integer in [1, 65536]"},
      {kBench, {"--radii", " 0.05", "-o", out}, "--radii: expected a decimal number in [1e-06, 1e+06]"},
      {kStudy, {"reference", "--contrast", "0x1p-4", "-o", json}, "--contrast: expected a decimal number in (0, 1]"},
      {kStudy, {"reference", "--contrast", "1e-400", "-o", json}, "--contrast: expected a decimal number in (0, 1]"},
      {kCurve, {"--contrast", "0", "--json", json}, "--contrast: expected a decimal number in (0, 1]"},
      {kCurve, {"--artifact-px", "inf", "--json", json}, "--artifact-px: expected a decimal number in [1, 1000]"},
      // Names the list does not know, refused while parsing.
      {kBench, {"--scenes", "nope", "-o", out}, "--scenes: expected a built-in scene (demo, box"},
      {kBench, {"--techniques", "nope", "-o", out}, "--techniques: expected hard, pcf"},
      {kDemo, {"--headless", "--techniques", "nope", "-o", out}, "--techniques: expected hard, pcf"},
      {kStudy, {"reference", "--pattern", "STAIR", "-o", json}, "--pattern: expected stair or step, or at most 64"},
      {kCurve, {"--pattern", "STAIR", "--json", json}, "--pattern: expected stair or step, or at most 64"},
  };
  for (const Case& c : cases) {
    const std::string tool = fs::path(c.exe).filename().string();
    SCOPED_TRACE(tool + " " + c.line);
    expect_one_line(run(c.exe, c.args, s), 2, tool, c.line);
  }
  EXPECT_FALSE(fs::exists(s / "out"));
  EXPECT_FALSE(fs::exists(s / "c.json"));
}

// Issue 45: values refused after parsing name their option and exit 2; paths are said as what
// they are, with their control characters escaped.
TEST(ErrorLines, ValuesRefusedAfterParsingNameTheirOption) {
  const Scratch s("after-parsing");
  const std::string out = (s / "out").string();
  std::ofstream(s / "counts.csv") << "level,n_correct,n_total\n-1,5,10\n0,9,10\n";
  const auto sessions = simulated_sessions(s / "sessions", 1);
  fs::create_directories(s / "folder.obj");
  std::ofstream(s / "dir-model.json") << R"({"objects": [{"shape": "model", "path": "folder.obj"}]})" << "\n";
  std::ofstream(s / "null-model.json") << R"({"objects": [{"shape": "model", "path": "/dev/null"}]})" << "\n";
  const std::string newline = (s / "a\nb.json").string(), tab = (s / "c\tounts.csv").string();
  struct Case {
    std::string exe;
    std::vector<std::string> args;
    int status;
    std::string line;
  };
  const std::vector<Case> cases = {
      // was: "the shadow map's frame is not finite" (exit 1) at 180° and 1e6°; 400° rendered as 40°
      {kRender, {"--light-size", "180", "-o", out}, 2,
       "--light-size 180: a directional light's angular diameter must lie in [0, 90] degrees (the sun's is 0.53)"},
      {kRender, {"--light-size", "1e6", "-o", out}, 2, "--light-size 1e+06: a directional light's angular diameter"},
      {kRender, {"--light-size", "400", "-o", out}, 2, "--light-size 400: a directional light's angular diameter"},
      {kDemo, {"--headless", "--light-size", "90.5", "-o", out}, 2, "--light-size 90.5: a directional light's angular diameter"},
      // was: the valid counts file blamed (exit 1), and with a session no option named
      {kFit, {"psychometric", "--input", (s / "counts.csv").string(), "--p-threshold", "0.5"}, 2,
       "--p-threshold 0.5: expected a proportion correct in (0.5, 1), above the guess rate"},
      {kFit, {sessions[0].string(), "-o", out, "--no-progress", "--p-threshold", "0.5"}, 2,
       "--p-threshold 0.5: expected a proportion correct between the guess rate 0.5 and 0.995"},
      {kFit, {sessions[0].string(), "-o", out, "--no-progress", "--p-threshold", "1"}, 2, "--p-threshold 1: expected a proportion correct"},
      // was: "no such file" for a directory and for /dev/null
      {kRender, {"--scene", (s / "dir-model.json").string(), "-o", out}, 1,
       "objects[0].path: cannot read model 'folder.obj': not a regular file (a directory)"},
      {kRender, {"--scene", (s / "null-model.json").string(), "-o", out}, 1,
       "objects[0].path: cannot read model '/dev/null': not a regular file (a device)"},
      // was: a newline or tab printed as a space, naming another path
      {kRender, {"--scene", newline, "-o", out}, 1, (s / "a\\x0ab.json").string() + ": cannot read scene file: no such file"},
      {kFit, {"psychometric", "--input", tab}, 1, (s / "c\\x09ounts.csv").string() + ": cannot read: no such file"},
  };
  for (const Case& c : cases) {
    const std::string tool = fs::path(c.exe).filename().string();
    SCOPED_TRACE(tool + " " + c.line);
    expect_one_line(run(c.exe, c.args, s), c.status, tool, c.line);
  }
  EXPECT_FALSE(fs::exists(s / "out"));
}

// Issue 45: a 16384² VSM under `ulimit -v 6 GiB` aborted ("The futex facility returned an unexpected
// error code.", SIGABRT, exit 134), and MSM printed a GL debug line before its error line. Out of
// memory is one line naming the map's size and what to lower, exit 1, nothing written.
// AddressSanitizer reserves terabytes of shadow memory at start and cannot run under an address-space
// limit at all, so the sanitized build skips this one (the plain suite runs it).
#if defined(__SANITIZE_ADDRESS__)
#define PENUMBRA_UNDER_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define PENUMBRA_UNDER_ASAN 1
#endif
#endif
TEST(ErrorLines, OutOfMemoryForAShadowMapIsOneLineNamingTheMap) {
#ifdef PENUMBRA_UNDER_ASAN
  GTEST_SKIP() << "AddressSanitizer cannot start under an address-space limit";
#endif
  const Scratch s("memory");
  for (const char* technique : {"vsm", "msm"}) {
    SCOPED_TRACE(technique);
    const test::Result r = run_with_address_limit(6ull << 30, kRender,
                                                  {"--technique", technique, "--resolution", "16384", "--width", "64", "--height",
                                                   "48", "--frames", "1", "--warmup", "0", "-o", (s / "out").string()},
                                                  s);
    expect_one_line(r, 1, "penumbra-render", "the shadow atlas 16384x16384 (depth and two moment maps, ");
    EXPECT_NE(r.err.find("does not fit in memory"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("(lower map.resolution_texels, adaptive.max_texels or map.cascades)"), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("GL debug"), std::string::npos) << r.err;
    std::vector<std::string> left;
    for (const auto& e : fs::directory_iterator(s.dir())) left.push_back(e.path().filename().string());
    std::sort(left.begin(), left.end());
    EXPECT_EQ(left, (std::vector<std::string>{"stderr.txt", "stdout.txt"})) << "nothing written, no staging directory";
  }
}

// Issue 45, part A: the virtual shadow map's options, the visibility and object paths, each with
// the line it must print (they were taken and not used, or failed blaming another option).
TEST(ErrorLines, VirtualMapVisibilityAndObjectPathsNameWhatIsWrong) {
  const Scratch s("virtual");
  const std::string out = (s / "out").string();
  std::ofstream(s / "twice.json") << R"({"objects": [{"name": "a", "shape": "sphere", "radius": 1}],
    "camera_path": {"keys": [{"frame": 0, "position": [0, 1, 5], "target": [0, 0, 0]}, {"frame": 9, "position": [1, 1, 5], "target": [0, 0, 0]}]},
    "object_paths": [{"object": "a", "keys": [{"frame": 0, "translate": [0, 0, 0]}, {"frame": 5, "translate": [1, 0, 0]}]},
                     {"object": "a", "keys": [{"frame": 0, "translate": [0, 0, 0]}, {"frame": 5, "translate": [0, 0, 9]}]}]})"
                                  << "\n";
  std::ofstream(s / "no-path.json") << R"({"objects": [{"name": "a", "shape": "sphere", "radius": 1}],
    "object_paths": [{"object": "a", "keys": [{"frame": 0, "translate": [0, 0, 0]}, {"frame": 5, "translate": [1, 0, 0]}]}]})"
                                    << "\n";
  std::ofstream(s / "shallow.json") << R"({"schema_version": 2, "entries": [{"technique": "pcf", "c": 3.47, "obtained_by": "simulated",
    "threshold": {"task": "2afc", "guess": 0.5, "criterion_f": 1e-6, "family": "log-weibull", "beta": 0.01}}]})"
                                    << "\n";
  const std::vector<std::string> pages = {"--technique", "pcf", "--pcf.kernel", "grid", "--pcf.radius_unit", "world", "--map.virtual_pages", "rule"};
  const auto with = [](std::vector<std::string> a, const std::vector<std::string>& b) {
    a.insert(a.end(), b.begin(), b.end());
    return a;
  };
  struct Case {
    std::string exe;
    std::vector<std::string> args;
    int status;
    std::string line;
  };
  const std::vector<Case> cases = {
      // was: 1e-45 .. 5e-324 a float's 0 (the entry's criterion), 1e-15 c = 69 215 texels, 1e-17 blamed adaptive.c (exit 1)
      {kRender, {"--adaptive.enabled", "true", "--adaptive.visibility", "1e-15", "-o", out}, 2,
       "--adaptive.visibility: visibility: expected 0 or a number in [0.001, 0.999], got '1e-15'"},
      {kRender, {"--adaptive.enabled", "true", "--adaptive.visibility", "5e-324", "-o", out}, 2, "got '5e-324'"},
      {kDemo, {"--headless", "--adaptive.visibility", "1e-17", "-o", out}, 2, "--adaptive.visibility: visibility: expected 0 or"},
      {kBench, {"--adaptive.visibility", "1e-45", "-o", out}, 2, "--adaptive.visibility: visibility: expected 0 or"},
      // was: a valid entry's c(F) = 0 blamed adaptive.c
      {kRender, {"--adaptive.enabled", "true", "--adaptive.visibility", "0.999", "--calibration", (s / "shallow.json").string(), "-o", out}, 2,
       "--adaptive.visibility: at F = 0.999 the pcf entry"},
      // was: taken and not used
      {kRender, {"--adaptive.enabled", "true", "--adaptive.c", "3", "--adaptive.visibility", "0.1", "-o", out}, 2,
       "--adaptive.visibility: not read: --adaptive.c gives c itself"},
      {kRender, {"--adaptive.visibility", "0.1", "-o", out}, 2, "--adaptive.visibility: not read: the adaptive rule is off"},
      {kRender, {"--map.virtual_pool_pages", "4", "-o", out}, 2,
       "--map.virtual_pool_pages: not read: it sets the virtual shadow map, and map.virtual_pages is off"},
      {kRender, {"--map.virtual_cache", "false", "-o", out}, 2, "--map.virtual_cache: not read"},
      {kRender, with(pages, {"--resolution", "64,4096", "-o", out}), 2, "--resolution: not read (it sets map.resolution_texels)"},
      {kRender, with(pages, {"--map.cascades", "4", "-o", out}), 2, "--map.cascades: not read: a virtual shadow map"},
      // was: pages that did not fit shaded lit, exit 0
      {kRender, with(pages, {"--map.virtual_pool_pages", "1", "--width", "64", "--height", "48", "-o", out}), 2,
       "--map.virtual_pool_pages 1: a pool of 1 page slot cannot hold the"},
      // was: the last path won; paths no frame poses
      {kRender, {"--scene", (s / "twice.json").string(), "-o", out}, 1,
       "twice.json: object_paths[1].object: 'a' already has a path (object_paths[0]); give an object one path"},
      {kRender, {"--scene", (s / "no-path.json").string(), "-o", out}, 1,
       "no-path.json: object_paths: needs a camera_path: objects move over its frames, and this scene has none"},
  };
  for (const Case& c : cases) {
    const std::string tool = fs::path(c.exe).filename().string();
    SCOPED_TRACE(tool + " " + c.line);
    expect_one_line(run(c.exe, c.args, s), c.status, tool, c.line);
  }
  EXPECT_FALSE(fs::exists(s / "out"));
}

}  // namespace
