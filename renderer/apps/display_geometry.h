#pragma once
// The viewing geometry of the apps' perceptual differences, from a study config: penumbra-compare
// --display and penumbra-demo --display read it the same way.
#include <string>
#include <string_view>

namespace penumbra::apps {

// Pixels per degree from a study config's display block (data/studies/*.json, docs/study-config.md):
// width_px, width_mm and viewing_distance_mm, each required here (the study would take its defaults
// for a missing one; a comparison should not rest on a silent default), by
// metrics::pixels_per_degree. `tool` names the app in the refusal's reason. Throws
// std::runtime_error naming the file and field.
double display_pixels_per_degree(const std::string& study_config, std::string_view tool);

}  // namespace penumbra::apps
