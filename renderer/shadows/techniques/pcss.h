#pragma once
// Percentage-closer soft shadows (Fernando 2005): blocker search, penumbra estimate from the
// light size, PCF of that radius (shaders/shadow_pcss.glsl).
#include <penumbra/shadows/technique.h>

namespace penumbra::shadows {

struct PcssParams {
  Kernel kernel = Kernel::poisson;
  int blocker_taps = 25;
  int filter_taps = 25;
  float min_penumbra_ws = 0.01f;      // smallest filter radius, world units at the receiver
  float search_scale = 1.0f;          // blocker-search radius relative to its geometric bound
  int max_grid_taps = 32;
  // Bounds from a min-max depth pyramid decide lit, umbra and a certain clamp to the minimum
  // penumbra before any search, so that only pixels in a real penumbra pay for the blocker search
  // (shadow_pcss.glsl); results equal the full search except where the Poisson search missed
  // blockers that the minimum-penumbra filter sees. Off by default: on llvmpipe building the
  // pyramid costs what the shading saves (docs/adaptive.md).
  bool hierarchical = false;
};
std::span<const Setting<PcssParams>> settings_table(const PcssParams*);

const TechniqueEntry& pcss_technique();

}  // namespace penumbra::shadows
