// penumbra-observer-fit: the image observer's decision parameter fitted to human thresholds, each
// held out in turn (docs/study.md, "The observer against people"). It renders the observer's
// noise-free deviations once (stair and step at each --contrast, on K radius grids offset from
// each other by a fraction of the grid step, each grid with its own stimuli), then for every
// --human CONDITION=C finds the `weber` (decision noise) at which that condition's c is C, and
// prints every other condition's c at that weber: the held-out prediction, its error against the
// human number, the step > stair ordering and the contrast effect.
// The deviations do not depend on weber, so the fits are arithmetic on one set of renders
// (observers/observer_curve.h). Intervals are over the K grids (each one radius grid offset and
// its own stimuli, the whole fit redone on each): one grid's bootstrap over its stimuli misses
// where its radii fall on a curve that is not monotone, which moves c more than the stimuli do.
//   penumbra-observer-fit --human step/1=3.47 --human stair/1=2.5 --grids 8 --seeds 2 --json fit.json
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli/list_option.h"
#include "cli/main.h"
#include "fit/multilevel_fit.h"
#include "gl/context.h"
#include "io/atomic_file.h"
#include "io/safe_path.h"
#include "json/json_input.h"
#include "observers/image_observer.h"
#include "observers/observer_curve.h"
#include "sampling/random.h"
#include "stimuli/stimulus.h"
#include "tool/tool.h"

using namespace penumbra;

namespace {

constexpr const char* kTool = "penumbra-observer-fit";

struct Human {
  std::string condition;  // "stair/1"
  double c = NAN;
};

// "stair/1=2.5": a rendered pattern, a lit level by the lists' number grammar, a c > 0.
std::optional<Human> read_human(const std::string& text) {
  const std::size_t eq = text.find('='), slash = text.find('/');
  if (eq == std::string::npos || slash == std::string::npos || slash > eq) return std::nullopt;
  const std::string pattern = text.substr(0, slash);
  const std::optional<double> contrast = cli::decimal(text.substr(slash + 1, eq - slash - 1));
  const std::optional<double> c = cli::decimal(text.substr(eq + 1));
  if ((pattern != "stair" && pattern != "step") || !contrast || !(*contrast > 0 && *contrast <= 1) || !c || !(*c > 0)) return std::nullopt;
  char contrast_text[32];
  std::snprintf(contrast_text, sizeof contrast_text, "%g", *contrast);
  return Human{pattern + "/" + contrast_text, *c};
}

// The mean and a t interval of log values over the grids (each grid one independent replicate of
// the whole measurement), back in linear units; [v, v] with one grid.
struct Summary {
  double value = NAN, low = NAN, high = NAN, min = NAN, max = NAN;
};
Summary summarize(const std::vector<double>& values) {
  Summary s;
  double sum = 0;
  for (const double v : values) sum += std::log(v);
  const double n = static_cast<double>(values.size()), mean = sum / n;
  double ss = 0;
  for (const double v : values) ss += (std::log(v) - mean) * (std::log(v) - mean);
  const double half = values.size() > 1 ? analysis::student_t_quantile(0.975, n - 1) * std::sqrt(ss / (n - 1) / n) : 0.0;
  s.value = std::exp(mean);
  s.low = std::exp(mean - half);
  s.high = std::exp(mean + half);
  s.min = *std::min_element(values.begin(), values.end());
  s.max = *std::max_element(values.begin(), values.end());
  return s;
}
nlohmann::json to_json(const Summary& s, const std::vector<double>& per_grid) {
  return {{"c", s.value}, {"ci95", {s.low, s.high}}, {"range", {s.min, s.max}}, {"per_grid", per_grid}};
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"The image observer's decision noise fitted to human thresholds, each held out in turn (docs/study.md)"};
  cli::describe_tool(app, kTool, "study.md");
  std::vector<std::string> human_text{"step/1=3.47", "stair/1=2.5"};
  std::vector<double> artifacts{10}, contrasts{1.0, 0.5};
  double ratio_min = 1.0, ratio_max = 8, step = 1.08, p_threshold = 0.82, shipped_weber = 0.003;
  int grids = 8, seeds = 2, size_px = 320;
  std::string technique, json_out;
  std::vector<std::string> settings;
  observers::ImageObserverParams params;
  params.blur_sigma_arcmin = 1.0;
  params.pixels_per_degree = 38.2;  // data/studies/default.json's display, as penumbra-observer-curve
  cli::add_list_option(app, "--human", human_text,
                       "human thresholds CONDITION=C (stair/1=2.5, step/1=3.47), at least two: each is fitted in turn and the "
                       "others predicted",
                       cli::ListItem<std::string>{"CONDITION=C with CONDITION stair/L or step/L (L a lit level in (0, 1]) and C > 0",
                                                  [](const std::string& s) -> std::optional<std::string> {
                                                    if (!read_human(s)) return std::nullopt;
                                                    return s;
                                                  }});
  cli::add_list_option(app, "--artifact-px", artifacts, "artifact sizes (a condition's c is their geometric mean)", cli::numbers_in(1, 1000));
  cli::add_list_option(app, "--contrast", contrasts, "lit levels, linear light (stair and step are drawn at each)",
                       cli::numbers_in(0, 1, cli::Bound::open));
  app.add_option("--technique", technique, "the renderer's technique that draws the stimuli (default pcf with pcf.kernel=disk)");
  app.add_option("--set", settings, "a technique setting KEY=VALUE by penumbra-render's keys; repeatable");
  app.add_option("--ratio-min", ratio_min, "smallest r / a of the first grid")->capture_default_str()->check(CLI::Range(0.05, 100.0));
  app.add_option("--ratio-max", ratio_max, "largest r / a (clamped radii are skipped)")->capture_default_str()->check(CLI::Range(0.05, 100.0));
  app.add_option("--ratio-step", step, "grid factor between radii")->capture_default_str()->check(CLI::Range(1.001, 4.0));
  app.add_option("--grids", grids, "radius grids, grid k starting at ratio-min * ratio-step^(k / grids), each with its own stimuli")
      ->capture_default_str()
      ->check(CLI::Range(1, 64));
  app.add_option("--seeds", seeds, "stimuli (phase, orientation) per radius of each grid")->capture_default_str()->check(CLI::Range(1, 100));
  app.add_option("--size-px", size_px, "stimulus side")->capture_default_str()->check(CLI::Range(32, 2048));
  app.add_option("--p-threshold", p_threshold, "threshold criterion, 2afc P(correct)")->capture_default_str()->check(CLI::Range(0.51, 0.999));
  app.add_option("--blur-arcmin", params.blur_sigma_arcmin, "optical blur sigma")->capture_default_str();
  app.add_option("--ppd", params.pixels_per_degree, "display pixels per degree")->capture_default_str();
  app.add_option("--window", params.window_r, "local window, filter radii")->capture_default_str()->check(CLI::Range(0.01, 100.0));
  app.add_option("--weber", shipped_weber, "the decision noise the observer ships with, whose c per condition is printed first")
      ->capture_default_str()
      ->check(CLI::Range(1e-6, 1.0));
  app.add_option("--json", json_out, "write the fits, predictions and per-grid values");
  if (const auto status = cli::parse(app, argc, argv, kTool)) return *status;
  try {
    std::vector<Human> humans;
    for (const std::string& text : human_text) {
      const Human h = *read_human(text);
      for (const Human& other : humans)
        if (other.condition == h.condition) throw cli::UsageError("--human: " + h.condition + " is given twice");
      humans.push_back(h);
    }
    if (humans.size() < 2) throw cli::UsageError("--human: needs at least two conditions (one fitted, the others held out)");
    if (!(ratio_min < ratio_max)) throw cli::UsageError("--ratio-min: must be below --ratio-max");
    if (!json_out.empty()) io::check_output(json_out, io::OutputKind::file);

    stimuli::StimulusSpec base;
    base.size_px = size_px;
    base.technique = technique;
    stimuli::set_technique_settings(base, settings);
    base = stimuli::as_renderer_pcf(base);
    const auto checked = stimuli::stimulus_settings(base, 15);
    if (const std::string why = stimuli::partner_unavailable(checked); !why.empty()) throw std::invalid_argument(why);
    const std::string kernel = shadows::variant_choice(checked);

    // The conditions: stair and step at every lit level, named as penumbra-fit names them.
    struct Condition {
      std::string name;
      stimuli::Pattern pattern;
      double contrast;
    };
    std::vector<Condition> conditions;
    for (const char* pattern : {"stair", "step"})
      for (const double contrast : contrasts) {
        char text[32];
        std::snprintf(text, sizeof text, "%g", contrast);
        conditions.push_back({std::string(pattern) + "/" + text, stimuli::parse_pattern(pattern), contrast});
      }
    std::map<std::string, std::size_t> index;
    for (std::size_t i = 0; i < conditions.size(); ++i) index[conditions[i].name] = i;
    for (const Human& h : humans)
      if (!index.count(h.condition))
        throw cli::UsageError("--human: " + h.condition + " is not drawn (--contrast names the lit levels drawn)");

    // Render: condition -> grid -> artifact size -> radius. Grid 0 is penumbra-observer-curve's
    // grid and stimuli (seeds 0 .. S-1); grid k starts ratio-step^(k / K) higher, seeds kS .. kS+S-1.
    gl::HeadlessContext context;
    stimuli::StimulusRenderer renderer;
    observers::ImageObserver eye(params, 1);
    std::vector<std::vector<observers::ConditionCurves>> curves(conditions.size(),
                                                                std::vector<observers::ConditionCurves>(static_cast<std::size_t>(grids)));
    std::printf("%s: technique %s%s, window %g r, blur %g arcmin at %g px/deg; %d radius grids (r/a %g to %g in steps of %g, "
                "grid k starting %g^(k/%d) higher), %d stimuli each\n",
                kTool, base.technique.c_str(), kernel.empty() ? "" : (" " + kernel).c_str(), params.window_r, params.blur_sigma_arcmin,
                params.pixels_per_degree, grids, ratio_min, ratio_max, step, step, grids, seeds);
    std::size_t renders = 0;
    for (std::size_t i = 0; i < conditions.size(); ++i) {
      for (int k = 0; k < grids; ++k) {
        for (const double a : artifacts) {
          std::vector<observers::CurvePoint> points;
          for (double ratio = ratio_min * std::pow(step, static_cast<double>(k) / grids); ratio <= ratio_max * 1.0001; ratio *= step) {
            if (stimuli::clamp_filter_radius(ratio * a, size_px).clamped) break;
            stimuli::StimulusSpec spec = base;
            spec.pattern = conditions[i].pattern;
            spec.artifact_px = a;
            spec.lit_linear = conditions[i].contrast;
            spec.filter_radius_px = ratio * a;
            observers::CurvePoint point;
            point.ratio = ratio;
            for (int s = 0; s < seeds; ++s) {
              spec.seed = sampling::derive_seed(11, static_cast<std::uint64_t>(k * seeds + s));
              const stimuli::StimulusPair pair = renderer.render(spec);
              point.jagged.push_back(eye.local_deviation(pair.artifact, spec, pair.geometry, false));
              point.straight.push_back(eye.local_deviation(pair.line, spec, pair.geometry, false));
              ++renders;
            }
            points.push_back(std::move(point));
          }
          if (points.empty()) throw cli::UsageError("--ratio-min: a = " + std::to_string(a) + " px is clamped at the first radius");
          curves[i][static_cast<std::size_t>(k)].push_back(std::move(points));
        }
      }
      std::fprintf(stderr, "%s: %s rendered (%zu renders so far)\n", kTool, conditions[i].name.c_str(), renders);
    }

    auto per_grid_c = [&](std::size_t i, double weber) {
      std::vector<double> out;
      for (const auto& grid : curves[i]) out.push_back(observers::replicate_c(grid, weber, p_threshold));
      return out;
    };
    auto finite = [](const std::vector<double>& v) {
      return std::all_of(v.begin(), v.end(), [](double x) { return std::isfinite(x); });
    };
    const double t_dof = grids - 1;
    nlohmann::json out = {{"tool", tool::version_line(kTool)},
                          {"settings",
                           {{"technique", base.technique}, {"kernel", kernel}, {"artifact_px", artifacts}, {"contrasts", contrasts},
                            {"ratio_min", ratio_min}, {"ratio_max", ratio_max}, {"ratio_step", step}, {"grids", grids}, {"seeds", seeds},
                            {"size_px", size_px}, {"p_threshold", p_threshold}, {"window_r", params.window_r},
                            {"blur_sigma_arcmin", params.blur_sigma_arcmin}, {"pixels_per_degree", params.pixels_per_degree}}},
                          {"interval", "95 % t interval (" + std::to_string(grids - 1) +
                                           " dof) of the mean log over the grids, each grid one radius offset with its own stimuli"}};

    // The shipped weber first: each condition's c with the interval over grids.
    std::printf("\nat weber %g (the shipped value): c per condition, mean over the %d grids [95 %% t, %g dof] (one grid: min to max)\n",
                shipped_weber, grids, t_dof);
    nlohmann::json shipped = nlohmann::json::object();
    for (std::size_t i = 0; i < conditions.size(); ++i) {
      const std::vector<double> c = per_grid_c(i, shipped_weber);
      if (!finite(c)) {
        std::printf("  %-10s above the criterion at r/a %g on some grid: raise --ratio-max\n", conditions[i].name.c_str(), ratio_max);
        continue;
      }
      const Summary s = summarize(c);
      std::printf("  %-10s %.3f [%.3f, %.3f]  (%.3f to %.3f)\n", conditions[i].name.c_str(), s.value, s.low, s.high, s.min, s.max);
      shipped[conditions[i].name] = to_json(s, c);
    }
    out["shipped"] = {{"weber", shipped_weber}, {"conditions", shipped}};

    // Each human number fitted in turn; every other condition predicted.
    nlohmann::json fits = nlohmann::json::array();
    for (const Human& target : humans) {
      const std::size_t t = index.at(target.condition);
      const observers::WeberFit pooled = observers::fit_weber(curves[t], target.c, p_threshold);
      std::vector<double> weber_k;  // the whole fit on each grid alone: the interval
      for (int k = 0; k < grids; ++k) {
        try {
          weber_k.push_back(observers::fit_weber({curves[t][static_cast<std::size_t>(k)]}, target.c, p_threshold).weber);
        } catch (const std::invalid_argument& e) {
          throw std::runtime_error("grid " + std::to_string(k) + ": " + target.condition + ": " + e.what());
        }
      }
      const Summary w = summarize(weber_k);
      const std::vector<double> fitted_c = per_grid_c(t, pooled.weber);
      std::printf("\nfitted to %s = %g: weber %.5f [%.5f, %.5f] (each grid fitted alone: %.5f to %.5f); %s's c at it %.3f (%+.2f %%)\n",
                  target.condition.c_str(), target.c, pooled.weber, w.low, w.high, w.min, w.max, target.condition.c_str(), pooled.c,
                  100 * (pooled.c / target.c - 1));
      nlohmann::json fit = {{"condition", target.condition},
                            {"human_c", target.c},
                            {"weber", pooled.weber},
                            {"weber_ci95", {w.low, w.high}},
                            {"weber_per_grid", weber_k},
                            {"c", pooled.c},
                            {"c_per_grid", fitted_c}};
      nlohmann::json predictions = nlohmann::json::array();
      std::map<std::string, std::vector<double>> at_fit;  // condition -> c per grid at that grid's own fit
      for (std::size_t i = 0; i < conditions.size(); ++i) {
        if (i == t) continue;
        std::vector<double> own;  // each grid's prediction at its own weber: the interval
        for (int k = 0; k < grids; ++k)
          own.push_back(observers::replicate_c(curves[i][static_cast<std::size_t>(k)], weber_k[static_cast<std::size_t>(k)], p_threshold));
        const std::vector<double> at_pooled = per_grid_c(i, pooled.weber);
        if (!finite(own) || !finite(at_pooled)) {
          std::printf("  %-10s above the criterion at r/a %g on some grid: raise --ratio-max\n", conditions[i].name.c_str(), ratio_max);
          predictions.push_back({{"condition", conditions[i].name}, {"c", nullptr}});
          continue;
        }
        at_fit[conditions[i].name] = own;
        // The prediction is the mean over the grids of each grid's own (fit and prediction on the
        // same grid and stimuli), so the interval is about the number printed; at the weber fitted
        // to all grids at once it is close (c_at_fitted_weber).
        const Summary p = summarize(own);
        const double c = p.value;
        nlohmann::json prediction = {{"condition", conditions[i].name}, {"c", c}, {"ci95", {p.low, p.high}}, {"per_grid", own},
                                     {"c_at_fitted_weber", summarize(at_pooled).value}};
        std::printf("  %-10s predicted %.3f [%.3f, %.3f]", conditions[i].name.c_str(), c, p.low, p.high);
        for (const Human& h : humans)
          if (h.condition == conditions[i].name) {
            const double error = c / h.c - 1;
            prediction["human_c"] = h.c;
            prediction["error"] = error;
            prediction["error_ci95"] = {p.low / h.c - 1, p.high / h.c - 1};
            std::printf(", human %g: %+.1f %% [%+.1f, %+.1f] (held out)", h.c, 100 * error, 100 * (p.low / h.c - 1), 100 * (p.high / h.c - 1));
          }
        std::printf("\n");
        predictions.push_back(prediction);
      }
      at_fit[target.condition] = fitted_c;
      fit["predictions"] = predictions;
      // The checks people pass: the step needs the larger filter; the half lit level makes the
      // stair slightly harder to see (a smaller c).
      nlohmann::json checks = nlohmann::json::array();
      for (const double contrast : contrasts) {
        char text[32];
        std::snprintf(text, sizeof text, "%g", contrast);
        const std::string stair = std::string("stair/") + text, step_name = std::string("step/") + text;
        if (!at_fit.count(stair) || !at_fit.count(step_name)) continue;
        int above = 0;
        std::vector<double> ratios;
        for (int k = 0; k < grids; ++k) {
          const double r = at_fit[step_name][static_cast<std::size_t>(k)] / at_fit[stair][static_cast<std::size_t>(k)];
          above += r > 1;
          ratios.push_back(r);
        }
        const Summary s = summarize(ratios);
        std::printf("  step > stair at %s: %d of %d grids, c(%s) / c(%s) %.3f [%.3f, %.3f] (people: step > stair)\n", text, above, grids,
                    step_name.c_str(), stair.c_str(), s.value, s.low, s.high);
        checks.push_back({{"check", "step above stair"}, {"contrast", contrast}, {"grids_passing", above}, {"grids", grids},
                          {"ratio", s.value}, {"ratio_ci95", {s.low, s.high}}});
      }
      if (contrasts.size() >= 2) {
        char low[32], high[32];
        std::snprintf(low, sizeof low, "%g", *std::min_element(contrasts.begin(), contrasts.end()));
        std::snprintf(high, sizeof high, "%g", *std::max_element(contrasts.begin(), contrasts.end()));
        for (const char* pattern : {"stair", "step"}) {
          const std::string lo_name = std::string(pattern) + "/" + low, hi_name = std::string(pattern) + "/" + high;
          if (!at_fit.count(lo_name) || !at_fit.count(hi_name)) continue;
          int below = 0;
          std::vector<double> ratios;
          for (int k = 0; k < grids; ++k) {
            const double r = at_fit[lo_name][static_cast<std::size_t>(k)] / at_fit[hi_name][static_cast<std::size_t>(k)];
            below += r < 1;
            ratios.push_back(r);
          }
          const Summary s = summarize(ratios);
          std::printf("  contrast: c(%s) / c(%s) %.3f [%.3f, %.3f], below 1 on %d of %d grids%s\n", lo_name.c_str(), hi_name.c_str(), s.value,
                      s.low, s.high, below, grids,
                      std::string(pattern) == "stair" ? " (people: below 1, the half lit level slightly harder to see)" : "");
          checks.push_back({{"check", "contrast"}, {"pattern", pattern}, {"grids_below_1", below}, {"grids", grids}, {"ratio", s.value},
                            {"ratio_ci95", {s.low, s.high}}});
        }
      }
      fit["checks"] = checks;
      fits.push_back(fit);
    }
    out["fits"] = fits;
    out["renders"] = renders;
    if (!json_out.empty()) {
      io::write_file_atomic(json_out, json_input::dump(out, 2) + "\n");
      std::printf("\nwrote %s\n", json_out.c_str());
    }
  } catch (const std::exception& e) {
    return cli::fail(kTool, e);
  }
  return 0;
}
