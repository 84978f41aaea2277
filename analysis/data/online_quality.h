#pragma once
// The data quality of each session as online labs check it (docs/fit.md#data-quality): for a
// session run in a participant's browser (penumbra-study serve, docs/study-online.md) the browser,
// screen size, devicePixelRatio, refresh estimate and the virtual chinrest's readings from
// session.json, fullscreen exits, tab switches and page loads from online.json; for every person's
// session the response-time outliers of its log. penumbra-fit prints them as a table, writes them
// into report.json and excludes sessions only by criteria given on its command line
// (--exclude-quality), each excluded session listed with its reason, never dropped silently.
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace penumbra::analysis {

// A response-time outlier: faster than a person can see and press (an anticipation), or slower
// than this many times the session's median (the participant was elsewhere).
inline constexpr double kRtFastMs = 150;
inline constexpr double kRtSlowTimesMedian = 3;

struct SessionQuality {
  std::string input;        // as given on the command line
  std::string participant;  // session.json's, else the log's
  bool person = false;      // observer_kind "person" (a simulation's response times mean nothing)
  bool browser = false;     // session.json holds a presentation of kind "browser" that fitted the window
  std::string browser_name; // from the user agent: "Chrome 131", "Firefox 133", ... (or its first words)
  double screen_width_css_px = NAN, screen_height_css_px = NAN;
  double device_pixel_ratio = NAN, refresh_hz = NAN;
  double viewing_distance_mm = NAN;  // the chinrest's (the mean of its blind-spot readings)
  double css_px_per_degree = NAN;    // at the screen centre, from the card and the viewing distance
  double stimulus_px_per_degree = NAN;  // what the fit uses: css_px_per_degree * size_px / stimulus_css_px
  // Device pixels per stimulus pixel (stimulus_css_px / size_px * devicePixelRatio): other than an
  // integer, the browser resampled the jagged edge.
  double device_px_per_stimulus_px = NAN;
  std::optional<int> fullscreen_exits, tab_switches, page_loads;  // online.json (browser sessions)
  int trials = 0;                      // answered, practice left out
  double rt_median_ms = NAN;           // of those trials (a person's session only)
  int rt_fast = 0, rt_slow = 0;        // below kRtFastMs, above kRtSlowTimesMedian x the median
  double rt_outlier_fraction = NAN;    // (fast + slow) / trials
  std::vector<double> chinrest_distances_mm;  // each blind-spot reading
  double chinrest_cv = NAN;            // sample sd / mean of the readings (two or more)
  std::vector<std::string> excluded_because;  // the criteria it failed: "tab_switches 5 > 3"
};

// One criterion: a session whose `measure` lies above `limit` is excluded. A session that does
// not have the measure (a lab session's fullscreen exits, one chinrest reading) is not excluded.
struct QualityCriterion {
  std::string measure;  // fullscreen_exits, tab_switches, page_loads, rt_outliers, chinrest_cv
  double limit = 0;     // rt_outliers: a fraction (given in per cent)
  std::string text;     // as written: "rt_outliers>10%"
};

// "fullscreen_exits>2,tab_switches>3,rt_outliers>10%,chinrest_cv>0.1" (any of them, each once).
// Throws std::invalid_argument whose message starts with "--exclude-quality" for anything else.
std::vector<QualityCriterion> parse_quality_criteria(const std::string& text);

// Each input's quality: a session directory's session.json, online.json and trials.csv, a bare
// trial CSV's rows. Throws std::runtime_error naming the file and field of a malformed value.
std::vector<SessionQuality> read_quality(const std::vector<std::filesystem::path>& inputs);

// Fills each session's excluded_because; returns how many are excluded.
int apply_quality_criteria(std::vector<SessionQuality>& sessions, const std::vector<QualityCriterion>& criteria);

// Whether the table is worth printing: a browser session among them, or criteria given.
bool quality_reported(const std::vector<SessionQuality>& sessions, const std::vector<QualityCriterion>& criteria);

// The table penumbra-fit prints and appends to summary.txt: one row per session, the criteria and
// each excluded session with its reason.
std::string quality_table(const std::vector<SessionQuality>& sessions, const std::vector<QualityCriterion>& criteria);

// report.json's "data_quality": the definitions, the criteria, one object per session, and the
// excluded sessions with their reasons.
nlohmann::json quality_json(const std::vector<SessionQuality>& sessions, const std::vector<QualityCriterion>& criteria);

}  // namespace penumbra::analysis
