#pragma once
// The trial log (contract in docs/architecture.md): one CSV per session, header first, one row per
// trial appended with a single write() and fsync()ed before the next trial starts; never
// rewritten. Doubles are written with 17 significant digits so replaying the log restores every
// QUEST staircase bit for bit.
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace penumbra::trial_log {

// How a trial's stimulus was presented, measured in the participant window (docs/study.md,
// "Frame timing"). Every swap of that window is timestamped on the steady clock after the swap and
// a glFinish; a stimulus frame's interval runs from the swap before it to its own swap, so frame 0's
// interval tells whether the onset itself came late.
struct FrameTiming {
  double onset_s = 0;        // the first stimulus frame's timestamp, seconds since this run of the session opened its window
  int frames = 0;            // frames that showed the stimulus before the answer (>= 1)
  double frame_ms_mean = 0;  // their intervals
  double frame_ms_max = 0;
  // Intervals over kDroppedFramePeriods refresh periods; none (written empty) when the refresh
  // rate was unknown.
  std::optional<int> dropped_frames;
};
// An interval longer than this many refresh periods (session.json presentation.video_mode.refresh_hz)
// means at least one refresh passed without a new frame.
inline constexpr double kDroppedFramePeriods = 1.5;
// The timing of one stimulus from its onset and its frames' intervals (ms; at least one);
// refresh_hz <= 0: unknown, dropped frames not judged.
FrameTiming frame_timing(double onset_s, const std::vector<double>& intervals_ms, double refresh_hz);

struct TrialRow {
  std::string session_id;
  std::string participant;
  std::string utc_time;       // ISO 8601, when the response was given
  int condition_index = 0;    // the round's condition: 0-based index into the config's rounds (column 'round' in older logs)
  int round_position = 0;     // where that round ran in this session, 1-based ("Round 2 of 4"); 0: not recorded (older logs)
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
  double rt_ms = 0;             // written to the microsecond
  double quest_mean = 0;      // the staircase's estimate after this trial
  double quest_sd = 0;
  int practice = 0;
  double requested_filter_radius_px = 0;  // what QUEST asked for, before clamping
  int clamped = 0;
  double artifact_arcmin = 0;
  double filter_radius_arcmin = 0;
  std::uint64_t stimulus_seed = 0;  // penumbra-study stimulus --seed reproduces the images
  // Written as empty fields when absent: headless and simulated sessions, and logs begun before the
  // timing columns existed.
  std::optional<FrameTiming> timing;
  // A frame study's rows (Layout::frames) instead of pattern, contrast, artifact and radius: the
  // round's technique, the scene and path frame of the patch (the staircase), the multiple k of the
  // rule's c shown (intensity = log10(1 / k)) and the one QUEST asked for.
  std::string technique, scene;
  int path_frame = -1;
  double k = 0, requested_k = 0;
};

// The log's layouts, oldest first. `current` names the round two ways: `condition_index` (the
// config's round, 0-based) and `round_position` (1-based, as the participant's screens number it);
// the older layouts had one column `round` holding the condition index, and `without_timing` lacks
// the timing columns. Older logs are read and, when such a session is resumed, appended to in their
// own layout.
// `frames` is a frame study's log (config.frames): the current layout's identity, answer, QUEST and
// timing columns with technique, scene, path_frame, k and requested_k in place of the edge
// stimulus's columns.
enum class Layout { without_timing, with_timing, current, frames };

const std::vector<std::string>& columns(Layout layout = Layout::current);
std::string header_line(Layout layout = Layout::current);  // with '\n'
std::string format_row(const TrialRow& row, Layout layout = Layout::current);  // with '\n'
// Throws std::runtime_error "<file>:<line>: column '<name>': <what>".
TrialRow parse_row(const std::string& line, const std::string& file, int line_number,
                   Layout layout = Layout::current);

// Appends to a log. `create` makes a new file (refusing an existing one) and writes the current
// header; an existing log keeps the layout of its header.
class Writer {
 public:
  Writer(const std::filesystem::path& path, bool create, Layout layout = Layout::current);
  ~Writer();
  Writer(const Writer&) = delete;
  Writer& operator=(const Writer&) = delete;
  // One write() of the whole line, then fsync(); throws naming the file on failure.
  void append(const TrialRow& row);
  // Cuts the log to its first `bytes` (a torn last line, ReadResult::complete_bytes) through this
  // writer's descriptor, which was opened without following a link.
  void cut_to(std::uintmax_t bytes);

 private:
  std::filesystem::path path_;
  int fd_ = -1;
  Layout layout_ = Layout::current;
};

struct ReadResult {
  std::vector<TrialRow> rows;
  bool torn_tail = false;  // the last line had no newline: a trial being written when the process died
  std::uintmax_t complete_bytes = 0;  // bytes up to the end of the last complete line
  Layout layout = Layout::current;    // from the header
};
// Reads and validates a log (header and every row); a symbolic link is refused, not followed.
// Throws std::runtime_error naming file and line.
ReadResult read(const std::filesystem::path& path);

}  // namespace penumbra::trial_log
