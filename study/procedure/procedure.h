#pragma once
// The study's procedure without a display or a log: interleaved QUEST staircases (one per artifact
// size) within rounds of (pattern, contrast), practice trials first (before the first round, or
// before every round with that round's condition: config.practice), and the stopping rule. All
// randomness of trial t comes from derive_seed(session seed, t), and the rounds run in the
// session's order, so feeding the logged answers back (replay_log in session_record.h) restores
// every staircase exactly. No GL: the fitter (analysis/) replays logs through the same code as
// penumbra-study's --resume.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "procedure/config.h"
#include "quest/quest.h"
#include "stimuli/stimulus_spec.h"

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
  std::string target;    // 2afc: left|right (side of the jagged one; a frame study: of the reference); yesno: jagged|straight
  // A frame study (config.frames): the multiple of the rule's c shown (a grid value) and the one
  // QUEST asked for; intensity = log10(1 / k). The patch is staircase_name.
  double k = 0, requested_k = 0;
};

struct Staircase {
  std::string name;
  double artifact_px = 0;  // 0 in a frame study (a staircase per patch)
  quest::Quest quest;
  bool done = false;
  std::vector<double> filter_radius_px;  // per trial, as shown (for the admin plot)
  std::vector<int> correct;
  // A tail staircase (config.tail_p_threshold): its QUEST aims at the tail's P(correct), not the
  // criterion; named by tail_staircase_name.
  bool tail = false;
};

// The name of the tail staircase beside `name` ("a10"): "a10@0.6" for a tail P(correct) 0.6, so
// that the log's staircase column says which target each trial's QUEST had.
std::string tail_staircase_name(const std::string& name, double tail_p_threshold);
// Whether `staircase` (the log's column) is a tail staircase of a session whose config has
// `tail_p_threshold` (0: none, so none is).
bool is_tail_staircase(const std::string& staircase, double tail_p_threshold);

// What differs between the sessions of one config: the seed of every random draw (target side,
// staircase, edge phase and orientation) and the order of the rounds. Recorded in session.json
// ("randomization"); a session.json without it (written before) is the config's seed and order.
struct Randomization {
  std::uint64_t seed = 1;
  std::string seed_from = "config";  // participant (config seed and participant id), --seed, or config
  std::vector<int> round_order;      // config round indices in the order they run
};
// The randomization of a new session: the seed from `explicit_seed` (--seed), else derived from the
// config's seed and the participant id; the rounds shuffled with that seed (config.round_order
// "shuffled"), in the config's order ("fixed") or the participant's Latin-square row ("latin-square").
Randomization randomize(const StudyConfig& config, const std::string& participant, std::optional<std::uint64_t> explicit_seed);
// The config's own seed and round order (sessions recorded before randomization existed).
Randomization config_randomization(const StudyConfig& config);
// round_order "latin-square": the participant's row of a Williams balanced Latin square over the
// config's n rounds, participant k (the number the id ends in: p1, p2, ...) taking row (k - 1) mod
// n (mod 2n for odd n, whose second n rows are the first reversed), so across n (2n) participants
// every round runs in every position equally often and follows every other equally often.
// Throws std::invalid_argument naming the participant when the id ends in no number.
int participant_number(const std::string& participant);
std::vector<int> latin_square_row(int rounds, int participant_number);
// Throws std::invalid_argument unless `order` is a permutation of the config's rounds.
void check_round_order(const StudyConfig& config, const std::vector<int>& order);

class Procedure {
 public:
  explicit Procedure(const StudyConfig& config) : Procedure(config, config_randomization(config)) {}
  Procedure(const StudyConfig& config, Randomization randomization);

  // The next trial, or nothing when every round is finished.
  std::optional<TrialPlan> next() const;
  // Counts the trial and updates its staircase (practice trials update none, nor do yes/no catch
  // trials unless the config scores yes/no balanced).
  void apply(const TrialPlan& plan, bool correct);
  // Finishes `round` now (the experimenter's "end round").
  void end_round(int round);

  // A stimulus of `round` (its pattern and contrast, the config's kernel, size and transfer): what
  // next() shows, and the instruction screens' examples.
  stimuli::StimulusSpec stimulus(int round, double artifact_px, double filter_radius_px, std::uint64_t seed) const;

  // Throws std::invalid_argument for a response the task does not have.
  bool correct_response(const TrialPlan& plan, const std::string& response) const;
  std::string condition(int round) const;  // "stair/1" etc.
  const StudyConfig& config() const { return config_; }
  const Randomization& randomization() const { return randomization_; }
  // 0 for the round that runs first, ... (the participant's "round k of n" is position + 1).
  int round_position(int round) const;
  const std::vector<std::vector<Staircase>>& rounds() const { return rounds_; }
  // The staircase a plan belongs to (for practice trials, one of its round's; it is not updated).
  const Staircase& staircase(const TrialPlan& plan) const;
  int current_round() const;  // rounds().size() when finished
  int trials_done() const { return trials_done_; }

 private:
  StudyConfig config_;
  Randomization randomization_;
  std::vector<std::vector<Staircase>> rounds_;
  std::vector<bool> ended_rounds_;
  int trials_done_ = 0;
  int practice_done_ = 0;
  std::vector<int> practice_done_in_round_;  // per config round (practice.every_round)
};

}  // namespace penumbra::procedure
