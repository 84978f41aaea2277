#pragma once
// The study's trial logs as the fitter sees them: session directories (trials.csv + session.json)
// or bare trial CSVs, read through the study's validating reader (penumbra_study_log, no GL).
// Practice rows and yes/no catch trials are counted and left out.
#include <filesystem>
#include <optional>
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
  double sd_below = 0.1;                   // the study's convergence criterion (session.json), else 0.1
  bool torn_tail = false;                  // the last line was cut (a trial unanswered when the app died)
};

struct Trial {
  trial_log::TrialRow row;
  std::size_t session = 0;  // index into Dataset::sessions
  int line = 0;             // line in the log (header = 1)
};

struct Dataset {
  std::vector<SessionInfo> sessions;
  std::vector<Trial> trials;  // practice excluded, in log order per session
  int practice_rows = 0;
  // yes/no: straight (catch) trials say nothing about the artifact's visibility; like QUEST
  // (study/procedure/session.cpp) the fits use the jagged trials only, where correct = detected.
  int catch_rows = 0;
  int catch_false_alarms = 0;  // catch trials answered "not straight"
};

// Throws std::runtime_error naming the file (and line and column for log rows) on bad input: a
// missing path, a directory without trials.csv, invalid session.json fields, a session given
// twice, rows whose session_id or participant disagree with session.json, trial numbers other than
// 0, 1, 2, ... in row order, no trials at all.
Dataset load_dataset(const std::vector<std::filesystem::path>& inputs);

// "stair/1", "step/0.5": pattern and contrast, as the study names a round's condition.
std::string condition_name(const std::string& pattern, double contrast);
std::string format_number(double v);  // %g

}  // namespace penumbra::analysis
