#pragma once
// Exponential variance shadow maps (Lauritzen & McCool 2008, "Layered variance shadow maps",
// GI): depth x in [-1, 1] warped to exp(c+ x) and -exp(-c- x), first and second moments of both
// stored, box-blurred like VSM, and the smaller of the two Chebyshev bounds taken
// (shaders/shadow_evsm.glsl).
#include <glm/glm.hpp>

#include <penumbra/shadows/technique.h>

namespace penumbra::shadows {

struct EvsmParams {
  float radius = 2;                   // box-blur radius of the moments, in `radius_unit`
  RadiusUnit radius_unit = RadiusUnit::texels;
  MomentFormat format = MomentFormat::rgba32f;
  float positive_exponent = 40;       // c+, clamped to the format's limit (42 float32, 5.54 float16)
  float negative_exponent = 5;        // c-, clamped likewise
  float min_variance = 1e-6f;         // in normalized depth^2, carried through the warp's slope
  float bleed_reduction = 0;          // as VsmParams
};
std::span<const Setting<EvsmParams>> settings_table(const EvsmParams*);

const TechniqueEntry& evsm_technique();

// Largest exponent c whose second moment exp(2c) is finite in `format` with headroom for the
// blur's sums: 42 for 32-bit floats (e^84 < 3.4e38), 5.54 for 16-bit floats (e^11.08 < 65504).
float evsm_exponent_limit(MomentFormat format);
// (c+, c-) as used: the parameters clamped to [0, evsm_exponent_limit(format)].
glm::vec2 evsm_exponents(const EvsmParams& p);
MomentsLayout evsm_layout(const EvsmParams& p);

}  // namespace penumbra::shadows
