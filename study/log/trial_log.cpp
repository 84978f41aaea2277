#include "log/trial_log.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "io/atomic_file.h"
#include "io/safe_path.h"
#include "text/csv_row.h"
#include "text/fields.h"
#include "json/json_input.h"
#include "text/printable.h"

namespace penumbra::trial_log {

const std::vector<std::string>& columns(Layout layout) {
  static const std::vector<std::string> without_timing = {
      "session_id", "participant", "utc_time", "round", "trial", "staircase", "pattern", "contrast",
      "artifact_px", "task", "intensity", "filter_radius_px", "kernel", "target", "response", "correct",
      "rt_ms", "quest_mean", "quest_sd", "practice", "requested_filter_radius_px", "clamped",
      "artifact_arcmin", "filter_radius_arcmin", "stimulus_seed"};
  static const std::vector<std::string> with_timing = [] {
    std::vector<std::string> c = without_timing;
    c.insert(c.end(), {"onset_s", "frames", "frame_ms_mean", "frame_ms_max", "dropped_frames"});
    return c;
  }();
  static const std::vector<std::string> current = [] {
    std::vector<std::string> c = with_timing;
    c[3] = "condition_index";
    c.insert(c.begin() + 4, "round_position");
    return c;
  }();
  static const std::vector<std::string> frames = {
      "session_id", "participant", "utc_time", "condition_index", "round_position", "trial", "staircase", "technique", "scene",
      "path_frame", "task", "intensity", "k", "requested_k", "clamped", "target", "response", "correct", "rt_ms", "quest_mean",
      "quest_sd", "practice", "stimulus_seed", "onset_s", "frames", "frame_ms_mean", "frame_ms_max", "dropped_frames"};
  switch (layout) {
    case Layout::without_timing: return without_timing;
    case Layout::with_timing: return with_timing;
    case Layout::current: return current;
    case Layout::frames: return frames;
  }
  return current;
}

std::string header_line(Layout layout) {
  std::string s;
  for (std::size_t i = 0; i < columns(layout).size(); ++i) s += (i ? "," : "") + columns(layout)[i];
  return s + "\n";
}

namespace {

// The shortest text that reads back as the same double (0.3, not 0.29999999999999999).
std::string num(double v) {
  char buf[32];
  const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, ec == std::errc() ? end : buf);
}

// A reaction time to the microsecond (a clock finer than that says nothing about a key press).
std::string ms_to_us(double ms) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.3f", ms);
  return buf;
}

// Free-text fields may not hold separators; the writer refuses them instead of quoting.
const std::string& text(const std::string& v, const char* name) {
  if (v.find_first_of(",\"\n\r") != std::string::npos)
    throw std::invalid_argument(std::string("trial log: ") + name + " '" + text::printable(v) + "' contains , \" or a newline");
  return v;
}

// Bounds no real session reaches: a log holding more is edited or corrupt.
constexpr double kMaxRtMs = 1e8, kMaxOnsetS = 1e7, kMaxFrameMs = 1e6;

// "2026-12-03T09:15:02.123Z" (the study writes milliseconds; seconds alone are read too).
bool utc_time_ok(const std::string& t) {
  int year = 0, month = 0, day = 0, hour = 0, minute = 0, second = 0, millis = 0, used = 0;
  const bool with_ms = std::sscanf(t.c_str(), "%4d-%2d-%2dT%2d:%2d:%2d.%3dZ%n", &year, &month, &day, &hour, &minute, &second, &millis, &used) == 7;
  if (!with_ms) {
    used = 0;
    if (std::sscanf(t.c_str(), "%4d-%2d-%2dT%2d:%2d:%2dZ%n", &year, &month, &day, &hour, &minute, &second, &used) != 6) return false;
  }
  return static_cast<std::size_t>(used) == t.size() && t.size() >= 20 && year >= 2000 && year <= 9999 && month >= 1 &&
         month <= 12 && day >= 1 && day <= 31 && hour <= 23 && minute <= 59 && second <= 60 && t[4] == '-' && t[10] == 'T';
}

// UTF-8 without control characters.
bool valid_text(const std::string& s) {
  for (char c : s)
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) return false;
  return text::valid_utf8(s);
}

}  // namespace

namespace {
void format_timing(std::ostringstream& o, const TrialRow& r) {
  if (r.timing)
    o << ',' << num(r.timing->onset_s) << ',' << r.timing->frames << ',' << num(r.timing->frame_ms_mean) << ','
      << num(r.timing->frame_ms_max) << ',' << (r.timing->dropped_frames ? std::to_string(*r.timing->dropped_frames) : "");
  else
    o << ",,,,,";  // not measured
}
}  // namespace

std::string format_row(const TrialRow& r, Layout layout) {
  std::ostringstream o;
  if (layout == Layout::frames) {
    o << text(r.session_id, "session_id") << ',' << text(r.participant, "participant") << ',' << r.utc_time << ','
      << r.condition_index << ',' << r.round_position << ',' << r.trial << ',' << text(r.staircase, "staircase") << ','
      << text(r.technique, "technique") << ',' << text(r.scene, "scene") << ',' << r.path_frame << ',' << r.task << ','
      << num(r.intensity) << ',' << num(r.k) << ',' << num(r.requested_k) << ',' << r.clamped << ',' << r.target << ','
      << r.response << ',' << r.correct << ',' << ms_to_us(r.rt_ms) << ',' << num(r.quest_mean) << ',' << num(r.quest_sd)
      << ',' << r.practice << ',' << r.stimulus_seed;
    format_timing(o, r);
    o << '\n';
    return o.str();
  }
  o << text(r.session_id, "session_id") << ',' << text(r.participant, "participant") << ',' << r.utc_time << ','
    << r.condition_index << ',' << (layout == Layout::current ? std::to_string(r.round_position) + "," : std::string()) << r.trial
    << ',' << text(r.staircase, "staircase") << ',' << r.pattern << ',' << num(r.contrast)
    << ',' << num(r.artifact_px) << ',' << r.task << ',' << num(r.intensity) << ',' << num(r.filter_radius_px) << ','
    << r.kernel << ',' << r.target << ',' << r.response << ',' << r.correct << ',' << ms_to_us(r.rt_ms) << ','
    << num(r.quest_mean) << ',' << num(r.quest_sd) << ',' << r.practice << ',' << num(r.requested_filter_radius_px)
    << ',' << r.clamped << ',' << num(r.artifact_arcmin) << ',' << num(r.filter_radius_arcmin) << ','
    << r.stimulus_seed;
  if (layout != Layout::without_timing) format_timing(o, r);
  o << '\n';
  return o.str();
}

TrialRow parse_row(const std::string& line, const std::string& file, int line_number, Layout layout) {
  const text::CsvRow f(file, line_number, columns(layout), text::split_fields(line));
  auto fail = [&](std::size_t i, const std::string& what) { f.fail(i, what); };
  auto real = [&](std::size_t i) { return f.real(i); };
  auto integer = [&](std::size_t i, long lo, long hi) { return static_cast<int>(f.integer(i, lo, hi)); };
  auto one_of = [&](std::size_t i, std::initializer_list<const char*> allowed) { return f.one_of(i, allowed); };
  // Free text as the writer writes it: no quotes or control bytes (a '\r' of a CRLF file included),
  // valid UTF-8, short; so every accepted row is written back unchanged and is safe in a report.
  auto nonempty = [&](std::size_t i) {
    if (f[i].empty()) fail(i, "expected a value");
    if (f[i].size() > 400) fail(i, "expected at most 400 bytes");
    if (f[i].find('"') != std::string::npos || !valid_text(f[i]))
      fail(i, "expected UTF-8 text without quotes or control characters");
    return f[i];
  };
  // The timing columns from `first` on: all empty (not measured) or all filled, but for
  // dropped_frames, empty when the refresh rate was unknown.
  auto timing = [&](std::size_t first) -> std::optional<FrameTiming> {
    const std::size_t n = 5;
    std::size_t empty = 0;
    for (std::size_t i = first; i < first + n; ++i) empty += f[i].empty();
    if (empty == n) return std::nullopt;
    for (std::size_t i = first; i < first + n - 1; ++i)
      if (f[i].empty()) fail(i, "expected a value (the timing columns are all empty or all filled)");
    FrameTiming t;
    t.onset_s = real(first);
    if (!(t.onset_s >= 0 && t.onset_s <= kMaxOnsetS)) fail(first, "expected a time in [0, 1e7] s since the window opened");
    t.frames = integer(first + 1, 1, 1000000000);
    t.frame_ms_mean = real(first + 2);
    if (!(t.frame_ms_mean >= 0 && t.frame_ms_mean <= kMaxFrameMs)) fail(first + 2, "expected a frame interval in [0, 1e6] ms");
    t.frame_ms_max = real(first + 3);
    if (t.frame_ms_max < t.frame_ms_mean) fail(first + 3, "expected >= frame_ms_mean");
    if (t.frame_ms_max > kMaxFrameMs) fail(first + 3, "expected a frame interval in [0, 1e6] ms");
    if (!f[first + 4].empty()) t.dropped_frames = integer(first + 4, 0, t.frames);
    return t;
  };
  TrialRow r;
  if (layout == Layout::frames) {
    r.session_id = nonempty(0);
    r.participant = nonempty(1);
    r.utc_time = nonempty(2);
    if (!utc_time_ok(r.utc_time)) fail(2, "expected a UTC time as the study writes it, 2026-12-03T09:15:02.123Z");
    r.condition_index = integer(3, 0, 1000);
    r.round_position = integer(4, 1, 1001);
    r.trial = integer(5, 0, 1000000);
    r.staircase = nonempty(6);
    r.technique = nonempty(7);
    r.scene = nonempty(8);
    r.path_frame = integer(9, -1, 10000000);
    r.task = one_of(10, {"2afc"});
    r.intensity = real(11);
    r.k = real(12);
    if (!(r.k > 0)) fail(12, "expected > 0");
    if (std::abs(r.intensity + std::log10(r.k)) > 1e-9) fail(11, "expected log10(1 / k)");
    r.requested_k = real(13);
    if (!(r.requested_k > 0)) fail(13, "expected > 0");
    r.clamped = integer(14, 0, 1);
    r.target = one_of(15, {"left", "right"});
    r.response = one_of(16, {"left", "right"});
    r.correct = integer(17, 0, 1);
    if (r.correct != (r.response == r.target ? 1 : 0)) fail(17, "does not agree with target and response");
    r.rt_ms = real(18);
    if (!(r.rt_ms >= 0 && r.rt_ms <= kMaxRtMs)) fail(18, "expected a time in [0, 1e8] ms");
    r.quest_mean = real(19);
    r.quest_sd = real(20);
    if (r.quest_sd < 0) fail(20, "expected >= 0");
    r.practice = integer(21, 0, 1);
    r.stimulus_seed = f.unsigned_integer(22);
    r.timing = timing(23);
    return r;
  }
  // The current layout has round_position after condition_index: the columns after it move by one.
  const std::size_t k = layout == Layout::current ? 1 : 0;
  r.session_id = nonempty(0);
  r.participant = nonempty(1);
  r.utc_time = nonempty(2);
  if (!utc_time_ok(r.utc_time)) fail(2, "expected a UTC time as the study writes it, 2026-12-03T09:15:02.123Z");
  r.condition_index = integer(3, 0, 1000);
  if (layout == Layout::current) r.round_position = integer(4, 1, 1001);
  r.trial = integer(4 + k, 0, 1000000);
  r.staircase = nonempty(5 + k);
  r.pattern = one_of(6 + k, {"stair", "step"});
  r.contrast = real(7 + k);
  if (!(r.contrast > 0 && r.contrast <= 1)) fail(7 + k, "expected a lit level in (0, 1]");
  r.artifact_px = real(8 + k);
  if (!(r.artifact_px > 0)) fail(8 + k, "expected > 0");
  r.task = one_of(9 + k, {"2afc", "yesno"});
  r.intensity = real(10 + k);
  r.filter_radius_px = real(11 + k);
  if (!(r.filter_radius_px > 0)) fail(11 + k, "expected > 0");
  if (std::abs(r.intensity - std::log10(r.artifact_px / r.filter_radius_px)) > 1e-9)
    fail(10 + k, "expected log10(artifact_px / filter_radius_px)");
  r.kernel = one_of(12 + k, {"disk", "grid", "poisson"});
  if (r.task == "2afc") {
    r.target = one_of(13 + k, {"left", "right"});
    r.response = one_of(14 + k, {"left", "right"});
  } else {
    r.target = one_of(13 + k, {"jagged", "straight"});
    r.response = one_of(14 + k, {"yes", "no"});
  }
  r.correct = integer(15 + k, 0, 1);
  const bool right = r.task == "2afc" ? r.response == r.target : (r.response == "yes") == (r.target == "straight");
  if (r.correct != (right ? 1 : 0)) fail(15 + k, "does not agree with target and response");
  r.rt_ms = real(16 + k);
  if (!(r.rt_ms >= 0 && r.rt_ms <= kMaxRtMs)) fail(16 + k, "expected a time in [0, 1e8] ms");
  r.quest_mean = real(17 + k);
  r.quest_sd = real(18 + k);
  if (r.quest_sd < 0) fail(18 + k, "expected >= 0");
  r.practice = integer(19 + k, 0, 1);
  r.requested_filter_radius_px = real(20 + k);
  r.clamped = integer(21 + k, 0, 1);
  r.artifact_arcmin = real(22 + k);
  r.filter_radius_arcmin = real(23 + k);
  r.stimulus_seed = f.unsigned_integer(24 + k);
  if (layout != Layout::without_timing) r.timing = timing(25 + k);
  return r;
}

FrameTiming frame_timing(double onset_s, const std::vector<double>& intervals_ms, double refresh_hz) {
  if (intervals_ms.empty()) throw std::logic_error("frame_timing: no frame");
  FrameTiming t;
  t.onset_s = onset_s;
  t.frames = static_cast<int>(intervals_ms.size());
  double sum = 0;
  for (double ms : intervals_ms) {
    sum += ms;
    t.frame_ms_max = std::max(t.frame_ms_max, ms);
  }
  if (refresh_hz > 0) {
    t.dropped_frames = 0;
    for (double ms : intervals_ms) *t.dropped_frames += ms > kDroppedFramePeriods * 1000.0 / refresh_hz;
  }
  t.frame_ms_mean = std::min(sum / t.frames, t.frame_ms_max);  // never above the max by rounding
  return t;
}

Writer::Writer(const std::filesystem::path& path, bool create, Layout layout) : path_(path), layout_(layout) {
  if (!create) {
    io::refuse_link(path, "a session directory holds its own files, never links");
    std::ifstream in(path, std::ios::binary);
    std::string first;
    std::getline(in, first);
    first += '\n';
    bool known = false;
    for (Layout l : {Layout::without_timing, Layout::with_timing, Layout::current, Layout::frames})
      if (first == header_line(l)) layout_ = l, known = true;
    if (in && !known) throw std::runtime_error(path.string() + ":1: the header does not match the trial-log columns");
  }
  // Never through a symbolic link: rows appended to trials.csv went to whatever file it pointed at.
  fd_ = io::open_no_follow(path, O_WRONLY | O_APPEND | (create ? (O_CREAT | O_EXCL) : 0), 0644, "the trial log");
  if (create) {
    int error = io::write_all(fd_, header_line(layout_));
    if (error == 0 && ::fsync(fd_) != 0) error = errno;
    if (error != 0) {
      ::close(fd_);
      throw std::runtime_error(path.string() + ": cannot write the header: " + std::strerror(error));
    }
  }
}

Writer::~Writer() {
  if (fd_ >= 0) ::close(fd_);
}

void Writer::cut_to(std::uintmax_t bytes) {
  if (::ftruncate(fd_, static_cast<off_t>(bytes)) != 0 || ::fsync(fd_) != 0)
    throw std::runtime_error(path_.string() + ": cannot cut the torn last line: " + std::strerror(errno));
}

void Writer::append(const TrialRow& row) {
  // A failure part-way leaves a torn last line, which readers ignore and --resume cuts off.
  if (const int error = io::write_all(fd_, format_row(row, layout_)); error != 0)
    throw std::runtime_error(path_.string() + ": cannot append trial " + std::to_string(row.trial) + ": " +
                             std::strerror(error));
  if (::fsync(fd_) != 0) {
    const int error = errno;
    throw std::runtime_error(path_.string() + ": cannot append trial " + std::to_string(row.trial) + ": fsync: " +
                             std::strerror(error));
  }
}

ReadResult read(const std::filesystem::path& path) {
  // A session directory's log, never through a link; a million trials stay far below the bound.
  const std::string all = io::read_file(path, std::size_t{256} << 20, io::Links::refuse);
  ReadResult result;
  const std::string file = path.string();
  std::size_t pos = 0;
  int line_number = 0;
  while (pos < all.size()) {
    const std::size_t nl = all.find('\n', pos);
    ++line_number;
    if (nl == std::string::npos) {
      result.torn_tail = true;
      break;
    }
    const std::string line = all.substr(pos, nl - pos);
    if (line_number == 1) {
      bool known = false;
      for (Layout l : {Layout::without_timing, Layout::with_timing, Layout::current, Layout::frames})
        if (line + "\n" == header_line(l)) result.layout = l, known = true;
      if (!known) {
        // The two ways a spreadsheet saves a good log badly, named (they look like the right header).
        if (line.rfind("\xEF\xBB\xBF", 0) == 0)
          throw std::runtime_error(file + ":1: starts with a UTF-8 byte-order mark (saved by a spreadsheet?); the log is plain UTF-8: "
                                          "remove the first three bytes");
        if (!line.empty() && line.back() == '\r')
          throw std::runtime_error(file + ":1: lines end with \\r\\n (saved on Windows?); the log ends its lines with \\n only");
        throw std::runtime_error(file + ":1: the header does not match the trial-log columns (" +
                                 header_line().substr(0, header_line().size() - 1) + ")");
      }
    } else {
      result.rows.push_back(parse_row(line, file, line_number, result.layout));
    }
    pos = nl + 1;
    result.complete_bytes = pos;
  }
  if (line_number == 0 || result.complete_bytes == 0) throw std::runtime_error(file + ":1: no header");
  return result;
}

}  // namespace penumbra::trial_log
