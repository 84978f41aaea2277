// penumbra-study: the 2AFC study app (docs/study.md).
//   penumbra-study stimulus --pattern stair --artifact-px 10 --filter-radius-px 20 -o DIR
#include <CLI/CLI.hpp>

#include <filesystem>
#include <iostream>

#include "gl/context.h"
#include "io/image_io.h"
#include "stimuli/stimulus.h"

namespace fs = std::filesystem;
using namespace penumbra;

namespace {

int run_stimulus(const std::string& pattern, const std::string& kernel, const std::string& transfer,
                 stimuli::StimulusSpec spec, const fs::path& out) {
  spec.pattern = stimuli::parse_pattern(pattern);
  spec.kernel = stimuli::parse_kernel(kernel);
  spec.transfer = stimuli::parse_transfer(transfer);
  const auto shown = stimuli::clamp_filter_radius(spec.filter_radius_px, spec.size_px);
  const double requested = spec.filter_radius_px;
  spec.filter_radius_px = shown.filter_radius_px;
  stimuli::validate(spec);
  gl::HeadlessContext context;
  stimuli::StimulusRenderer renderer;
  const stimuli::StimulusPair pair = renderer.render(spec);
  fs::create_directories(out);
  io::write_png(out / "artifact.png", pair.artifact);
  io::write_png(out / "line.png", pair.line);
  nlohmann::json j = stimuli::to_json(spec, pair.geometry);
  j["requested_filter_radius_px"] = requested;
  j["filter_radius_clamped"] = shown.clamped;
  j["intensity"] = std::log10(spec.artifact_px / spec.filter_radius_px);
  j["images"] = {{"artifact", "artifact.png"}, {"line", "line.png"}};
  j["renderer"] = context.info().renderer;
  io::write_text(out / "stimulus.json", j.dump(2) + "\n");
  std::cout << "wrote " << (out / "artifact.png").string() << ", line.png, stimulus.json\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"penumbra-study: 2AFC shadow-artifact study (docs/study.md)"};
  app.require_subcommand(1);

  auto* stim = app.add_subcommand("stimulus", "render one stimulus pair (artifact and line) to PNG + JSON");
  stimuli::StimulusSpec spec;
  std::string pattern = "stair", kernel = "disk", transfer = "srgb";
  fs::path stim_out;
  stim->add_option("--pattern", pattern, "stair or step")->capture_default_str();
  stim->add_option("--artifact-px", spec.artifact_px, "shadow-map texel size on screen (px)")->required();
  stim->add_option("--filter-radius-px", spec.filter_radius_px, "PCF radius (px); clamped to [1, size/2]")->required();
  stim->add_option("--contrast", spec.lit_linear, "lit level in linear light (1 = full, 0.5 = half)")->capture_default_str();
  stim->add_option("--kernel", kernel, "disk (exact dense disk), grid (box) or poisson")->capture_default_str();
  stim->add_option("--taps", spec.poisson_taps, "Poisson taps")->capture_default_str();
  stim->add_option("--size-px", spec.size_px, "stimulus side (px)")->capture_default_str();
  stim->add_option("--transfer", transfer, "display transfer function: srgb, gamma2.2, linear")->capture_default_str();
  stim->add_option("--seed", spec.seed, "edge phase and orientation")->capture_default_str();
  stim->add_option("-o,--output", stim_out, "output directory")->required();

  CLI11_PARSE(app, argc, argv);
  try {
    if (stim->parsed()) return run_stimulus(pattern, kernel, transfer, spec, stim_out);
  } catch (const std::exception& e) {
    std::cerr << "penumbra-study: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
