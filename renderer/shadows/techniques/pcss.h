#pragma once
// Percentage-closer soft shadows (Fernando 2005): blocker search, penumbra estimate from the
// light size, PCF of that radius (shaders/shadow_pcss.glsl).
#include "shadows/technique.h"

namespace penumbra::shadows {

struct PcssParams {
  Kernel kernel = Kernel::poisson;
  int blocker_taps = 25;
  int filter_taps = 25;
  float min_penumbra_ws = 0.01f;      // smallest filter radius, world units at the receiver
  float search_scale = 1.0f;          // blocker-search radius relative to its geometric bound
  int max_grid_taps = 32;
};
std::span<const Setting<PcssParams>> settings_table(const PcssParams*);

const TechniqueEntry& pcss_technique();

}  // namespace penumbra::shadows
