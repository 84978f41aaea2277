#pragma once
// Revectorization-based shadow mapping (Macedo & Apolinario 2016, "Revectorization-Based Shadow
// Mapping", GI; summarized in /work/shared/papers/001_*) and RPCF, the PCF of the revectorized
// test. The shader (shaders/shadow_rbsm.glsl) exposes
//   float shadow_rbsm(vec3 sc, vec2 gradient)   revectorized hard visibility, 0 or 1
// so that screen-space techniques can start from RBSM's hard shadow: a frame with
// Technique::rbsm writes exactly that into the visibility target. Procedure and the choices the
// paper leaves open: docs/alternatives.md.
#include "gl/objects.h"
#include "shadows/settings.h"

namespace penumbra::shadows {

void set_rbsm_uniforms(const gl::Program& shading, const RbsmParams& p);
void set_rpcf_uniforms(const gl::Program& shading, const RpcfParams& p);

}  // namespace penumbra::shadows
