// penumbra-observer-curve: the image observer's psychometric curve for one pattern, without a
// staircase. For each r / a on a log grid it renders the stimulus pair (several seeds: phase and
// orientation), takes the observer's noise-free local deviations of the jagged and the straight
// image, and turns their difference into P(correct) = Phi(diff / (sqrt 2 weber)) (2afc: both
// decisions carry independent N(0, weber) noise). The implied c is the r / a beyond which P stays
// below p_threshold (interpolated in log r / a at the last crossing): the radius from which on the
// artifact is detected at no more than the criterion.
// --observer frame asks the frame observer (renderer/metrics/frame_observer.h) instead: the straight
// image is its reference, the jagged one the frame, and the deviation is the largest patch's (the
// reference's own is 0); --weber and --window are then the frame observer's (the window in degrees).
// It is how that observer was calibrated on the step and validated on the rest (docs/compare.md).
// With --technique the renderer's technique draws the stimuli (docs/study.md); --json writes the
// implied c per condition as a calibration.json image-observer entry (data/calibration/predicted.json),
// with a percentile bootstrap interval over the stimuli (seeds) rendered per radius.
//   penumbra-observer-curve --pattern stair,step --contrast 1,0.5 --artifact-px 5,10,20
//       --technique pcf --set pcf.kernel=grid --json pcf-grid.json
// The renders are independent: --shard I/N --part FILE renders every N-th of them (shard/shard.h)
// on any machine, and `penumbra-observer-curve merge PARTS... -o OUT` turns the N parts into
// exactly what the unsharded run writes to --json OUT (docs/cluster.md).
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli/list_option.h"
#include "cli/main.h"
#include "shard/shard.h"
#include "tool/tool.h"
#include "io/atomic_file.h"
#include "io/safe_path.h"
#include "json/json_input.h"
#include "metrics/frame_observer.h"
#include "gl/context.h"
#include "observers/image_observer.h"
#include "observers/observer_curve.h"
#include "psychometric/psychometric.h"
#include "stats/summary.h"
#include "sampling/random.h"
#include "stimuli/stimulus.h"

using namespace penumbra;

namespace {

using observers::CurvePoint;
using observers::condition_c;
using observers::condition_slope;
using observers::implied_c;

// 2afc P(correct) at one radius over the stimuli `pick` (observers/observer_curve.h).
double p_correct(const CurvePoint& point, const std::vector<int>& pick, double weber) {
  return observers::curve_p_correct(point, pick, weber);
}

constexpr int kResamples = 400;  // bootstrap over the stimuli per radius

// Every technique of the registry that the study can draw (its settings are accepted and it has an
// artifact-free partner), one per choice of its variant setting: "pcf:pcf.kernel=grid", "vsm".
std::vector<std::string> drawable_techniques() {
  std::vector<std::string> out;
  for (const std::string_view name : shadows::technique_names()) {
    const shadows::Technique t = shadows::technique_from_string(name);
    std::vector<std::string> settings;  // one "section.key=choice" per variant, or none
    for (const std::string& choice : shadows::variant_choices(t))
      settings.push_back(std::string(name) + "." + std::string(shadows::technique_entry(t).variant_setting) + "=" + choice);
    if (settings.empty()) settings.emplace_back();
    for (const std::string& setting : settings) {
      stimuli::StimulusSpec spec;
      spec.technique = name;
      try {
        stimuli::set_technique_settings(spec, setting.empty() ? std::vector<std::string>{} : std::vector{setting});
        if (!stimuli::partner_unavailable(stimuli::stimulus_settings(spec, 15)).empty()) continue;
      } catch (const std::invalid_argument&) {
        continue;  // a technique the study cannot draw (hard, the screen-space ones)
      }
      out.push_back(setting.empty() ? std::string(name) : std::string(name) + ":" + setting);
    }
  }
  return out;
}


// The options that say where the output goes and which shard runs, not what is computed: left out
// of a part's settings and of the recorded command, which ends with the --json the merge writes.
std::vector<std::string> settings_args(const std::vector<std::string>& args) {
  return shard::without_options(args, {"--shard", "--part", "--json"});
}

constexpr std::string_view kPartKind = "penumbra-observer-curve part";

// The renders of a merge: every grid item's deviations from the parts (item number -> value).
struct Merged {
  std::vector<shard::Part> parts;
};

int run(const std::vector<std::string>& args, const Merged* merged);

// penumbra-observer-curve merge PARTS... -o OUT: the parts' deviations, checked, through the same
// curves, bootstrap and output as the unsharded run (run() with the parts' own arguments).
int merge_main(int argc, char** argv) {
  CLI::App app{"Merge the part files of penumbra-observer-curve --shard I/N --part FILE into the calibration.json the "
               "unsharded run writes (docs/cluster.md)",
               "penumbra-observer-curve merge"};
  cli::describe_tool(app, "penumbra-observer-curve merge", "cluster.md");
  std::vector<std::string> paths;
  std::string out;
  app.add_option("parts", paths, "the part files, one per shard 0/N to N-1/N, any order")->required();
  app.add_option("-o,--output", out, "the calibration.json to write (as --json of the unsharded run)")->required();
  if (const auto status = cli::parse(app, argc - 1, argv + 1, "penumbra-observer-curve merge")) return *status;
  Merged merged;
  std::vector<std::string> args;
  try {
    io::check_output(out, io::OutputKind::file);
    shard::Checked checked = shard::read_parts({paths.begin(), paths.end()}, kPartKind, tool::version_line("penumbra-observer-curve"));
    args = shard::stored_args(checked.settings, paths.front());
    merged.parts = std::move(checked.parts);
  } catch (const std::exception& e) {
    return cli::fail("penumbra-observer-curve merge", e);
  }
  args.push_back("--json");
  args.push_back(out);
  return run(args, &merged);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc >= 2 && std::string_view(argv[1]) == "merge") return merge_main(argc, argv);
  return run(std::vector<std::string>(argv + 1, argv + argc), nullptr);
}

namespace {

int run(const std::vector<std::string>& args, const Merged* merged) {
  shard::Argv argv("penumbra-observer-curve", args);
  CLI::App app{"The image observer's 2afc psychometric curve and implied c (docs/study.md)"};
  cli::describe_tool(app, "penumbra-observer-curve", "study.md");
  std::vector<std::string> patterns{"stair"};
  std::vector<double> artifacts{5, 10, 20}, contrasts{1.0};
  double ratio_min = 0.5, ratio_max = 8, step = 1.06, p_threshold = 0.82;
  int seeds = 3, size_px = 320;
  std::string technique;
  std::vector<std::string> settings;
  std::string json_out;
  observers::ImageObserverParams params;
  std::string observer_kind = "image";
  params.blur_sigma_arcmin = 1.0;
  params.pixels_per_degree = 38.2;  // data/studies/default.json's display: 1.57 arcmin per pixel
  cli::add_list_option(app, "--pattern", patterns, "stair and/or step", cli::one_of({"stair", "step"}));
  cli::add_list_option(app, "--artifact-px", artifacts, "artifact sizes", cli::numbers_in(1, 1000));
  cli::add_list_option(app, "--contrast", contrasts, "lit levels, linear light", cli::numbers_in(0, 1, cli::Bound::open));
  app.add_option("--technique", technique, "the renderer's technique that draws the stimuli (pcf, rpcf, vsm, ...; default pcf with pcf.kernel=disk)");
  app.add_option("--set", settings, "a technique setting KEY=VALUE by penumbra-render's keys (pcf.kernel=grid); repeatable");
  app.add_option("--json", json_out, "write the implied c per condition as a calibration.json (schema 2) image-observer entry");
  app.add_option("--observer", observer_kind,
                 "image: the study's image observer (traces the edge); frame: the frame observer on the jagged image against "
                 "the straight one as its reference (renderer/metrics/frame_observer.h)")
      ->capture_default_str()
      ->check(CLI::IsMember({"image", "frame"}));
  app.add_option("--ratio-min", ratio_min, "smallest r / a")->capture_default_str()->check(CLI::Range(0.05, 100.0));
  app.add_option("--ratio-max", ratio_max, "largest r / a (clamped radii are skipped)")->capture_default_str()->check(CLI::Range(0.05, 100.0));
  app.add_option("--ratio-step", step, "grid factor between radii")->capture_default_str()->check(CLI::Range(1.001, 4.0));
  app.add_option("--seeds", seeds, "stimuli (phase, orientation) averaged per radius")->capture_default_str()->check(CLI::Range(1, 1000));
  app.add_option("--size-px", size_px, "stimulus side")->capture_default_str();
  app.add_option("--p-threshold", p_threshold, "threshold criterion")->capture_default_str()->check(CLI::Range(0.51, 0.999));
  app.add_option("--blur-arcmin", params.blur_sigma_arcmin, "optical blur sigma")->capture_default_str();
  app.add_option("--ppd", params.pixels_per_degree, "display pixels per degree")->capture_default_str();
  app.add_option("--window", params.window_r, "local window, filter radii (--observer frame: the smallest window, degrees, default 0.25)")->capture_default_str();
  metrics::FrameObserverParams frame_params;
  app.add_option("--window-max", frame_params.window_max_deg, "--observer frame: the largest window, degrees (octaves from --window)")
      ->capture_default_str();
  app.add_option("--pool-arcmin", frame_params.pool_arcmin, "--observer frame: sigma of the pooling of the signed change, arcmin")
      ->capture_default_str();
  app.add_option("--contrast-floor", frame_params.contrast_floor, "--observer frame: the local contrast's floor, a fraction of the local mean")
      ->capture_default_str();
  app.add_option("--contrast-deg", frame_params.contrast_deg, "--observer frame: side of the local contrast's square, degrees")
      ->capture_default_str();
  app.add_option("--weber", params.weber, "decision noise sd (relative deviation; --observer frame: its own, default 0.0304)")
      ->capture_default_str();
  std::string shard_text, part_out;
  app.add_option("--shard", shard_text,
                 "I/N: render only shard I of N (0 <= I < N) of the grid of conditions x sizes x radii x seeds (every item "
                 "whose number in that order is I modulo N) into --part; `penumbra-observer-curve merge` joins the N parts "
                 "into what the unsharded run writes (docs/cluster.md)");
  app.add_option("--part", part_out, "--shard: the part file to write (the shard's deviations, its settings and the build's version)");
  bool list_techniques = false;
  app.add_flag("--list-techniques", list_techniques,
               "print the techniques the study can draw, one a line as --technique and --set take them (TECHNIQUE or "
               "TECHNIQUE:SECTION.KEY=CHOICE, one per choice of a variant setting such as pcf's kernel), from the renderer's "
               "registry, and exit");
  if (const auto status = cli::parse(app, argv.argc(), argv.argv(), "penumbra-observer-curve")) return *status;
  if (list_techniques) {
    for (const std::string& spec : drawable_techniques()) std::printf("%s\n", spec.c_str());
    return 0;
  }
  try {
    std::optional<shard::Shard> sharded;
    if (!shard_text.empty()) {
      sharded = shard::parse(shard_text);
      if (part_out.empty()) throw cli::UsageError("--shard: needs --part FILE, where the shard's part goes");
      if (!json_out.empty())
        throw cli::UsageError("--json: a shard writes a part (--part); `penumbra-observer-curve merge PARTS... -o OUT` writes the calibration.json");
      io::check_output(part_out, io::OutputKind::file);
    } else if (!part_out.empty()) {
      throw cli::UsageError("--part: only with --shard I/N");
    }
    if (!json_out.empty()) io::check_output(json_out, io::OutputKind::file);  // before the curves: every output's rule
    stimuli::StimulusSpec base;
    base.size_px = size_px;
    base.technique = technique;
    stimuli::set_technique_settings(base, settings);
    base = stimuli::as_renderer_pcf(base);  // no --technique: the exact disk
    const auto checked = stimuli::stimulus_settings(base, 15);  // the settings' errors before any rendering
    if (const std::string why = stimuli::partner_unavailable(checked); !why.empty()) throw std::invalid_argument(why);
    const std::string kernel = shadows::variant_choice(checked);
    std::vector<stimuli::Pattern> parsed_patterns;
    for (const std::string& p : patterns) parsed_patterns.push_back(stimuli::parse_pattern(p));

    const bool frame = observer_kind == "frame";
    frame_params.pixels_per_degree = params.pixels_per_degree;
    frame_params.blur_sigma_arcmin = params.blur_sigma_arcmin;
    if (app.count("--window")) frame_params.window_deg = params.window_r;
    if (app.count("--weber")) frame_params.weber = params.weber;
    if (frame) {  // the rest of the curve reads these two: the frame observer's
      params.window_r = frame_params.window_deg;
      params.weber = frame_params.weber;
    }
    // The shown 8-bit values decoded through the display's transfer: the frame observer sees
    // exactly the luminance the image observer sees.
    auto displayed = [](const io::Image8& img, const stimuli::Transfer& transfer) {
      image::ImageF out{img.width, img.height, 1, std::vector<float>(img.pixels.size())};
      for (std::size_t i = 0; i < img.pixels.size(); ++i) out.pixels[i] = static_cast<float>(stimuli::decode(img.pixels[i], transfer));
      return out;
    };

    // The grid: condition (pattern x contrast) x artifact size x radius x seed, its items numbered
    // in this loop order; a shard renders the items whose number is its index modulo N. The radii
    // stop where the filter would be clamped, which depends on the size alone.
    std::vector<std::vector<double>> ratios(artifacts.size());
    for (std::size_t j = 0; j < artifacts.size(); ++j)
      for (double ratio = ratio_min; ratio <= ratio_max * 1.0001; ratio *= step) {
        if (stimuli::clamp_filter_radius(ratio * artifacts[j], size_px).clamped) break;
        ratios[j].push_back(ratio);
      }
    std::size_t items = 0;
    for (const auto& r : ratios) items += r.size() * static_cast<std::size_t>(seeds);
    items *= parsed_patterns.size() * contrasts.size();
    std::vector<double> jagged_at(items, NAN), straight_at(items, NAN);  // item -> deviation
    if (merged) {  // every item from the one part that covers it, in the shard's own order
      for (const shard::Part& part : merged->parts) {
        const std::string file = part.path.string();
        const nlohmann::json& points = part.payload.contains("points") ? part.payload["points"] : nlohmann::json();
        if (part.payload.value("items", nlohmann::json()) != nlohmann::json(items) || !points.is_array())
          throw std::runtime_error(file + ": payload: not a part of this grid of " + std::to_string(items) + " renders");
        std::size_t item = part.shard.index;
        for (std::size_t k = 0; k < points.size(); ++k, item += part.shard.count) {
          const nlohmann::json& point = points[k];
          const auto value = [&](std::size_t f) { return point[f].is_null() ? NAN : point[f].get<double>(); };
          if (item >= items || !point.is_array() || point.size() != 3 || point[0] != nlohmann::json(item) ||
              !(point[1].is_number() || point[1].is_null()) || !(point[2].is_number() || point[2].is_null()))
            throw std::runtime_error(file + ": payload.points[" + std::to_string(k) + "]: not [" + std::to_string(item) +
                                     ", jagged, straight] of shard " + part.shard.text() + " of " + std::to_string(items) + " renders");
          jagged_at[item] = value(1);
          straight_at[item] = value(2);
        }
        if (item < items)
          throw std::runtime_error(file + ": payload.points: " + std::to_string(points.size()) + " renders, shard " + part.shard.text() +
                                   " of " + std::to_string(items) + " has more");
      }
    }
    std::optional<gl::HeadlessContext> context;  // a merge renders nothing
    std::optional<stimuli::StimulusRenderer> renderer;
    if (!merged) {
      context.emplace();
      renderer.emplace();
    }
    observers::ImageObserver eye(params, 1);
    std::printf("%s%s, %s observer, window %g %s, weber %g, blur %g arcmin at %g px/deg, %d seeds%s\n",
                ("technique " + base.technique).c_str(), kernel.empty() ? "" : (" " + kernel).c_str(), observer_kind.c_str(), params.window_r,
                frame ? "deg" : "r", params.weber, params.blur_sigma_arcmin, params.pixels_per_degree, seeds,
                sharded ? (", shard " + sharded->text() + " of " + std::to_string(items) + " renders").c_str() : "");
    nlohmann::json per_condition = nlohmann::json::array();
    double largest = NAN;
    std::string largest_condition;
    std::vector<int> all_seeds(static_cast<std::size_t>(seeds));
    for (int s = 0; s < seeds; ++s) all_seeds[static_cast<std::size_t>(s)] = s;
    std::vector<std::vector<std::vector<CurvePoint>>> data;  // condition -> artifact size -> radius
    nlohmann::json part_points = nlohmann::json::array();  // --shard: [item, jagged, straight] per render of the shard
    std::size_t item = 0;
    for (const stimuli::Pattern pattern : parsed_patterns) {
      for (const double contrast : contrasts) {
        char contrast_text[32];
        std::snprintf(contrast_text, sizeof contrast_text, "%g", contrast);  // "stair/1", "step/0.5": penumbra-fit's names
        const std::string condition = stimuli::to_string(pattern) + "/" + contrast_text;
        nlohmann::json per_artifact = nlohmann::json::array();
        std::vector<std::vector<CurvePoint>> condition_points;
        for (std::size_t j = 0; j < artifacts.size(); ++j) {
          const double a = artifacts[j];
          if (!sharded) std::printf("%s, a = %g px\n  r/a    deviation jagged  straight   P(correct)\n", condition.c_str(), a);
          std::vector<CurvePoint> points;
          const std::size_t shard_before = part_points.size();
          for (const double ratio : ratios[j]) {
            stimuli::StimulusSpec spec = base;
            spec.pattern = pattern;
            spec.artifact_px = a;
            spec.lit_linear = contrast;
            spec.filter_radius_px = stimuli::clamp_filter_radius(ratio * a, size_px).filter_radius_px;
            CurvePoint point;
            point.ratio = ratio;
            for (int s = 0; s < seeds; ++s, ++item) {
              if (!merged && (!sharded || sharded->covers(item))) {
                spec.seed = sampling::derive_seed(11, static_cast<std::uint64_t>(s));  // the seed's own: the same in every shard
                const stimuli::StimulusPair pair = renderer->render(spec);
                if (frame) {
                  jagged_at[item] = metrics::detect_difference(displayed(pair.line, spec.transfer), metrics::Encoding::linear,
                                                               displayed(pair.artifact, spec.transfer), metrics::Encoding::linear, frame_params)
                                        .deviation_max;
                  straight_at[item] = 0.0;  // the reference against itself
                } else {
                  jagged_at[item] = eye.local_deviation(pair.artifact, spec, pair.geometry, false);
                  straight_at[item] = eye.local_deviation(pair.line, spec, pair.geometry, false);
                }
                if (sharded) part_points.push_back({item, jagged_at[item], straight_at[item]});
              }
              point.jagged.push_back(jagged_at[item]);
              point.straight.push_back(straight_at[item]);
            }
            if (sharded) continue;
            double jagged = 0, straight = 0;
            for (int s = 0; s < seeds; ++s) {
              jagged += point.jagged[static_cast<std::size_t>(s)] / seeds;
              straight += point.straight[static_cast<std::size_t>(s)] / seeds;
            }
            std::printf("  %5.2f  %.5f          %.5f    %.3f\n", ratio, jagged, straight, p_correct(point, all_seeds, params.weber));
            points.push_back(std::move(point));
          }
          if (sharded) {
            std::printf("%s, a = %g px: %zu renders\n", condition.c_str(), a, part_points.size() - shard_before);
            std::fflush(stdout);
            continue;
          }
          const observers::ImpliedC curve = implied_c(points, all_seeds, params.weber, p_threshold);
          std::printf("  implied c (P below p_threshold for every larger r/a; interpolated): %s%.2f\n", curve.at_most ? "at most " : "",
                      curve.c);
          std::fflush(stdout);
          nlohmann::json per = {{"artifact_px", a}, {"c", std::isnan(curve.c) ? nlohmann::json(nullptr) : nlohmann::json(curve.c)}};
          if (curve.at_most) per["at_most"] = true;  // hidden at the smallest ratio tried already
          per_artifact.push_back(per);
          condition_points.push_back(std::move(points));
        }
        if (sharded) continue;
        const double c = condition_c(condition_points, all_seeds, params.weber, p_threshold);
        nlohmann::json entry = {{"condition", condition}, {"c", std::isnan(c) ? nlohmann::json(nullptr) : nlohmann::json(c)},
                                {"per_artifact", per_artifact}};
        per_condition.push_back(entry);
        data.push_back(std::move(condition_points));
        if (!std::isnan(c) && !(c <= largest)) {
          largest = c;
          largest_condition = condition;
        }
      }
    }
    if (sharded) {  // the settings are the arguments themselves: the merge parses them again
      const nlohmann::json part_settings = {{"args", settings_args(args)}};
      io::write_file_atomic(part_out, shard::part_text(kPartKind, tool::version_line("penumbra-observer-curve"), *sharded, part_settings,
                                                       {{"items", items}, {"points", part_points}}));
      std::printf("wrote %s: shard %s, %zu of %zu renders\n", part_out.c_str(), sharded->text().c_str(), part_points.size(), items);
      return 0;
    }
    // The interval from the stimuli themselves: a percentile bootstrap over the seeds (each one
    // phase and orientation of the edge), the same resampled seeds for every radius, size and
    // condition, so the entry's c (the largest condition's) is resampled as a whole. With one
    // seed there is nothing to resample: [c, c].
    std::vector<std::vector<double>> condition_draws(data.size());
    std::vector<double> largest_draws, slope_draws;  // slope_draws: the entry's (largest) condition's
    std::size_t largest_index = 0;
    for (std::size_t k = 0; k < per_condition.size(); ++k)
      if (per_condition[k]["condition"] == largest_condition) largest_index = k;
    if (seeds > 1) {
      sampling::Random random(sampling::derive_seed(29, static_cast<std::uint64_t>(seeds)));
      std::vector<int> pick(static_cast<std::size_t>(seeds));
      for (int b = 0; b < kResamples; ++b) {
        for (int& s : pick) s = static_cast<int>(random.uniform() * seeds);
        double draw_largest = NAN;
        for (std::size_t k = 0; k < data.size(); ++k) {
          const double c = condition_c(data[k], pick, params.weber, p_threshold);
          if (std::isnan(c)) continue;
          condition_draws[k].push_back(c);
          if (!(c <= draw_largest)) draw_largest = c;
        }
        if (!std::isnan(draw_largest)) largest_draws.push_back(draw_largest);
        if (!data.empty())
          if (const double slope = condition_slope(data[largest_index], pick, params.weber, p_threshold); !std::isnan(slope))
            slope_draws.push_back(slope);
      }
    }
    auto interval = [&](const std::vector<double>& draws, double c) {
      if (draws.empty()) return nlohmann::json::array({c, c});
      return nlohmann::json::array({std::min(c, stats::percentile(draws, 0.025)), std::max(c, stats::percentile(draws, 0.975))});
    };
    for (std::size_t k = 0; k < data.size(); ++k) {
      const double beta = condition_slope(data[k], all_seeds, params.weber, p_threshold);
      per_condition[k]["beta"] = std::isnan(beta) ? nlohmann::json(nullptr) : nlohmann::json(beta);
      const nlohmann::json& c = per_condition[k]["c"];
      if (c.is_null()) continue;
      per_condition[k]["ci95"] = interval(condition_draws[k], c.get<double>());
      std::printf("%s: c = %.3f, 95 %% over the stimuli [%.3f, %.3f]\n", per_condition[k]["condition"].get<std::string>().c_str(),
                  c.get<double>(), per_condition[k]["ci95"][0].get<double>(), per_condition[k]["ci95"][1].get<double>());
    }
    if (!json_out.empty()) {
      if (std::isnan(largest)) throw std::runtime_error("--json: no condition crossed p_threshold within the ratio range; nothing to write");
      std::string command = "penumbra-observer-curve";  // the same for a merge of shards: --json last
      for (const std::string& a : settings_args(args)) command += " " + a;
      command += " --json " + json_out;
      nlohmann::json entry = {{"technique", technique.empty() ? "pcf" : technique},
                                    {"kernel", kernel},
                                    {"c", largest},
                                    {"ci95", interval(largest_draws, largest)},
                                    {"condition", largest_condition},
                                    {"obtained_by", "image-observer"},  // a model observer either way: "observer"."kind" says which
                                    {"participants", nullptr},
                                    {"trials", nullptr},
                                    {"per_condition", per_condition},
                                    {"observer", {{"kind", observer_kind}, {frame ? "window_deg" : "window_r", params.window_r}, {"weber", params.weber},
                                                  {"blur_sigma_arcmin", params.blur_sigma_arcmin},
                                                  {"pixels_per_degree", params.pixels_per_degree},
                                                  {"p_threshold", p_threshold}, {"seeds", seeds}, {"size_px", size_px},
                                                  {"resamples", seeds > 1 ? kResamples : 0}}},
                                    {"command", command}};
      // What c is a threshold of, with the observer's own slope (log-Weibull, per log10 unit of
      // a / r): c(F) at another visibility follows it instead of QUEST's assumed 3.5. ci95 of the
      // slope over the same stimulus bootstrap as c's (none with one stimulus).
      const double beta = per_condition[largest_index]["beta"].is_null() ? NAN : per_condition[largest_index]["beta"].get<double>();
      if (!std::isnan(beta)) {
        nlohmann::json threshold = {{"task", "2afc"}, {"guess", 0.5}, {"criterion_f", (p_threshold - 0.5) / 0.5}, {"family", "log-weibull"},
                                    {"beta", beta}, {"lapse", 0.0}, {"beta_from", "the observer's curve of the entry's condition"}};
        if (!slope_draws.empty())
          threshold["beta_ci95"] = {std::min(beta, stats::percentile(slope_draws, 0.025)), std::max(beta, stats::percentile(slope_draws, 0.975))};
        entry["threshold"] = threshold;
      }
      const nlohmann::json file = {
          {"schema_version", 2},
          {"source", "image-observer prediction (a model of the observer, not human data): the largest condition's c; "
                     "a condition's c is the geometric mean over artifact sizes of the r / a beyond which the model's "
                     "2afc P(correct) stays below p_threshold; ci95 is a percentile bootstrap over the stimuli (phase and "
                     "orientation) rendered per radius ([c, c] with one stimulus), widened to contain c"},
          {"entries", {entry}}};
      io::write_file_atomic(json_out, json_input::dump(file, 2) + "\n");
      std::printf("wrote %s: %s%s c = %.3f (%s), image-observer prediction\n", json_out.c_str(), entry["technique"].get<std::string>().c_str(),
                  kernel.empty() ? "" : (" " + kernel).c_str(), largest, largest_condition.c_str());
    }
  } catch (const std::exception& e) {
    return cli::fail(merged ? "penumbra-observer-curve merge" : "penumbra-observer-curve", e);
  }
  return 0;
}

}  // namespace
