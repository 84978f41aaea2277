#include "apps/reference_command.h"
#include "io/atomic_file.h"
#include "io/safe_path.h"
#include "json/json_input.h"
#include "cli/checks.h"
#include "cli/list_option.h"
#include "cli/progress_bar.h"

#include <cstdio>
#include <iostream>

#include "gl/context.h"
#include "io/image_io.h"

namespace penumbra::study_app {

namespace fs = std::filesystem;

ReferenceCommand::ReferenceCommand(CLI::App& app) {
  command_ = app.add_subcommand(
      "reference", "reference filter size: the smallest radius at which jagged and straight 8-bit stimuli are identical");
  cli::add_list_option(*command_, "--pattern", patterns_, "stair and/or step", cli::one_of({"stair", "step"}));
  cli::add_list_option(*command_, "--contrast", contrasts_, "lit levels in linear light", cli::numbers_in(0, 1, cli::Bound::open));
  cli::add_list_option(*command_, "--artifact-px", artifact_px_, "artifact sizes (px)", cli::numbers_in(1, 1000));
  command_->add_option("--partner", partner_,
                       "straight partner: original (the study's), mean-line (through the staircase's mean; stair only) or bresenham (the edge drawn at 1 px and filtered the same way: sec. 4.4)")
      ->capture_default_str();
  command_->add_option("--kernel", kernel_, "disk, grid or poisson")->capture_default_str();
  command_->add_option("--taps", poisson_taps_, "Poisson taps")->capture_default_str();
  command_->add_option("--size-px", size_px_, "stimulus side (px)")->capture_default_str();
  command_->add_option("--transfer", transfer_, "display transfer function: srgb, gamma2.2, linear")->capture_default_str();
  cli::add_list_option(*command_, "--seeds", search_.seeds, "edge phases/orientations to check (the result is the worst)",
                       cli::non_negative_integers());  // each item: `--seeds ""` ran with seed 0
  command_->add_option("--r-min", search_.r_min_px, "smallest radius scanned (px)")->capture_default_str();
  command_->add_option("--r-max", search_.r_max_px, "largest radius scanned (px); 0 = size/2")->capture_default_str();
  command_->add_option("--growth", search_.growth, "ratio between scanned radii")->capture_default_str();
  command_->add_option("--resolution", search_.resolution_px, "bisection resolution (px)")->capture_default_str();
  command_->add_option("--tolerance-levels", search_.tolerance_levels,
                       "identical = no pixel differs by more than this many 8-bit levels (0: exactly identical)")
      ->capture_default_str();
  command_->add_flag("--no-progress", no_progress_, "no progress line on stderr");
  command_->add_option("-o,--output", output_, "output JSON file")->required()->check(cli::path_given());
}

int ReferenceCommand::run() const {
  io::check_output(output_, io::OutputKind::file);  // before the long search: a folder that exists, no link
  stimuli::ReferenceSearch search = search_;
  search.partner = stimuli::parse_partner(partner_);
  std::vector<stimuli::StimulusSpec> specs;
  for (const std::string& pattern : patterns_) {
    for (double contrast : contrasts_) {
      for (double a : artifact_px_) {
        stimuli::StimulusSpec spec;
        spec.pattern = stimuli::parse_pattern(pattern);
        spec.lit_linear = contrast;
        spec.artifact_px = a;
        spec.kernel = stimuli::parse_kernel(kernel_);
        spec.poisson_taps = poisson_taps_;
        spec.size_px = size_px_;
        spec.transfer = stimuli::parse_transfer(transfer_);
        spec.filter_radius_px = 1.0;
        stimuli::validate(spec);  // before any rendering: bad options fail at once
        if (search.partner == stimuli::Partner::mean_line && spec.pattern != stimuli::Pattern::stair)
          throw std::invalid_argument("--partner mean-line: defined for the stair pattern only");
        specs.push_back(spec);
      }
    }
  }
  gl::HeadlessContext context;
  stimuli::StimulusRenderer renderer;
  nlohmann::json entries = nlohmann::json::array();
  ProgressBar bar("reference", !no_progress_, " seeds");
  for (std::size_t i = 0; i < specs.size(); ++i) {
    char note[96];
    std::snprintf(note, sizeof note, "stimulus %zu/%zu: %s a=%g contrast %g", i + 1, specs.size(),
                  stimuli::to_string(specs[i].pattern).c_str(), specs[i].artifact_px, specs[i].lit_linear);
    // Seeds done over every stimulus's seeds (each has the same count).
    const auto progress = [&](int done, int total) {
      bar(static_cast<int>(i) * total + done, static_cast<int>(specs.size()) * total, note);
    };
    const stimuli::Reference ref = stimuli::find_reference(renderer, specs[i], search, progress);
    entries.push_back(stimuli::to_json(ref));
  }
  bar.clear();
  const nlohmann::json out = {
      {"what", "reference filter size: smallest filter radius (px) at which the 8-bit stimuli drawn from the jagged "
               "shadow map and from the straight original are pixel-identical, worst over the seeds; null when they "
               "still differ at r_max"},
      {"renderer", context.info().renderer},
      {"entries", entries}};
  io::write_file_atomic(output_, json_input::dump(out, 2) + "\n");
  for (const auto& e : entries) {
    const auto& r = e["reference_filter_radius_px"];
    std::printf("%-5s contrast %-4g a %-4g %s partner: reference r = %s%s\n", e["pattern"].get<std::string>().c_str(),
                e["contrast"].get<double>(), e["artifact_px"].get<double>(), e["partner"].get<std::string>().c_str(),
                r.is_null() ? "none <= r_max" : (std::to_string(r.get<double>()) + " px").c_str(),
                e["monotone"].get<bool>() ? "" : "  (not monotone in r)");
  }
  std::cout << "wrote " << output_.string() << "\n";
  return 0;
}

}  // namespace penumbra::study_app
