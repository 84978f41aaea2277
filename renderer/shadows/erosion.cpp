#include "shadows/erosion.h"

#include <algorithm>

#include "gl/context.h"
#include "shadows/scoped_pass.h"

namespace penumbra::shadows {

const gl::Texture& run_erosion(ScreenSpace& ss, const ErosionParams& p, const PostPassContext& ctx) {
  ScreenSpace::SiteSearch search;
  search.laplacian = true;
  search.blocker_search = true;
  search.blocker_taps = p.blocker_taps;
  search.search_scale = p.search_scale;
  ss.detect_sites(search, p.depth_threshold, ctx);

  gl::Texture& edges = ss.edges_mip();
  {
    ScopedPass pass(ctx.timer, "erosion_minmax", *ctx.passes);
    const gl::Program& prog = ss.program("erosion_minmax.comp");
    prog.use();
    ss.bind_gbuffer(prog, ctx.view, p.depth_threshold);
    ss.sites().bind(7);
    ss.site_width().bind(8);
    int w = ss.width(), h = ss.height();
    for (int level = 0; level < edges.desc().levels; ++level) {
      glProgramUniform1i(prog.id(), prog.location("u_level"), level);
      glBindImageTexture(0, edges.id(), level > 0 ? level - 1 : 0, GL_FALSE, 0, GL_READ_ONLY, GL_RG32F);
      glBindImageTexture(1, edges.id(), level, GL_FALSE, 0, GL_WRITE_ONLY, GL_RG32F);
      dispatch_pixels(w, h);
      glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT);
      w = std::max(1, w / 2);
      h = std::max(1, h / 2);
    }
    gl::check_errors("erosion_minmax pass");
  }
  {
    ScopedPass pass(ctx.timer, "erosion", *ctx.passes);
    const gl::Program& prog = ss.program("erosion_search.comp");
    prog.use();
    ctx.set_light_uniforms(prog);
    ss.bind_gbuffer(prog, ctx.view, p.depth_threshold);
    edges.bind(7);
    glProgramUniform1f(prog.id(), prog.location("u_pcss_search_scale"), p.search_scale);
    glProgramUniform1f(prog.id(), prog.location("u_max_search_px"), static_cast<float>(p.max_search_px));
    glBindImageTexture(0, ss.scratch(0).id(), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RG32F);
    dispatch_pixels(ss.width(), ss.height());
    glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT);
    gl::check_errors("erosion pass");
  }
  return ss.scratch(0);
}

}  // namespace penumbra::shadows
