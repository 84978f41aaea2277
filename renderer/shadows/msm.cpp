#include "shadows/msm.h"

namespace penumbra::shadows {

MomentsLayout msm_layout() {
  // The far plane z = 1 has every moment 1.
  return {GL_RGBA32F, "shadow_msm_moments.frag", {1, 1, 1, 1}};
}

void set_msm_uniforms(const gl::Program& shading, const MsmParams& p) {
  glProgramUniform1f(shading.id(), shading.location("u_msm_moment_bias"), p.moment_bias);
  glProgramUniform1f(shading.id(), shading.location("u_msm_depth_bias"), p.depth_bias);
  glProgramUniform1f(shading.id(), shading.location("u_msm_bleed_reduction"), p.bleed_reduction);
}

}  // namespace penumbra::shadows
