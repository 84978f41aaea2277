#pragma once
// Monte-Carlo runs of a staircase against a simulated observer: the planning tool behind
// `penumbra-quest simulate`. Each run k uses its own RNG stream derived from (seed, k), so any run
// can be reproduced alone and the summary does not depend on how runs are scheduled.

#include <cstdint>
#include <functional>
#include <optional>
#include <string_view>
#include <vector>

#include <penumbra/observers/observer.h>
#include <penumbra/observers/psychometric_observer.h>
#include <penumbra/quest/quest.h>

namespace penumbra::observers {

enum class Placement { quantile, mean, mode };
enum class Method { quest, quest_plus };
std::optional<Placement> parse_placement(std::string_view name);
std::optional<Method> parse_method(std::string_view name);

struct SimulationConfig {
  quest::QuestParams quest;   // the staircase's assumptions (prior, slope, guess, lapse)
  PlantedModel planted;       // the simulated observer's truth
  Method method = Method::quest;
  Placement placement = Placement::quantile;  // QUEST only; QUEST+ places by expected entropy
  double artifact_px = 4.0;   // intensity is log10(a / r), so the threshold does not depend on it
  int trials = 40;
  int runs = 200;
  std::uint64_t seed = 1;
  double sd_target = 0.05;    // report the trial at which the posterior sd first falls below it
};

struct RunResult {
  double final_mean;     // posterior mean (QuestMean) after the last trial
  double final_mode;     // posterior mode
  double final_sd;       // posterior sd
  int trials_to_sd;      // first trial count with posterior sd < sd_target; -1 if never
};

struct SimulationResult {
  double planted_threshold;  // -log10(c_true), in intensity units
  std::vector<RunResult> runs;
};

// Throws std::invalid_argument for a bad configuration. `progress(done, total)` is called after
// each run when given.
SimulationResult simulate_runs(const SimulationConfig& config,
                               const std::function<void(int done, int total)>& progress = {});

// One staircase run of `trials` trials against `observer` (any Observer, e.g. an image-based one).
RunResult run_quest(const SimulationConfig& config, Observer& observer);
RunResult run_quest_plus(const SimulationConfig& config, Observer& observer);

}  // namespace penumbra::observers
