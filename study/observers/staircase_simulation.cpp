#include "observers/staircase_simulation.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <string>

#include "psychometric/psychometric.h"
#include "quest/quest_plus.h"
#include "sampling/random.h"

namespace penumbra::observers {
namespace {

constexpr const char* kCondition = "simulated";

Stimulus stimulus_at(const SimulationConfig& config, double intensity) {
  return {kCondition, config.artifact_px, config.artifact_px / std::pow(10.0, intensity)};
}

}  // namespace

std::optional<Placement> parse_placement(std::string_view name) {
  if (name == "quantile") return Placement::quantile;
  if (name == "mean") return Placement::mean;
  if (name == "mode") return Placement::mode;
  return std::nullopt;
}

std::optional<Method> parse_method(std::string_view name) {
  if (name == "quest") return Method::quest;
  if (name == "questplus" || name == "quest+" || name == "quest_plus") return Method::quest_plus;
  return std::nullopt;
}

RunResult run_quest(const SimulationConfig& config, Observer& observer) {
  quest::Quest staircase(config.quest);
  RunResult result{0.0, 0.0, 0.0, -1};
  for (int trial = 1; trial <= config.trials; ++trial) {
    double intensity = 0.0;
    switch (config.placement) {
      case Placement::quantile:
        intensity = staircase.quantile();
        break;
      case Placement::mean:
        intensity = staircase.mean();
        break;
      case Placement::mode:
        intensity = staircase.mode();
        break;
    }
    const Response response = observer.respond(stimulus_at(config, intensity));
    staircase.update(intensity, response.correct ? 1 : 0);
    if (result.trials_to_sd < 0 && staircase.sd() < config.sd_target) result.trials_to_sd = trial;
  }
  result.final_mean = staircase.mean();
  result.final_mode = staircase.mode();
  result.final_sd = staircase.sd();
  return result;
}

RunResult run_quest_plus(const SimulationConfig& config, Observer& observer) {
  // Threshold-only QUEST+ over QUEST's own domain (tGuess +- dim/2 grain) at <= 201 points, with
  // QUEST's slope, guess and lapse and its Gaussian prior, so the two methods differ only in
  // placement and estimation.
  const quest::QuestParams& q = config.quest;
  const int dim = quest::quest_dim(q);
  const double half_width = dim / 2 * q.grain;
  const int points = std::min(dim, 200) + 1;
  std::vector<double> grid(static_cast<std::size_t>(points));
  std::vector<double> prior(grid.size());
  for (int i = 0; i < points; ++i) {
    grid[static_cast<std::size_t>(i)] = q.t_guess - half_width + 2.0 * half_width * i / (points - 1);
    const double z = (grid[static_cast<std::size_t>(i)] - q.t_guess) / q.t_guess_sd;
    prior[static_cast<std::size_t>(i)] = std::exp(-0.5 * z * z);
  }
  const double lapse = psychometric::quest_lapse(q.delta, q.gamma);
  const double p_threshold = q.p_threshold;
  const double guess = q.gamma;
  auto model = [p_threshold, guess](double x, const quest::QuestPlusParameter& theta) {
    const double alpha = psychometric::alpha_for_threshold(psychometric::Model::log_weibull, theta.threshold,
                                                           p_threshold, theta.slope, guess, theta.lapse);
    return psychometric::probability(psychometric::Model::log_weibull, x, {alpha, theta.slope, guess, theta.lapse});
  };
  quest::QuestPlus staircase(grid, quest::quest_plus_grid(grid, {q.beta}, {lapse}), model, prior);
  RunResult result{0.0, 0.0, 0.0, -1};
  for (int trial = 1; trial <= config.trials; ++trial) {
    const double intensity = staircase.next();
    const Response response = observer.respond(stimulus_at(config, intensity));
    staircase.update(intensity, response.correct ? 1 : 0);
    if (result.trials_to_sd < 0 && staircase.threshold_sd() < config.sd_target) result.trials_to_sd = trial;
  }
  result.final_mean = staircase.posterior_mean().threshold;
  result.final_mode = staircase.posterior_mode().threshold;
  result.final_sd = staircase.threshold_sd();
  return result;
}

SimulationResult simulate_runs(const SimulationConfig& config, const std::function<void(int, int)>& progress) {
  if (config.trials < 1) throw std::invalid_argument("trials must be at least 1");
  if (config.runs < 1) throw std::invalid_argument("runs must be at least 1");
  if (!(config.artifact_px > 0.0)) throw std::invalid_argument("artifact_px must be positive");
  quest::Quest validate(config.quest);  // fail before the first run on bad QUEST parameters
  SimulationResult result{-std::log10(config.planted.c_true), {}};
  result.runs.reserve(static_cast<std::size_t>(config.runs));
  for (int run = 0; run < config.runs; ++run) {
    PsychometricObserver observer({{kCondition, config.planted}},
                                  sampling::derive_seed(config.seed, static_cast<std::uint64_t>(run)));
    result.runs.push_back(config.method == Method::quest ? run_quest(config, observer)
                                                         : run_quest_plus(config, observer));
    if (progress) progress(run + 1, config.runs);
  }
  return result;
}

}  // namespace penumbra::observers
