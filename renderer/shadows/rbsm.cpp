#include "shadows/rbsm.h"

namespace penumbra::shadows {

void set_rbsm_uniforms(const gl::Program& shading, const RbsmParams& p) {
  glProgramUniform1i(shading.id(), shading.location("u_rbsm_max_search"), p.max_search_texels);
}

void set_rpcf_uniforms(const gl::Program& shading, const RpcfParams& p) {
  const bool world = p.radius_unit == RadiusUnit::world;
  glProgramUniform1i(shading.id(), shading.location("u_rbsm_max_search"), p.max_search_texels);
  glProgramUniform1f(shading.id(), shading.location("u_rpcf_radius_texels"), world ? 0.0f : p.radius);
  glProgramUniform1f(shading.id(), shading.location("u_rpcf_radius_ws"), world ? p.radius : -1.0f);
  glProgramUniform1i(shading.id(), shading.location("u_rpcf_max_grid_taps"), p.max_grid_taps);
}

}  // namespace penumbra::shadows
