#pragma once
// EDT soft shadows (Macedo & Apolinario 2017), screen space: PCSS blocker search at silhouette
// pixels only -> w_p = w_light (z_R - z_avg) / z_avg -> EDT propagates w_p -> alpha = 1/2 -+ d / (beta w_p)
// -> mean filter.
#include <penumbra/shadows/technique.h>

namespace penumbra::shadows {

struct EdtssmParams {
  ShadowInput input = ShadowInput::rbsm;
  float beta = 1.0f;                  // penumbra scale (w_p is in world units here; the paper's 750 was for light-space units)
  int blocker_taps = 25;              // Poisson taps of the blocker search at silhouette pixels
  float search_scale = 1.0f;          // blocker-search radius over its geometric bound
  float filter_ws = 0.05f;            // w_filter, world units
  float depth_threshold = 0.05f;
  int max_filter_px = 64;
  bool edge_between_pixels = false;
};
std::span<const Setting<EdtssmParams>> settings_table(const EdtssmParams*);

const TechniqueEntry& edtssm_technique();

}  // namespace penumbra::shadows
