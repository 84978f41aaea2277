#pragma once
// Moment shadow maps (Peters & Klein 2015, "Moment Shadow Mapping", I3D): four moments of the
// light-space depth z in [-1, 1], box-blurred like VSM, evaluated with the Hamburger 4MSM bound
// (shaders/shadow_msm.glsl). Stored as plain RGBA32F (no 16-bit quantization); see
// docs/alternatives.md for the choice of bias.
#include <penumbra/shadows/technique.h>

namespace penumbra::shadows {

struct MsmParams {
  float radius = 2;                   // box-blur radius of the moments, in `radius_unit`
  RadiusUnit radius_unit = RadiusUnit::texels;
  float moment_bias = 3e-5f;          // alpha: b' = (1 - alpha) b + alpha (0, 0.63, 0, 0.63)
  float depth_bias = 0;               // subtracted from the receiver's depth in [-1, 1]
  float bleed_reduction = 0;          // visibility below this maps to 0, rest rescaled to [0, 1]
};
std::span<const Setting<MsmParams>> settings_table(const MsmParams*);

const TechniqueEntry& msm_technique();

}  // namespace penumbra::shadows
