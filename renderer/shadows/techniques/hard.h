#pragma once
// Hard shadows: one nearest-texel depth comparison (shaders/shadow_hard.glsl). No parameters.
#include <penumbra/shadows/technique.h>

namespace penumbra::shadows {

const TechniqueEntry& hard_technique();

}  // namespace penumbra::shadows
