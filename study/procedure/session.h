#pragma once
// One participant session: interleaved QUEST staircases (one per artifact size) within rounds of
// (pattern, contrast), practice trials first, the stopping rule, and the crash-safe log. All
// randomness of trial t comes from derive_seed(config.seed, t), so replaying the log through
// the same procedure restores every staircase exactly and continues as if never interrupted.
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "log/directory_lock.h"
#include "log/trial_log.h"
#include "procedure/config.h"
#include "quest/quest.h"
#include "stimuli/stimulus.h"

namespace penumbra::procedure {

struct TrialPlan {
  int round = 0;
  int trial = 0;
  int staircase = -1;  // index within the round
  std::string staircase_name;
  bool practice = false;
  stimuli::StimulusSpec stimulus;  // filter_radius_px as shown
  double requested_filter_radius_px = 0;
  bool clamped = false;
  double intensity = 0;  // log10(a / r) as shown
  std::string target;    // 2afc: left|right (side of the jagged one); yesno: jagged|straight
};

struct Staircase {
  std::string name;
  double artifact_px = 0;
  quest::Quest quest;
  bool done = false;
  std::vector<double> filter_radius_px;  // per trial, as shown (for the admin plot)
  std::vector<int> correct;
};

class Session {
 public:
  // A new session in `dir` (created; refused when it already holds a session). Both create and
  // resume lock the directory first (trial_log::DirectoryLock) and hold it for the Session's life,
  // so a second process on the same directory is refused before it reads or writes anything.
  static Session create(const StudyConfig& config, const std::filesystem::path& dir, const std::string& participant,
                        const nlohmann::json& extra);
  // Replays dir/trials.csv after checking session.json (types, sizes, nesting, agreement with its
  // config block) and every row against it (participant, session id, seed, design, display, QUEST
  // posteriors). `accept`, when given, sees the checked session.json and its config and may throw to refuse (e.g.
  // a command-line option that contradicts it). Only after all of that is a torn last line (the
  // trial on screen when the process died) cut off and anything written: a refused resume leaves
  // every byte as it was.
  static Session resume(const std::filesystem::path& dir,
                        const std::function<void(const nlohmann::json&, const StudyConfig&)>& accept = {});

  // The next trial, or nothing when every round is finished.
  std::optional<TrialPlan> next() const;
  // Records the answer: updates the staircase and appends the row (flushed and fsynced).
  trial_log::TrialRow record(const TrialPlan& plan, const std::string& response, double rt_ms);
  // Admin: finish the current round now (persisted in session.json, honoured by resume).
  void end_round();

  bool correct_response(const TrialPlan& plan, const std::string& response) const;
  std::string condition(int round) const;  // "stair/1" etc.
  const StudyConfig& config() const { return config_; }
  const std::vector<std::vector<Staircase>>& rounds() const { return rounds_; }
  int current_round() const;  // rounds().size() when finished
  int trials_done() const { return trials_done_; }
  bool break_due() const;     // a break screen belongs before the next trial
  const std::string& session_id() const { return session_id_; }
  const std::filesystem::path& dir() const { return dir_; }
  const nlohmann::json& session_json() const { return session_json_; }

 private:
  Session() = default;
  void init_staircases();
  void apply(const TrialPlan& plan, bool correct);
  trial_log::TrialRow make_row(const TrialPlan& plan, const std::string& response, double rt_ms, bool correct) const;
  void write_session_json() const;

  trial_log::DirectoryLock lock_;  // first member: released after the writer is closed
  StudyConfig config_;
  std::filesystem::path dir_;
  std::string session_id_, participant_;
  nlohmann::json session_json_;
  std::vector<std::vector<Staircase>> rounds_;
  std::vector<bool> ended_rounds_;
  int trials_done_ = 0;
  int practice_done_ = 0;
  std::unique_ptr<trial_log::Writer> writer_;
};

std::string utc_now();

}  // namespace penumbra::procedure
