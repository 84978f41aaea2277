// penumbra-fit: thresholds and the constant c of r = c a from the study's logs (docs/fit.md).
//   penumbra-fit SESSION_DIR... -o OUT [--reference reference.json] [--bootstrap 1000] [--accept-inconsistent] [--pool]
//   penumbra-fit psychometric --input data.csv [--format counts|trials] [--family log-weibull]
#include <CLI/CLI.hpp>
#include <glog/logging.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <optional>
#include <set>
#include <thread>

#include "data/dataset.h"
#include "data/level_data.h"
#include "data/online_quality.h"
#include "data/reference_table.h"
#include "fit/frame_fit.h"
#include "fit/model_fit.h"
#include "fit/plan.h"
#include "fit/study_fit.h"
#include "report/outputs.h"
#include "cli/progress_bar.h"
#include "cli/checks.h"
#include "cli/main.h"
#include "io/atomic_file.h"
#include "io/staged_dir.h"
#include "json/json_input.h"

namespace fs = std::filesystem;
using namespace penumbra;
using namespace penumbra::analysis;

namespace {

struct ModelOptions {
  std::string family = "log-weibull";
  std::optional<double> guess;
  std::optional<double> lapse;
  double lapse_max = 0.06;
  std::optional<double> p_threshold;
};

void add_model_options(CLI::App& app, ModelOptions& o) {
  app.add_option("--family", o.family, "log-weibull (QUEST's), weibull, normal or logistic")->capture_default_str();
  app.add_option("--guess", o.guess,
                 "guess rate gamma, fixed (default 0.5; for session logs the sessions' QUEST gamma)");
  auto* lapse = app.add_option("--lapse", o.lapse, "hold the lapse rate lambda at this value");
  app.add_option("--lapse-max", o.lapse_max, "otherwise lambda is free in [0, this]")->capture_default_str()->excludes(lapse);
  app.add_option("--p-threshold", o.p_threshold,
                 "percent correct that defines the threshold (default: QUEST's pThreshold from session.json, else 0.82)");
}

psychometric::Model parse_family(const std::string& name) {
  const auto model = psychometric::parse_model(name);
  if (!model)
    throw std::invalid_argument("--family '" + json_input::printable(name) + "': expected log-weibull, weibull, normal or logistic");
  return *model;
}

// A rate as the error lines show it ("0.5", "0.82").
std::string rate_text(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", v);
  return text;
}

// The progress of the run's phases on stderr, one bar per phase named after it (cli/progress_bar.h:
// redrawn in place on a terminal; in a log, whole lines: one once the phase has run half a second,
// then at most one every ten seconds, and always its last).
class PhaseProgress {
 public:
  explicit PhaseProgress(bool enabled) : enabled_(enabled) {}
  void operator()(const std::string& phase, int done, int total) {
    if (!enabled_) return;
    if (!bar_ || phase != phase_) {
      bar_.reset();
      bar_.emplace(phase, true, phase == "bootstrap" ? " resamples" : "");
      phase_ = phase;
    }
    (*bar_)(done, total);
  }
  // Ends the last bar's line (on a terminal) before other output.
  void end() { bar_.reset(); }

 private:
  bool enabled_;
  std::optional<ProgressBar> bar_;
  std::string phase_;
};

LapseSpec lapse_of(const ModelOptions& o) {
  LapseSpec l;
  l.fixed = o.lapse;
  l.max = o.lapse_max;
  const double guess = o.guess.value_or(0.5);
  // The guess rate first: the lapse bounds below are stated in terms of it.
  if (o.guess && !(*o.guess >= 0 && *o.guess < 1)) throw std::invalid_argument("--guess: expected a rate in [0, 1)");
  if (o.lapse && !(*o.lapse >= 0 && *o.lapse < 1 - guess))
    throw std::invalid_argument("--lapse: expected a value in [0, 1 - guess)");
  if (!o.lapse && !(o.lapse_max > 0 && o.lapse_max < 1 - guess))
    throw std::invalid_argument("--lapse-max: expected a value in (0, 1 - guess)");
  return l;
}

int run_psychometric(const fs::path& input, const std::string& format, const ModelOptions& o) {
  LevelFormat f;
  if (format == "counts") f = LevelFormat::counts;
  else if (format == "trials") f = LevelFormat::trials;
  else throw std::invalid_argument("--format '" + json_input::printable(format) + "': expected counts or trials");
  ModelSpec spec;
  spec.family = parse_family(o.family);
  spec.guess = o.guess.value_or(0.5);
  spec.lapse = lapse_of(o);
  spec.p_threshold = o.p_threshold.value_or(0.82);
  // The option, not the counts file, when the criterion lies outside what the curve reaches (it
  // runs from the guess rate to 1; the criterion's lapse is 0 here).
  if (o.p_threshold && !(spec.p_threshold > spec.guess && spec.p_threshold < 1))
    throw std::invalid_argument("--p-threshold " + rate_text(spec.p_threshold) + ": expected a proportion correct in (" +
                                rate_text(spec.guess) + ", 1), above the guess rate");
  std::vector<BinomialRow> rows = read_level_data(input, f);
  spec.groups.push_back({rows, 0, 0.0});
  const FitResult fit = [&] {
    try {
      return analysis::fit(spec);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(input.string() + ": " + e.what());
    }
  }();
  const double beta = std::exp(fit.params.log_beta);
  const double u = fit.params.u[0];
  const bool weibull = spec.family == psychometric::Model::weibull;
  const double threshold = weibull ? std::pow(10.0, u) : u;
  const double threshold_se = weibull ? threshold * std::log(10.0) * fit.se(0) : fit.se(0);
  nlohmann::json out = {
      {"input", input.string()},
      {"format", format},
      {"family", psychometric::model_name(spec.family)},
      {"model", "psi(x) = gamma + (1 - gamma - lambda) F(x; alpha, beta)"},
      {"parameters", {{"alpha", number(alpha_of(spec, u, beta))},
                      {"beta", number(beta)},
                      {"gamma", spec.guess},
                      {"lambda", number(fit.params.lambda)}}},
      {"standard_errors", {{"alpha", number(alpha_se(spec, fit, 0))},
                           {"beta", number(beta * fit.se(fit.index_log_beta()))},
                           {"lambda", number(fit.se(fit.index_lambda()))}}},
      {"lapse", spec.lapse.fixed ? nlohmann::json{{"fixed", *spec.lapse.fixed}}
                                 : nlohmann::json{{"bounds", {0.0, spec.lapse.max}}}},
      {"threshold", {{"p_correct", spec.p_threshold}, {"x", number(threshold)}, {"se", number(threshold_se)}}},
      {"negative_log_likelihood", number(fit.nll)},
      {"deviance", number(fit.deviance)},
      {"trials", fit.trials},
      {"levels", rows.size()},
      {"converged", fit.converged},
      {"flags", fit.flags.list}};
  std::cout << out.dump(2) << "\n";
  return 0;
}

struct StudyOptions {
  std::vector<fs::path> inputs;
  fs::path output;
  std::vector<fs::path> references;
  std::optional<std::string> condition;
  int bootstrap = 1000;
  std::uint64_t seed = 1;
  int threads = 0;
  bool no_progress = false;
  double observer_percentile = 90;  // the multilevel fit's observer percentile, in per cent
  bool accept_inconsistent = false;
  bool pool = false;
  bool pool_observers = false;
  bool allow_unusable = false;
  std::optional<std::string> exclude_quality;  // --exclude-quality: data-quality criteria (data/online_quality.h)
};

// The sessions' data quality and what the criteria exclude: the inputs left to fit, and the table
// and report.json block when there is anything to report (a browser session, or criteria given).
struct QualityCheck {
  std::vector<fs::path> fitted;
  int excluded = 0;
  std::string table;
  nlohmann::json report;
};

QualityCheck check_quality(const StudyOptions& so, const std::vector<QualityCriterion>& criteria) {
  std::vector<SessionQuality> sessions = read_quality(so.inputs);
  QualityCheck out;
  out.excluded = apply_quality_criteria(sessions, criteria);
  for (std::size_t i = 0; i < sessions.size(); ++i)
    if (sessions[i].excluded_because.empty()) out.fitted.push_back(so.inputs[i]);
  if (quality_reported(sessions, criteria)) {
    out.table = quality_table(sessions, criteria);
    out.report = quality_json(sessions, criteria);
  }
  if (out.excluded > 0 && out.fitted.empty()) {
    std::cout << out.table;
    throw std::runtime_error("every session is excluded by --exclude-quality " + *so.exclude_quality + " (the table above says why); nothing to fit");
  }
  return out;
}

// A frame study's sessions: k* per patch, per technique and pooled (fit/frame_fit.h) into
// report.json and summary.txt; no calibration.json (k* is a verdict on c, not a new c).
int run_frame_study(const StudyOptions& so, const StudyFitOptions& options, const Dataset& data, PhaseProgress& progress,
                    const QualityCheck& quality) {
  if (!so.references.empty()) throw std::invalid_argument("--reference: a frame study has no reference filter sizes");
  if (so.condition) throw std::invalid_argument("--condition: a frame study writes no calibration entry to choose one for");
  std::set<std::string> kinds;
  for (const SessionInfo& s : data.sessions) kinds.insert(s.observer_kind);
  if (kinds.size() > 1 && !so.pool_observers)
    throw std::runtime_error("the sessions were answered by different kinds of observer (people, simulations, the image observer); "
                             "fit them apart, or --pool-observers");
  progress("reading logs", static_cast<int>(so.inputs.size()), static_cast<int>(so.inputs.size()));
  progress.end();
  const auto start = std::chrono::steady_clock::now();
  const FrameStudyFit fit = fit_frame_study(data, options);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::vector<std::string> inputs;
  for (const fs::path& p : so.inputs) inputs.push_back(p.string());
  nlohmann::json report = frame_report_json(fit, inputs, utc_now());
  report["fit_seconds"] = seconds;
  if (!quality.report.is_null()) report["data_quality"] = quality.report;
  const std::string summary = frame_summary_text(fit) + quality.table;
  io::StagedDirectory out(so.output.string(), "report.json");
  io::write_file_atomic(out.path() / "summary.txt", summary);
  io::write_file_atomic(out.path() / "report.json", json_input::dump(report, 1) + "\n");
  out.commit();
  std::cout << summary;
  std::printf("fit took %.2f s; wrote %s/{report.json, summary.txt}\n", seconds, so.output.string().c_str());
  return 0;
}

int run_study(const StudyOptions& so, const ModelOptions& mo) {
  if (so.output.empty()) throw std::invalid_argument("-o/--output DIR is required");
  StudyFitOptions options;
  options.family = parse_family(mo.family);
  options.guess = mo.guess;
  options.lapse = lapse_of(mo);
  options.p_threshold = mo.p_threshold;
  options.bootstrap = so.bootstrap;
  options.seed = so.seed;
  options.observer_percentile = so.observer_percentile / 100.0;
  options.threads = so.threads;
  // Read before the long work so a bad file fails at once. Several files (e.g. one per partner or
  // pattern) are searched in order; the first entry for a (pattern, contrast, size) wins.
  std::optional<ReferenceTable> reference;
  for (const fs::path& path : so.references) {
    ReferenceTable table = load_reference_table(path);
    if (!reference) {
      reference = std::move(table);
      continue;
    }
    reference->file += ", " + table.file;
    reference->entries.insert(reference->entries.end(), table.entries.begin(), table.entries.end());
  }
  options.accept_inconsistent = so.accept_inconsistent;
  options.pool = so.pool;
  const std::vector<QualityCriterion> criteria =
      so.exclude_quality ? parse_quality_criteria(*so.exclude_quality) : std::vector<QualityCriterion>{};
  PhaseProgress progress(!so.no_progress);
  const auto load = [&](const std::vector<fs::path>& inputs) {
    try {
      // The last line of reading waits for the checks below: refused input stays one line.
      const auto reading = [&](int done, int total) {
        if (done < total) progress("reading logs", done, total);
      };
      return load_dataset(inputs, {.accept_inconsistent = so.accept_inconsistent, .pool = so.pool, .progress = reading});
    } catch (const InconsistentLog& e) {
      throw std::runtime_error(std::string(e.what()) +
                               "; the log is inconsistent (rows duplicated, removed, reordered or edited?): not fitted "
                               "(--accept-inconsistent fits it anyway, listed in report.json and summary.txt)");
    }
  };
  // Every session is read and checked, excluded or not; the fit reads those the criteria keep.
  Dataset data = load(so.inputs);
  const QualityCheck quality = check_quality(so, criteria);
  if (quality.excluded > 0) data = load(quality.fitted);
  if (is_frame_study(data)) return run_frame_study(so, options, data, progress, quality);
  // Before the fit: sessions of different kernels or observer kinds are refused at once.
  const CalibrationProvenance provenance = calibration_provenance(data, so.pool_observers);
  progress("reading logs", static_cast<int>(so.inputs.size()), static_cast<int>(so.inputs.size()));
  const auto start = std::chrono::steady_clock::now();
  const StudyFit fit = [&] {
    options.progress = [&progress](const std::string& phase, int done, int total) { progress(phase, done, total); };
    return fit_study(data, options);
  }();
  progress.end();
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const WorstCase chosen = entry_choice(fit, so.condition);  // an unknown --condition fails before anything is written

  std::vector<std::string> inputs;
  for (const fs::path& p : so.inputs) inputs.push_back(p.string());
  const std::string created = utc_now();
  const ReferenceTable* ref = reference ? &*reference : nullptr;
  const nlohmann::json calibration = calibration_json(fit, so.condition, created, inputs, provenance);
  nlohmann::json report = report_json(fit, ref, inputs, created, provenance);
  report["fit_seconds"] = seconds;
  report["threads"] = so.threads > 0 ? so.threads : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  if (!quality.report.is_null()) report["data_quality"] = quality.report;
  const std::string summary = summary_text(fit, ref, so.condition, provenance) + quality.table;
  // A fit nobody should use does not become a calibration the renderer reads without a word.
  if (const std::vector<std::string> why = unusable_because(chosen); !why.empty() && !so.allow_unusable) {
    std::cout << summary;
    std::string list;
    for (const std::string& w : why) list += (list.empty() ? "" : ", ") + w;
    throw std::runtime_error("the fit of " + chosen.condition + " is not usable as a calibration (" + list +
                             "); nothing written (the summary above says why; --allow-unusable writes it marked \"usable\": false)");
  }
  // The three files are one output: staged together and swapped in as a unit, so a failure (a full
  // disk) never leaves a new report beside an old calibration.
  io::StagedDirectory out(so.output.string(), "calibration.json");
  io::write_file_atomic(out.path() / "report.json", json_input::dump(report, 1) + "\n");
  io::write_file_atomic(out.path() / "summary.txt", summary);
  io::write_file_atomic(out.path() / "calibration.json", json_input::dump(calibration, 2) + "\n");
  out.commit();
  std::cout << summary;
  std::printf("calibration.json: entry %s %s (%s, %d participant%s)%s\n", provenance.technique.c_str(), provenance.kernel.c_str(),
              provenance.observers.c_str(), provenance.participants, provenance.participants == 1 ? "" : "s",
              unusable_because(chosen).empty() ? "" : ", marked NOT USABLE (--allow-unusable)");
  std::printf("fit took %.2f s; wrote %s/{calibration.json, report.json, summary.txt}\n", seconds,
              so.output.string().c_str());
  std::printf("plots: /usr/bin/python3 %s %s\n", tool::script_file("plot_fit.py").c_str(), fs::absolute(so.output).string().c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  // Ceres logs a rank-deficient covariance as an error; the fit reports it as a flag instead.
  FLAGS_minloglevel = google::GLOG_FATAL;
  CLI::App app{"penumbra-fit: thresholds and the constant c of r = c a from penumbra-study logs (docs/fit.md)"};
  cli::describe_tool(app, "penumbra-fit", "fit.md");
  StudyOptions so;
  ModelOptions study_model;
  app.add_option("inputs", so.inputs, "session directories (trials.csv + session.json) or trial CSV files");
  app.add_option("-o,--output", so.output, "output directory: calibration.json, report.json, summary.txt")
      ->check(cli::path_given());
  app.add_option("--reference", so.references,
                 "reference filter sizes from penumbra-study reference (repeatable; the first match wins)");
  app.add_option("--condition", so.condition, "calibration.json takes c from this condition (e.g. stair/1) instead of the largest");
  app.add_option("--bootstrap", so.bootstrap, "resamples of the bootstrap over participants (0: none)")
      ->capture_default_str()
      ->check(CLI::Range(0, 1000000));
  app.add_option("--seed", so.seed, "bootstrap seed")->capture_default_str()->check(cli::non_negative_integer());
  app.add_option("--observer-percentile", so.observer_percentile,
                 "the multilevel fit's observer: c for this percentile of the population of observers (90: nine in ten see "
                 "the staircase at a smaller radius), with its interval, beside the population's mean c and spread")
      ->capture_default_str()
      ->check(CLI::Range(0.1, 99.9));
  app.add_option("--threads", so.threads, "threads for the fits of every phase (0: all cores); the results do not depend on it")
      ->capture_default_str()
      ->check(CLI::Range(0, 4096));
  app.add_flag("--no-progress", so.no_progress,
               "no progress on stderr (otherwise one bar per phase: redrawn on a terminal, whole lines in a log)");
  app.add_flag("--accept-inconsistent", so.accept_inconsistent,
               "fit logs that fail the integrity check (trial numbers, design, QUEST replay) and list them in "
               "report.json and summary.txt; without it such a log is refused");
  app.add_flag("--pool", so.pool,
               "fit sessions whose setup differs (stimulus size, display geometry, transfer, task, QUEST parameters) "
               "together, listing the differences in report.json and summary.txt; without it such sessions are refused");
  app.add_flag("--pool-observers", so.pool_observers,
               "fit sessions answered by different kinds of observer (people, psychometric simulations, the image "
               "observer) together; the entry says obtained_by \"mixed\" and lists the kinds. Without it they are refused");
  app.add_flag("--allow-unusable", so.allow_unusable,
               "write calibration.json even when the chosen condition's fit is not usable (not converged, threshold at a bound, "
               "open or infinite interval, c outside [0.5, 20]), marked \"usable\": false; without it nothing is written");
  app.add_option("--exclude-quality", so.exclude_quality,
                 "leave out sessions whose data quality fails these criteria, e.g. "
                 "fullscreen_exits>2,tab_switches>3,page_loads>3,rt_outliers>10%,chinrest_cv>0.1 (docs/fit.md#data-quality); each "
                 "excluded session is printed with its reason and listed in report.json. Default: none excluded, the table reported");
  add_model_options(app, study_model);

  auto* psychometric = app.add_subcommand("psychometric", "fit one data set and print JSON");
  fs::path input;
  std::string format = "counts";
  ModelOptions single_model;
  psychometric->add_option("--input", input, "CSV: level,n_correct,n_total (counts) or level,correct (trials)")
      ->required()
      ->check(cli::path_given());
  psychometric->add_option("--format", format, "counts or trials")->capture_default_str();
  add_model_options(*psychometric, single_model);

  auto* plan = app.add_subcommand("plan", "simulate studies of a design and print the precision of c, the power to detect a "
                                          "planted difference and the coverage of the entry's interval");
  PlanOptions plan_options;
  plan->add_option("--participants", plan_options.participants, "participants per study")->capture_default_str()->check(CLI::Range(2, 1000));
  plan->add_option("--trials", plan_options.trials_per_staircase, "trials per staircase")->capture_default_str()->check(CLI::Range(5, 10000));
  plan->add_option("--conditions", plan_options.conditions, "conditions (pattern x contrast)")->capture_default_str()->check(CLI::Range(2, 12));
  plan->add_option("--c", plan_options.c, "planted c of the other conditions")->capture_default_str()->check(CLI::Range(0.5, 20.0));
  plan->add_option("--difference", plan_options.difference, "the worst condition lies this fraction above the others (0.1 = 10 %)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 2.0));
  plan->add_option("--sd", plan_options.sd_log10, "between-participant sd of log10 c")->capture_default_str()->check(CLI::Range(0.0, 0.5));
  plan->add_option("--alpha", plan_options.alpha, "level of the test whose power is printed")->capture_default_str()->check(CLI::Range(0.001, 0.5));
  plan->add_option("--studies", plan_options.studies, "simulated studies")->capture_default_str()->check(CLI::Range(1, 100000));
  plan->add_option("--seed", plan_options.seed, "seed")->capture_default_str();
  plan->add_option("--threads", plan_options.threads, "studies fitted side by side (0: all cores); the results do not depend on it")
      ->capture_default_str()
      ->check(CLI::Range(0, 4096));

  if (const auto status = cli::parse(app, argc, argv, "penumbra-fit")) return *status;
  try {
    if (psychometric->parsed()) return run_psychometric(input, format, single_model);
    if (plan->parsed()) {
      const PlanResult r = plan_study(plan_options);
      const PlanOptions& o = r.options;
      std::printf("plan: %d participants x %d conditions x %zu sizes x %d trials per staircase; worst condition %.0f %% above c = %g, "
                  "participant sd %.3f log10; %d simulated studies\n",
                  o.participants, o.conditions, o.artifact_px.size(), o.trials_per_staircase, 100 * o.difference, o.c, o.sd_log10,
                  o.studies);
      std::printf("precision of the entry's c: median ci95 half-width +-%.1f %%; bias %+.2f %%\n", r.median_half_width_percent,
                  r.bias_percent);
      std::printf("power to detect the difference (conditions differ, LR test at %g): %.2f +- %.2f (Monte Carlo se)\n", o.alpha, r.power,
                  r.power_se);
      std::printf("coverage of the worst condition's c %.3f: entry ci95 %.2f, population interval %.2f\n", r.worst_c, r.coverage,
                  r.coverage_population);
      return 0;
    }
    return run_study(so, study_model);
  } catch (const std::exception& e) {
    return cli::fail("penumbra-fit", e);
  }
}
