#pragma once
// Variance shadow maps (Donnelly & Lauritzen 2006): box-blurred moments (t, t²) of linear depth
// and Chebyshev's bound (shaders/shadow_vsm.glsl).
#include <penumbra/shadows/technique.h>

namespace penumbra::shadows {

struct VsmParams {
  float radius = 2;                   // box-blur radius of the moments, in `radius_unit`
  RadiusUnit radius_unit = RadiusUnit::texels;
  float min_variance = 1e-6f;         // in normalized depth²
  float bleed_reduction = 0.2f;       // p below this maps to 0, rest rescaled to [0, 1]
};
std::span<const Setting<VsmParams>> settings_table(const VsmParams*);

const TechniqueEntry& vsm_technique();

}  // namespace penumbra::shadows
