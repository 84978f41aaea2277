#pragma once
// The trial log (contract in shared/DESIGN.md): one CSV per session, header first, one row per
// trial appended with a single write() and fsync()ed before the next trial starts; never
// rewritten. Doubles are written with 17 significant digits so replaying the log restores every
// QUEST staircase bit for bit.
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace penumbra::trial_log {

struct TrialRow {
  std::string session_id;
  std::string participant;
  std::string utc_time;       // ISO 8601, when the response was given
  int round = 0;              // 0-based
  int trial = 0;              // 0-based, across the session (practice included)
  std::string staircase;      // e.g. "a10": one QUEST per artifact size within a round
  std::string pattern;        // stair | step
  double contrast = 1;        // lit level, linear light
  double artifact_px = 0;
  std::string task;           // 2afc | yesno
  double intensity = 0;       // log10(artifact_px / filter_radius_px), as shown (fed to QUEST)
  double filter_radius_px = 0;  // as shown
  std::string kernel;
  std::string target;         // 2afc: side of the jagged stimulus (left|right); yesno: jagged|straight
  std::string response;       // 2afc: left|right; yesno: yes|no ("the original was a straight line")
  int correct = 0;
  double rt_ms = 0;
  double quest_mean = 0;      // the staircase's estimate after this trial
  double quest_sd = 0;
  int practice = 0;
  double requested_filter_radius_px = 0;  // what QUEST asked for, before clamping
  int clamped = 0;
  double artifact_arcmin = 0;
  double filter_radius_arcmin = 0;
  std::uint64_t stimulus_seed = 0;  // penumbra-study stimulus --seed reproduces the images
};

const std::vector<std::string>& columns();
std::string header_line();             // with '\n'
std::string format_row(const TrialRow& row);  // with '\n'
// Throws std::runtime_error "<file>:<line>: column '<name>': <what>".
TrialRow parse_row(const std::string& line, const std::string& file, int line_number);

// Appends to a log. `create` makes a new file (refusing an existing one) and writes the header.
class Writer {
 public:
  Writer(const std::filesystem::path& path, bool create);
  ~Writer();
  Writer(const Writer&) = delete;
  Writer& operator=(const Writer&) = delete;
  // One write() of the whole line, then fsync(); throws naming the file on failure.
  void append(const TrialRow& row);

 private:
  std::filesystem::path path_;
  int fd_ = -1;
};

struct ReadResult {
  std::vector<TrialRow> rows;
  bool torn_tail = false;  // the last line had no newline: a trial being written when the process died
  std::uintmax_t complete_bytes = 0;  // bytes up to the end of the last complete line
};
// Reads and validates a log (header and every row). Throws std::runtime_error naming file and line.
ReadResult read(const std::filesystem::path& path);

}  // namespace penumbra::trial_log
