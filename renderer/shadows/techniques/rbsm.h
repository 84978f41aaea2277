#pragma once
// Revectorization-based shadow mapping (Macedo & Apolinario 2016, "Revectorization-Based Shadow
// Mapping", GI; summarized in their "Efficient Shadow Anti-Aliasing Techniques using Silhouette Revectorization"): hard shadows whose texel staircase is
// replaced by the line through the steps' risers. The shader (shaders/shadow_rbsm.glsl) exposes
//   float shadow_rbsm(vec3 sc, vec2 gradient)   revectorized hard visibility, 0 or 1
// so that screen-space techniques can start from RBSM's hard shadow. Procedure and the choices
// the paper leaves open: docs/alternatives.md.
#include <penumbra/shadows/technique.h>

namespace penumbra::gl {
class Program;
}

namespace penumbra::shadows {

struct RbsmParams {
  int max_search_texels = 16;         // texels walked along a silhouette step in each direction
};
std::span<const Setting<RbsmParams>> settings_table(const RbsmParams*);

const TechniqueEntry& rbsm_technique();
// The revectorization's uniforms (also set by RPCF and the screen-space techniques' G-buffer).
void set_rbsm_uniforms(const gl::Program& program, const RbsmParams& p);

}  // namespace penumbra::shadows
