// penumbra-observer-curve: the image observer's psychometric curve for one pattern, without a
// staircase. For each r / a on a log grid it renders the stimulus pair (several seeds: phase and
// orientation), takes the observer's noise-free local deviations of the jagged and the straight
// image, and turns their difference into P(correct) = Phi(diff / (sqrt 2 weber)) (2afc: both
// decisions carry independent N(0, weber) noise). The implied c is the r / a beyond which P stays
// below p_threshold (interpolated in log r / a at the last crossing): the filter that hides the
// artifact for every larger radius.
//   penumbra-observer-curve --pattern step --artifact-px 5,10,20
#include <CLI/CLI.hpp>

#include <cmath>
#include <cstdio>
#include <iostream>

#include "cli/main.h"
#include "gl/context.h"
#include "observers/image_observer.h"
#include "quest/psychometric.h"
#include "sampling/random.h"
#include "stimuli/stimulus.h"

using namespace penumbra;

int main(int argc, char** argv) {
  CLI::App app{"The image observer's 2afc psychometric curve and implied c (docs/study.md)"};
  cli::describe_tool(app, "penumbra-observer-curve", "study.md");
  std::string pattern = "stair";
  std::vector<double> artifacts{5, 10, 20};
  double contrast = 1.0, ratio_min = 0.5, ratio_max = 8, step = 1.06, p_threshold = 0.82;
  int seeds = 3, size_px = 320;
  observers::ImageObserverParams params;
  params.blur_sigma_arcmin = 1.0;
  params.pixels_per_degree = 38.2;  // data/studies/default.json's display: 1.57 arcmin per pixel
  app.add_option("--pattern", pattern, "stair or step")->capture_default_str();
  app.add_option("--artifact-px", artifacts, "artifact sizes")->delimiter(',')->capture_default_str();
  app.add_option("--contrast", contrast, "lit level, linear light")->capture_default_str();
  app.add_option("--ratio-min", ratio_min, "smallest r / a")->capture_default_str()->check(CLI::Range(0.05, 100.0));
  app.add_option("--ratio-max", ratio_max, "largest r / a (clamped radii are skipped)")->capture_default_str()->check(CLI::Range(0.05, 100.0));
  app.add_option("--ratio-step", step, "grid factor between radii")->capture_default_str()->check(CLI::Range(1.001, 4.0));
  app.add_option("--seeds", seeds, "stimuli (phase, orientation) averaged per radius")->capture_default_str()->check(CLI::Range(1, 1000));
  app.add_option("--size-px", size_px, "stimulus side")->capture_default_str();
  app.add_option("--p-threshold", p_threshold, "threshold criterion")->capture_default_str()->check(CLI::Range(0.51, 0.999));
  app.add_option("--blur-arcmin", params.blur_sigma_arcmin, "optical blur sigma")->capture_default_str();
  app.add_option("--ppd", params.pixels_per_degree, "display pixels per degree")->capture_default_str();
  app.add_option("--window", params.window_r, "local window, filter radii")->capture_default_str();
  app.add_option("--weber", params.weber, "decision noise sd (relative deviation)")->capture_default_str();
  if (const auto status = cli::parse(app, argc, argv, "penumbra-observer-curve")) return *status;
  try {
    gl::HeadlessContext context;
    stimuli::StimulusRenderer renderer;
    observers::ImageObserver eye(params, 1);
    std::printf("pattern %s, contrast %g, window %g r, weber %g, blur %g arcmin at %g px/deg, %d seeds\n",
                pattern.c_str(), contrast, params.window_r, params.weber, params.blur_sigma_arcmin,
                params.pixels_per_degree, seeds);
    for (double a : artifacts) {
      double implied = NAN, last_ratio = NAN, last_p = NAN;
      std::printf("a = %g px\n  r/a    deviation jagged  straight   P(correct)\n", a);
      for (double ratio = ratio_min; ratio <= ratio_max * 1.0001; ratio *= step) {
        stimuli::StimulusSpec spec;
        spec.pattern = stimuli::parse_pattern(pattern);
        spec.artifact_px = a;
        spec.lit_linear = contrast;
        spec.size_px = size_px;
        const auto shown = stimuli::clamp_filter_radius(ratio * a, size_px);
        if (shown.clamped) break;
        spec.filter_radius_px = shown.filter_radius_px;
        double jagged = 0, straight = 0;
        for (int s = 0; s < seeds; ++s) {
          spec.seed = sampling::derive_seed(11, static_cast<std::uint64_t>(s));
          const stimuli::StimulusPair pair = renderer.render(spec);
          jagged += eye.local_deviation(pair.artifact, spec, pair.geometry, false) / seeds;
          straight += eye.local_deviation(pair.line, spec, pair.geometry, false) / seeds;
        }
        const double p = 0.5 * std::erfc(-(jagged - straight) / (2 * params.weber));  // Phi(d / (sqrt2 w))
        if (p >= p_threshold) {
          implied = NAN;
        } else if (std::isnan(implied)) {  // crossed down: interpolate in log r/a
          implied = std::isnan(last_p) ? ratio
                                       : last_ratio * std::pow(ratio / last_ratio, (last_p - p_threshold) / (last_p - p));
        }
        last_ratio = ratio;
        last_p = p;
        std::printf("  %5.2f  %.5f          %.5f    %.3f\n", ratio, jagged, straight, p);
      }
      std::printf("  implied c (P below p_threshold for every larger r/a; interpolated): %.2f\n", implied);
      std::fflush(stdout);
    }
  } catch (const std::exception& e) {
    return cli::fail("penumbra-observer-curve", e.what());
  }
  return 0;
}
