#pragma once
// One participant session: the procedure (procedure.h) with its crash-safe log and session.json in
// a locked directory. Replaying the log through the same procedure restores every staircase
// exactly and continues as if never interrupted.
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "log/directory_lock.h"
#include "log/trial_log.h"
#include "procedure/config.h"
#include "procedure/procedure.h"

namespace penumbra::procedure {

class Session {
 public:
  // A new session in `dir` (created; refused when it already holds a session). Both create and
  // resume lock the directory first (trial_log::DirectoryLock) and hold it for the Session's life,
  // so a second process on the same directory is refused before it reads or writes anything.
  // The session's seed is `seed` (--seed) or derived from the config's seed and the participant
  // id; its round order follows config.round_order (procedure.h, randomize). Both are recorded in
  // session.json ("randomization").
  static Session create(const StudyConfig& config, const std::filesystem::path& dir, const std::string& participant,
                        const nlohmann::json& extra, std::optional<std::uint64_t> seed = std::nullopt);
  // Replays dir/trials.csv after checking session.json (types, sizes, nesting, agreement with its
  // config block) and every row against it (replay_log: participant, session id, seed, design,
  // display, QUEST posteriors). `accept`, when given, sees the replayed session (its session.json,
  // config and next trial) and may throw to refuse (e.g. a command-line option that contradicts it). Only after all of that is a torn last line (the
  // trial on screen when the process died) cut off and anything written: a refused resume leaves
  // every byte as it was.
  static Session resume(const std::filesystem::path& dir,
                        const std::function<void(const Session&)>& accept = {});

  // The next trial, or nothing when every round is finished.
  std::optional<TrialPlan> next() const { return procedure_.next(); }
  // Records the answer: updates the staircase and appends the row (flushed and fsynced). `timing`:
  // how the stimulus was presented, from the windows (headless sessions have none).
  trial_log::TrialRow record(const TrialPlan& plan, const std::string& response, double rt_ms,
                             const std::optional<trial_log::FrameTiming>& timing = std::nullopt);
  // Admin: finish the current round now (persisted in session.json, honoured by resume).
  void end_round();
  // The participant view as it really is (video mode, refresh rate, window, full screen, GL
  // renderer), appended to session.json's "presentation" once per start or resume.
  void record_presentation(const nlohmann::json& presentation);

  bool correct_response(const TrialPlan& plan, const std::string& response) const {
    return procedure_.correct_response(plan, response);
  }
  std::string condition(int round) const { return procedure_.condition(round); }
  stimuli::StimulusSpec stimulus(int round, double artifact_px, double filter_radius_px, std::uint64_t seed) const {
    return procedure_.stimulus(round, artifact_px, filter_radius_px, seed);
  }
  const StudyConfig& config() const { return procedure_.config(); }
  const Randomization& randomization() const { return procedure_.randomization(); }
  int round_position(int round) const { return procedure_.round_position(round); }
  const std::vector<std::vector<Staircase>>& rounds() const { return procedure_.rounds(); }
  int current_round() const { return procedure_.current_round(); }  // rounds().size() when finished
  int trials_done() const { return procedure_.trials_done(); }
  const std::string& session_id() const { return session_id_; }
  const std::filesystem::path& dir() const { return dir_; }
  const nlohmann::json& session_json() const { return session_json_; }

 private:
  Session(const StudyConfig& config, const Randomization& randomization) : procedure_(config, randomization) {}
  static Session start(const StudyConfig& config, const std::filesystem::path& dir, const std::string& participant,
                       const nlohmann::json& extra, trial_log::DirectoryLock lock, std::optional<std::uint64_t> seed);
  trial_log::TrialRow make_row(const TrialPlan& plan, const std::string& response, double rt_ms, bool correct) const;
  void write_session_json() const;

  trial_log::DirectoryLock lock_;  // first member: released after the writer is closed
  Procedure procedure_;
  std::filesystem::path dir_;
  std::string session_id_, participant_;
  nlohmann::json session_json_;
  std::unique_ptr<trial_log::Writer> writer_;
};

std::string utc_now();

}  // namespace penumbra::procedure
