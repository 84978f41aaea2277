#pragma once
// Moment shadow maps (Peters & Klein 2015, "Moment Shadow Mapping", I3D): four moments of the
// light-space depth z in [-1, 1], box-blurred like VSM, evaluated with the Hamburger 4MSM bound
// (shaders/shadow_msm.glsl). Stored as plain RGBA32F (no 16-bit quantization); see
// docs/alternatives.md for the choice of bias.
#include "gl/objects.h"
#include "shadows/moments.h"
#include "shadows/settings.h"

namespace penumbra::shadows {

MomentsLayout msm_layout();
// Sets the shading program's MSM uniforms.
void set_msm_uniforms(const gl::Program& shading, const MsmParams& p);

}  // namespace penumbra::shadows
