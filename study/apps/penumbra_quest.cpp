// penumbra-quest: plan and re-analyse QUEST staircases (docs/quest.md).
//   replay    rebuild a staircase from its responses (and intensities) and print its estimates
//   simulate  run many staircases against a planted observer and summarise the final estimates

#include <CLI/CLI.hpp>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "cli/checks.h"
#include "cli/main.h"
#include "cli/progress_bar.h"
#include "observers/staircase_simulation.h"
#include "published.h"
#include "psychometric/psychometric.h"
#include "quest/quest.h"
#include "text/fields.h"
#include "stats/summary.h"

namespace {

using Json = nlohmann::ordered_json;
using penumbra::ProgressBar;
using penumbra::quest::Quest;
using penumbra::quest::QuestParams;

// A user error: the message is printed as one line and the program exits with status 2.
using penumbra::cli::UsageError;

Json number(double value) { return std::isfinite(value) ? Json(value) : Json(nullptr); }

std::vector<std::string> split_commas(const std::string& text, const std::string& option) {
  std::vector<std::string> items;
  for (const std::string& field : penumbra::text::split_fields(text)) {
    const std::string item = penumbra::text::trim(field);
    if (item.empty())
      throw UsageError(option + ": empty item " + std::to_string(items.size() + 1) + " in '" + penumbra::text::printable(text) + "'");
    items.push_back(item);
  }
  return items;
}

std::vector<int> parse_responses(const std::string& text) {
  std::vector<int> responses;
  for (const std::string& item : split_commas(text, "--responses")) {
    if (item != "0" && item != "1")
      throw UsageError("--responses: item " + std::to_string(responses.size() + 1) + " is '" + penumbra::text::printable(item) +
                       "', expected 0 (incorrect) or 1 (correct)");
    responses.push_back(item == "1" ? 1 : 0);
  }
  return responses;
}

std::vector<double> parse_intensities(const std::string& text) {
  std::vector<double> values;
  for (const std::string& item : split_commas(text, "--intensities")) {
    double value = 0.0;
    const auto [end, error] = std::from_chars(item.data(), item.data() + item.size(), value);
    // +-inf is accepted (used at the table's edge, as Psychtoolbox does); NaN is not.
    if (error != std::errc() || end != item.data() + item.size() || std::isnan(value))
      throw UsageError("--intensities: item " + std::to_string(values.size() + 1) + " is '" + penumbra::text::printable(item) +
                       "', expected a number");
    values.push_back(value);
  }
  return values;
}

void print_warnings(const Quest& quest, std::size_t from = 0) {
  const auto& warnings = quest.warnings();
  for (std::size_t i = from; i < warnings.size(); ++i) std::cerr << "penumbra-quest: warning: " << warnings[i] << "\n";
}

struct QuestOptions {
  QuestParams params;
  double range = 0.0;

  void add_to(CLI::App& command, bool required) {
    auto* t = command.add_option("--tguess", params.t_guess, "prior threshold guess (log units)");
    auto* s = command.add_option("--tguess-sd", params.t_guess_sd, "prior sd (inf = flat prior)");
    auto* p = command.add_option("--pthreshold", params.p_threshold, "percent correct defining threshold");
    auto* b = command.add_option("--beta", params.beta, "Weibull slope (per log10 unit)");
    auto* d = command.add_option("--delta", params.delta, "fraction of blind presses");
    auto* g = command.add_option("--gamma", params.gamma, "guess rate");
    if (required) {
      for (auto* option : {t, s, p, b, d, g}) option->required();
    } else {
      for (auto* option : {t, s, p, b, d, g}) option->capture_default_str();
    }
    command.add_option("--grain", params.grain, "table step (log units)")->capture_default_str();
    command.add_option("--range", range, "table width (log units); without it dim = 500");
  }
  QuestParams resolved(const CLI::App& command) const {
    QuestParams result = params;
    if (command.count("--range") > 0) result.range = range;
    return result;
  }
};

int run_replay(const CLI::App& command, const QuestOptions& options, const std::string& responses_text,
               const std::string& intensities_text, const std::string& placement_name, double first,
               bool beta_analysis) {
  const std::vector<int> responses = parse_responses(responses_text);
  const bool have_intensities = command.count("--intensities") > 0;
  std::vector<double> intensities;
  if (have_intensities) {
    intensities = parse_intensities(intensities_text);
    if (intensities.size() != responses.size())
      throw UsageError("--intensities has " + std::to_string(intensities.size()) + " values but --responses has " +
                       std::to_string(responses.size()));
  }
  const auto placement = penumbra::observers::parse_placement(placement_name);
  if (!placement) throw UsageError("--placement: '" + penumbra::text::printable(placement_name) + "', expected quantile, mean or mode");
  if (command.count("--first") > 0 && !std::isfinite(first)) throw UsageError("--first must be finite");

  Quest quest(options.resolved(command));
  for (std::size_t k = 0; k < responses.size(); ++k) {
    double intensity = 0.0;
    if (have_intensities) {
      intensity = intensities[k];
    } else if (k == 0 && command.count("--first") > 0) {
      intensity = first;
    } else {
      switch (*placement) {
        case penumbra::observers::Placement::quantile:
          intensity = quest.quantile();
          break;
        case penumbra::observers::Placement::mean:
          intensity = quest.mean();
          break;
        case penumbra::observers::Placement::mode:
          intensity = quest.mode();
          break;
      }
    }
    quest.update(intensity, responses[k]);
  }
  print_warnings(quest);

  Json out;
  Json used = Json::array();
  for (double intensity : quest.intensities()) used.push_back(number(intensity));
  out["intensities"] = used;
  out["mean"] = number(quest.mean());
  out["sd"] = number(quest.sd());
  out["mode"] = number(quest.mode());
  out["quantile"] = number(quest.quantile());
  out["x_threshold"] = number(quest.x_threshold());
  out["quantile_order"] = number(quest.quantile_order());
  if (beta_analysis) {
    const auto analysis = penumbra::quest::beta_analysis(quest);
    out["beta_analysis"] = {{"t", number(analysis.t)},
                            {"sd", number(analysis.sd)},
                            {"beta", number(analysis.beta)},
                            {"beta_sd", number(analysis.beta_sd)}};
  }
  std::cout << out.dump(2) << "\n";
  return 0;
}

using penumbra::stats::median;

Json summary(const std::vector<double>& values, double truth) {
  double total = 0.0, squares = 0.0;
  std::vector<double> errors;
  for (double v : values) {
    total += v;
    errors.push_back(std::abs(v - truth));
  }
  const double mean = total / static_cast<double>(values.size());
  for (double v : values) squares += (v - mean) * (v - mean);
  const double sd = values.size() > 1 ? std::sqrt(squares / static_cast<double>(values.size() - 1)) : 0.0;
  return {{"median", number(median(values))},
          {"bias", number(mean - truth)},
          {"sd", number(sd)},
          {"median_abs_error", number(median(errors))}};
}

int run_simulate(const CLI::App& command, const QuestOptions& options, penumbra::observers::SimulationConfig config,
                 const std::string& method_name, const std::string& placement_name, const std::string& model_name,
                 bool no_progress) {
  const auto method = penumbra::observers::parse_method(method_name);
  if (!method) throw UsageError("--method: '" + penumbra::text::printable(method_name) + "', expected quest or questplus");
  const auto placement = penumbra::observers::parse_placement(placement_name);
  if (!placement) throw UsageError("--placement: '" + penumbra::text::printable(placement_name) + "', expected quantile, mean or mode");
  const auto model = penumbra::psychometric::parse_model(model_name);
  if (!model)
    throw UsageError("--observer-model: '" + penumbra::text::printable(model_name) + "', expected log-weibull, weibull, normal or logistic");
  config.quest = options.resolved(command);
  config.method = *method;
  config.placement = *placement;
  config.planted.model = *model;
  if (command.count("--observer-slope") == 0) config.planted.slope = config.quest.beta;
  if (command.count("--observer-guess") == 0) config.planted.guess = config.quest.gamma;
  if (command.count("--observer-lapse") == 0)
    config.planted.lapse = penumbra::psychometric::quest_lapse(config.quest.delta, config.quest.gamma);
  if (command.count("--observer-pthreshold") == 0) config.planted.p_threshold = config.quest.p_threshold;

  ProgressBar bar("simulate", !no_progress, " runs");
  const auto result = penumbra::observers::simulate_runs(config, [&bar](int done, int total) { bar(done, total); });

  std::vector<double> means, modes, sds, trials_to_sd;
  for (const auto& run : result.runs) {
    means.push_back(run.final_mean);
    modes.push_back(run.final_mode);
    sds.push_back(run.final_sd);
    if (run.trials_to_sd > 0) trials_to_sd.push_back(run.trials_to_sd);
  }
  Json out;
  out["method"] = config.method == penumbra::observers::Method::quest ? "quest" : "questplus";
  out["placement"] = config.method == penumbra::observers::Method::quest ? placement_name : "expected-entropy";
  out["runs"] = config.runs;
  out["trials"] = config.trials;
  out["seed"] = config.seed;
  out["c_true"] = config.planted.c_true;
  out["planted_threshold"] = number(result.planted_threshold);
  out["observer"] = {{"model", std::string(penumbra::psychometric::model_name(config.planted.model))},
                     {"slope", config.planted.slope},
                     {"guess", config.planted.guess},
                     {"lapse", config.planted.lapse},
                     {"p_threshold", config.planted.p_threshold}};
  out["final_mean"] = summary(means, result.planted_threshold);
  out["final_mode"] = summary(modes, result.planted_threshold);
  out["c_estimate_median"] = number(std::pow(10.0, -median(means)));
  out["final_sd_median"] = number(median(sds));
  out["sd_target"] = config.sd_target;
  out["trials_to_sd"] = {{"reached_runs", trials_to_sd.size()}, {"median", number(median(trials_to_sd))}};
  std::cout << out.dump(2) << "\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"penumbra-quest: Psychtoolbox-identical QUEST staircases, replayed or simulated"};
  penumbra::cli::describe_tool(app, "penumbra-quest", "quest.md");
  app.require_subcommand(1);

  auto* replay = app.add_subcommand("replay", "rebuild a staircase from its trials and print its estimates as JSON");
  QuestOptions replay_options;
  replay_options.add_to(*replay, true);
  std::string responses_text, intensities_text, replay_placement = "quantile";
  double first = 0.0;
  bool beta_analysis = false;
  replay->add_option("--responses", responses_text, "comma-separated 1 (correct) / 0 (incorrect)")->required();
  replay->add_option("--intensities", intensities_text, "comma-separated intensities used; default: placed by rule");
  replay->add_option("--placement", replay_placement, "quantile | mean | mode (when intensities are not given)")
      ->capture_default_str();
  replay->add_option("--first", first, "intensity of the first trial (when intensities are not given)");
  replay->add_flag("--beta-analysis", beta_analysis, "add QuestBetaAnalysis (threshold and slope free)");

  auto* simulate = app.add_subcommand("simulate", "run staircases against a planted observer; print the estimates' spread");
  QuestOptions simulate_options;
  simulate_options.params.t_guess = -std::log10(penumbra::kPublishedC);
  simulate_options.params.t_guess_sd = 0.5;
  simulate_options.add_to(*simulate, false);
  penumbra::observers::SimulationConfig config;
  std::string method_name = "quest", simulate_placement = "quantile", model_name = "log-weibull";
  bool no_progress = false;
  simulate->add_option("--c-true", config.planted.c_true, "planted threshold filter radius / artifact size")->required();
  simulate->add_option("--trials", config.trials, "trials per run")->capture_default_str();
  simulate->add_option("--runs", config.runs, "independent runs")->capture_default_str();
  simulate->add_option("--seed", config.seed, "RNG seed")->capture_default_str()->check(penumbra::cli::non_negative_integer());
  simulate->add_option("--method", method_name, "quest | questplus")->capture_default_str();
  simulate->add_option("--placement", simulate_placement, "QUEST placement: quantile | mean | mode")->capture_default_str();
  simulate->add_option("--sd-target", config.sd_target, "report trials until the posterior sd falls below this")
      ->capture_default_str()
      ->check(penumbra::cli::finite_range(0, 100));
  simulate->add_option("--artifact-px", config.artifact_px, "artifact size of the simulated stimuli")->capture_default_str();
  simulate->add_option("--observer-model", model_name, "log-weibull | weibull | normal | logistic")->capture_default_str();
  simulate->add_option("--observer-slope", config.planted.slope, "planted slope (default: --beta)");
  simulate->add_option("--observer-guess", config.planted.guess, "planted guess rate (default: --gamma)");
  simulate->add_option("--observer-lapse", config.planted.lapse, "planted lapse (default: delta * (1 - gamma))");
  simulate->add_option("--observer-pthreshold", config.planted.p_threshold,
                       "percent correct at which c_true is planted (default: --pthreshold)");
  simulate->add_flag("--no-progress", no_progress, "never draw the progress bar");

  try {
    app.parse(argc, argv);
    if (replay->parsed())
      return run_replay(*replay, replay_options, responses_text, intensities_text, replay_placement, first, beta_analysis);
    return run_simulate(*simulate, simulate_options, config, method_name, simulate_placement, model_name, no_progress);
  } catch (const CLI::ParseError& error) {
    if (error.get_exit_code() == 0) return app.exit(error);
    return penumbra::cli::fail("penumbra-quest: error", std::string(error.what()) + " (see --help)", penumbra::cli::kExitUsage);
  } catch (const UsageError& error) {
    return penumbra::cli::fail("penumbra-quest: error", error.what(), penumbra::cli::kExitUsage);
  } catch (const std::exception& error) {
    return penumbra::cli::fail("penumbra-quest: error", error.what());
  }
}
