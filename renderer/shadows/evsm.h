#pragma once
// Exponential variance shadow maps (Lauritzen & McCool 2008, "Layered variance shadow maps",
// GI): depth x in [-1, 1] warped to exp(c+ x) and -exp(-c- x), first and second moments of both
// stored, box-blurred like VSM, and the smaller of the two Chebyshev bounds taken
// (shaders/shadow_evsm.glsl).
#include <glm/glm.hpp>

#include "gl/objects.h"
#include "shadows/moments.h"
#include "shadows/settings.h"

namespace penumbra::shadows {

// Largest exponent c whose second moment exp(2c) is finite in `format` with headroom for the
// blur's sums: 42 for 32-bit floats (e^84 < 3.4e38), 5.54 for 16-bit floats (e^11.08 < 65504).
float evsm_exponent_limit(MomentFormat format);
// (c+, c-) as used: the parameters clamped to [0, evsm_exponent_limit(format)].
glm::vec2 evsm_exponents(const EvsmParams& p);

MomentsLayout evsm_layout(const EvsmParams& p);
// Sets u_evsm_exponents (moments and shading programs) and the shading program's other uniforms.
void set_evsm_uniforms(const gl::Program& program, const EvsmParams& p);

}  // namespace penumbra::shadows
