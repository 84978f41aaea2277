#pragma once
// The study's trial logs as the fitter sees them: session directories (trials.csv + session.json)
// or bare trial CSVs, read through the study's validating reader (penumbra_study_log, no GL).
// Practice rows are counted and left out; yes/no catch trials are kept apart (Dataset::catch_trials).
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "log/trial_log.h"
#include "quest/quest.h"

namespace penumbra::analysis {

struct SessionInfo {
  std::string session_id;
  std::string participant;
  std::string log_file;                    // the trials.csv read
  std::optional<quest::QuestParams> quest;  // from session.json, with the table size it used
  int quest_dim = 0;
  // The config's quest.tail_p_threshold: the P(correct) its tail staircases' QUEST aimed at
  // (procedure::is_tail_staircase names them); 0: none.
  double tail_p_threshold = 0;
  double sd_below = 0.1;                   // the study's convergence criterion (session.json), else 0.1
  bool torn_tail = false;                  // the last line was cut (a trial unanswered when the app died)
  // Who answered (procedure::ObserverKind as session.json holds it): "person",
  // "psychometric-simulation" or "image-observer"; "" for a log without a session.json beside it.
  std::string observer_kind;
  std::string observer;  // session.json's "observer": a simulated observer's spec ("psychometric:c=..", "image:..")
  // yes/no: what QUEST was fed (the config's yesno_scoring): "jagged_only" or "balanced".
  std::string yesno_scoring = "jagged_only";
  // How the session measured, flattened from session.json ("display.viewing_distance_mm" -> "600"):
  // the task, the stimulus block, the display as recorded (geometry, transfer; a measured
  // transfer by its calibration's fingerprint, "display.calibration") and the QUEST parameters.
  // Sessions that differ here are not pooled without LoadOptions::pool.
  std::map<std::string, std::string> setup;
  // A session in a participant's browser (penumbra-study serve): the stimulus pixels per degree
  // that participant saw, from session.json's last presentation of kind "browser" that fitted the
  // window: the virtual chinrest's CSS pixels per degree times the stimulus pixels per CSS pixel
  // (size_px / stimulus_css_px). Unset for a lab session (its display is in `setup`).
  std::optional<double> browser_pixels_per_degree;
};

struct Trial {
  trial_log::TrialRow row;
  std::size_t session = 0;  // index into Dataset::sessions
  int line = 0;             // line in the log (header = 1)
};

// A log the study could not have written as it stands: rows duplicated, removed, reordered or edited
// (trial numbers, staircases the design does not have, a QUEST posterior the replay contradicts).
struct Inconsistency {
  std::string file;
  int line = 0;   // the first row that is wrong (header = 1)
  int trial = 0;  // as logged in that row
  std::string problem;  // one line: "<file>:<line>: column '<name>': ..."
};

// Thrown by load_dataset for an inconsistent log unless LoadOptions::accept_inconsistent.
class InconsistentLog : public std::runtime_error {
 public:
  explicit InconsistentLog(const Inconsistency& i) : std::runtime_error(i.problem), inconsistency(i) {}
  Inconsistency inconsistency;
};

struct LoadOptions {
  // Fit inconsistent logs anyway; their first problem each is kept in Dataset::inconsistencies.
  bool accept_inconsistent = false;
  // Pool sessions whose setup differs (stimulus size, display geometry, transfer, task, QUEST
  // parameters); each difference is kept in Dataset::pooled_differences. Without it such
  // sessions are refused, naming both and the first field that differs.
  bool pool = false;
  // Called before each input is read and checked (done = inputs read so far, total = all inputs)
  // and once when all are (done = total).
  std::function<void(int done, int total)> progress;
};

struct Dataset {
  std::vector<SessionInfo> sessions;
  std::vector<Inconsistency> inconsistencies;  // one per inconsistent log (accept_inconsistent only)
  std::vector<std::string> pooled_differences;  // "display.width_mm: 527 (A/session.json), 600 (B/...)" (pool only)
  std::vector<Trial> trials;  // practice excluded, in log order per session
  int practice_rows = 0;
  // yes/no: straight (catch) trials say nothing about the artifact's visibility; like QUEST
  // (study/procedure/session.cpp) the fits use the jagged trials only, where correct = detected.
  int catch_rows = 0;
  int catch_false_alarms = 0;  // catch trials answered "not straight"
  // The catch trials themselves, in log order per session: a participant's false-alarm rate is
  // the guess rate of their detections (fit_study), and a balanced-scored session's QUEST saw them.
  std::vector<Trial> catch_trials;
};

// Throws std::runtime_error naming the file (and line and column for log rows) on bad input: a
// missing path, a directory without trials.csv, invalid session.json fields, a session given
// twice, rows whose session_id or participant disagree with session.json, no trials at all.
//
// Every log is checked for integrity, and an inconsistent one throws InconsistentLog naming the
// first wrong row (unless options.accept_inconsistent): trial numbers other than 0, 1, 2, ... in
// row order; where session.json holds the study's config, every row against the procedure replayed
// from it (procedure::replay_log, as --resume checks: staircase, stimulus, target, seed, QUEST
// posterior); otherwise staircases named after their artifact size, one condition per round, and
// each row's QUEST posterior against session.json's QUEST replayed over the log.
Dataset load_dataset(const std::vector<std::filesystem::path>& inputs, const LoadOptions& options = {});

// "stair/1", "step/0.5": pattern and contrast, as the study names a round's condition.
std::string condition_name(const std::string& pattern, double contrast);
std::string format_number(double v);  // %g

}  // namespace penumbra::analysis
