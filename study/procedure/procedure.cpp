#include "procedure/procedure.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "sampling/random.h"
#include "text/fingerprint.h"
#include "text/printable.h"

namespace penumbra::procedure {

namespace {
std::string fmt(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%g", v);
  return b;
}
}  // namespace

namespace {
constexpr std::uint64_t kRoundOrderStream = 0x726f756e645f6f72ull;  // "round_or": apart from the trials' streams
}  // namespace

Randomization config_randomization(const StudyConfig& config) {
  Randomization r;
  r.seed = config.seed;
  r.seed_from = "config";
  for (std::size_t i = 0; i < config.rounds.size(); ++i) r.round_order.push_back(static_cast<int>(i));
  return r;
}

Randomization randomize(const StudyConfig& config, const std::string& participant, std::optional<std::uint64_t> explicit_seed) {
  Randomization r = config_randomization(config);
  if (explicit_seed) {
    r.seed = *explicit_seed;
    r.seed_from = "--seed";
  } else {
    r.seed = sampling::derive_seed(config.seed, text::fnv1a64(participant)) >> 12;  // fits a double and a JSON number exactly
    r.seed_from = "participant";
  }
  if (config.round_order == "shuffled") {
    sampling::Random random(sampling::derive_seed(r.seed, kRoundOrderStream));
    for (std::size_t i = r.round_order.size(); i > 1; --i) std::swap(r.round_order[i - 1], r.round_order[random.bits() % i]);
  }
  if (config.round_order == "latin-square") r.round_order = latin_square_row(static_cast<int>(config.rounds.size()), participant_number(participant));
  return r;
}

int participant_number(const std::string& participant) {
  std::size_t digits = 0;
  while (digits < participant.size() && digits < 9 && std::isdigit(static_cast<unsigned char>(participant[participant.size() - 1 - digits])))
    ++digits;
  if (digits == 0)
    throw std::invalid_argument("round_order latin-square: participant '" + text::printable(participant) +
                                "' ends in no number to choose its row of the square (use ids like p1, p2, ...)");
  return std::stoi(participant.substr(participant.size() - digits));
}

std::vector<int> latin_square_row(int n, int participant) {
  // Williams: the first row 0, 1, n-1, 2, n-2, ...; row k adds k (mod n). For even n every round
  // follows every other exactly once across the n rows; odd n needs the n rows reversed as well.
  std::vector<int> first;
  for (int j = 0, lo = 1, hi = n - 1; j < n; ++j) first.push_back(j == 0 ? 0 : (j % 2 == 1 ? lo++ : hi--));
  const int rows = n % 2 == 0 ? n : 2 * n;
  const int k = ((participant - 1) % rows + rows) % rows;
  std::vector<int> row;
  for (int j = 0; j < n; ++j) row.push_back((first[static_cast<std::size_t>(j)] + k) % n);
  if (k >= n) std::reverse(row.begin(), row.end());
  return row;
}

void check_round_order(const StudyConfig& config, const std::vector<int>& order) {
  std::vector<int> sorted = order;
  std::sort(sorted.begin(), sorted.end());
  for (std::size_t i = 0; i < sorted.size(); ++i)
    if (sorted[i] != static_cast<int>(i)) sorted.clear();
  if (sorted.size() != config.rounds.size())
    throw std::invalid_argument("expected each of the config's " + std::to_string(config.rounds.size()) + " rounds (0.." +
                                std::to_string(config.rounds.size() - 1) + ") once");
}

std::string tail_staircase_name(const std::string& name, double tail_p_threshold) { return name + "@" + fmt(tail_p_threshold); }

bool is_tail_staircase(const std::string& staircase, double tail_p_threshold) {
  const std::size_t at = staircase.rfind('@');
  return tail_p_threshold > 0 && at != std::string::npos && staircase.substr(at + 1) == fmt(tail_p_threshold);
}

int Procedure::round_position(int round) const {
  const auto& order = randomization_.round_order;
  const auto it = std::find(order.begin(), order.end(), round);
  return it == order.end() ? static_cast<int>(order.size()) : static_cast<int>(it - order.begin());
}

Procedure::Procedure(const StudyConfig& config, Randomization randomization) : config_(config), randomization_(std::move(randomization)) {
  check_round_order(config_, randomization_.round_order);
  for (std::size_t r = 0; r < config_.rounds.size(); ++r) {
    std::vector<Staircase> round;
    for (double a : config_.artifact_px) round.push_back({"a" + fmt(a), a, quest::Quest(config_.quest), false, {}, {}});
    // After the criterion's staircases, so that practice (which walks the first ones) and the
    // staircases of configs without a tail are as before. The same prior: its sd (1 log10 unit by
    // default) spans the tail's offset (-0.19 for P 0.6 at slope 3.5).
    if (config_.tail_p_threshold > 0) {
      quest::QuestParams tail = config_.quest;
      tail.p_threshold = config_.tail_p_threshold;
      for (double a : config_.artifact_px)
        round.push_back({tail_staircase_name("a" + fmt(a), tail.p_threshold), a, quest::Quest(tail), false, {}, {}, true});
    }
    for (const FramePatch& patch : config_.frames.patches) round.push_back({patch.name, 0, quest::Quest(config_.quest), false, {}, {}});
    rounds_.push_back(std::move(round));
  }
  ended_rounds_.assign(config_.rounds.size(), false);
  practice_done_in_round_.assign(config_.rounds.size(), 0);
}

std::string Procedure::condition(int round) const {
  const auto& r = config_.rounds.at(static_cast<std::size_t>(round));
  if (config_.frames.enabled()) return r.technique;
  return stimuli::to_string(r.pattern) + "/" + fmt(r.contrast);
}

int Procedure::current_round() const {
  for (const int r : randomization_.round_order) {
    if (ended_rounds_[static_cast<std::size_t>(r)]) continue;
    for (const auto& sc : rounds_[static_cast<std::size_t>(r)])
      if (!sc.done) return r;
  }
  return static_cast<int>(rounds_.size());
}

void Procedure::end_round(int round) { ended_rounds_.at(static_cast<std::size_t>(round)) = true; }

const Staircase& Procedure::staircase(const TrialPlan& plan) const {
  return rounds_.at(static_cast<std::size_t>(plan.round)).at(static_cast<std::size_t>(plan.staircase));
}

std::optional<TrialPlan> Procedure::next() const {
  TrialPlan p;
  p.trial = trials_done_;
  sampling::Random random(sampling::derive_seed(randomization_.seed, static_cast<std::uint64_t>(p.trial)));
  double artifact = 0, x = 0;
  const Practice& practice = config_.practice;
  // Before the first round only (configs before the practice block: the first round in the
  // session's order, even one the experimenter ended at the start), or before every round.
  int practice_done = practice_done_;
  if (practice.every_round) {
    p.round = current_round();
    if (p.round >= static_cast<int>(rounds_.size())) return std::nullopt;
    practice_done = practice_done_in_round_[static_cast<std::size_t>(p.round)];
  } else {
    p.round = randomization_.round_order.front();
  }
  const int staircases = static_cast<int>(config_.artifact_px.size() + config_.frames.patches.size());
  if (practice_done < practice.trials) {
    p.practice = true;  // shows the round's pattern and contrast
    p.staircase = practice_done % staircases;
    artifact = config_.frames.enabled() ? 0.0 : config_.artifact_px[static_cast<std::size_t>(p.staircase)];
    x = practice.intensity;
    p.staircase_name = rounds_[static_cast<std::size_t>(p.round)][static_cast<std::size_t>(p.staircase)].name;
    random.bits();  // the staircase draw a main trial makes, so both use the stream alike
  } else {
    p.round = current_round();
    if (p.round >= static_cast<int>(rounds_.size())) return std::nullopt;
    const auto& round = rounds_[static_cast<std::size_t>(p.round)];
    std::vector<int> open;
    for (std::size_t i = 0; i < round.size(); ++i)
      if (!round[i].done) open.push_back(static_cast<int>(i));
    p.staircase = open[random.bits() % open.size()];
    const Staircase& sc = round[static_cast<std::size_t>(p.staircase)];
    p.staircase_name = sc.name;
    artifact = sc.artifact_px;
    x = sc.quest.quantile();
    if (config_.frames.enabled()) p.requested_k = std::pow(10.0, -x);
    x = std::clamp(x, config_.intensity_min, config_.intensity_max);
  }
  if (config_.frames.enabled()) {
    // QUEST's suggestion rounded to the grid of k: every frame a session shows is one of a few, rendered once.
    p.k = config_.frames.round_k(std::pow(10.0, -x));
    if (p.practice) p.requested_k = p.k;
    p.clamped = p.requested_k < config_.frames.k_min * (1 - 1e-12) || p.requested_k > config_.frames.k_max * (1 + 1e-12);
    p.intensity = -std::log10(p.k);
    p.target = random.uniform() < 0.5 ? "left" : "right";  // the side of the reference
    p.stimulus = stimulus(p.round, 0, 0, random.bits() >> 12);
    return p;
  }
  p.requested_filter_radius_px = artifact / std::pow(10.0, x);
  const auto shown = stimuli::clamp_filter_radius(p.requested_filter_radius_px, config_.stimulus_size_px);
  p.clamped = shown.clamped;
  p.intensity = std::log10(artifact / shown.filter_radius_px);
  const bool first = random.uniform() < 0.5;
  p.target = config_.task == "2afc" ? (first ? "left" : "right") : (first ? "jagged" : "straight");
  p.stimulus = stimulus(p.round, artifact, shown.filter_radius_px, random.bits() >> 12);  // the seed fits a double and a JSON number exactly
  return p;
}

stimuli::StimulusSpec Procedure::stimulus(int round, double artifact_px, double filter_radius_px, std::uint64_t seed) const {
  const auto& rc = config_.rounds.at(static_cast<std::size_t>(round));
  stimuli::StimulusSpec s;
  if (config_.frames.enabled()) {  // a patch of a frame: its size, the display's transfer and the seed; the plan holds k
    s.technique = rc.technique;
    s.size_px = config_.stimulus_size_px;
    s.transfer = config_.display.transfer;
    s.seed = seed;
    return s;
  }
  s.pattern = rc.pattern;
  s.artifact_px = artifact_px;
  s.filter_radius_px = filter_radius_px;
  s.lit_linear = rc.contrast;
  s.kernel = config_.kernel;
  s.poisson_taps = config_.poisson_taps;
  s.technique = config_.technique;
  s.technique_settings = config_.technique_settings;
  s.size_px = config_.stimulus_size_px;
  s.transfer = config_.display.transfer;
  s.seed = seed;
  return s;
}

bool Procedure::correct_response(const TrialPlan& plan, const std::string& response) const {
  if (config_.task == "2afc") {
    if (response != "left" && response != "right") throw std::invalid_argument("2afc response must be left or right");
    return response == plan.target;
  }
  if (response != "yes" && response != "no") throw std::invalid_argument("yesno response must be yes or no");
  return (response == "yes") == (plan.target == "straight");
}

void Procedure::apply(const TrialPlan& plan, bool correct) {
  ++trials_done_;
  if (plan.practice) {
    ++practice_done_;
    ++practice_done_in_round_.at(static_cast<std::size_t>(plan.round));
    return;
  }
  // yesno: a straight stimulus (catch trial) says nothing about the artifact's visibility; only
  // the jagged ones update QUEST, with "not straight" = detected. Scored balanced, the straight
  // ones count too (correct = "straight"), as a percent correct over both kinds.
  if (config_.task == "yesno" && plan.target == "straight" && config_.yesno_scoring != "balanced") return;
  Staircase& sc = rounds_[static_cast<std::size_t>(plan.round)][static_cast<std::size_t>(plan.staircase)];
  sc.quest.update(plan.intensity, correct ? 1 : 0);
  sc.filter_radius_px.push_back(plan.stimulus.filter_radius_px);
  sc.correct.push_back(correct ? 1 : 0);
  const int n = static_cast<int>(sc.quest.trial_count());
  sc.done = n >= config_.max_trials || (n >= config_.min_trials && sc.quest.sd() < config_.sd_below);
}

}  // namespace penumbra::procedure
