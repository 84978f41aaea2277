#include "shadows/edtssm.h"

#include "gl/context.h"
#include "shadows/scoped_pass.h"

namespace penumbra::shadows {

const gl::Texture& run_edtssm(ScreenSpace& ss, const EdtssmParams& p, const PostPassContext& ctx) {
  ScreenSpace::SiteSearch search;
  search.blocker_search = true;
  search.blocker_taps = p.blocker_taps;
  search.search_scale = p.search_scale;
  ss.detect_sites(search, p.depth_threshold, ctx);
  {
    ScopedPass pass(ctx.timer, "edt", *ctx.passes);
    ss.edt().compute(ss.sites());
  }
  {
    ScopedPass pass(ctx.timer, "edt_penumbra", *ctx.passes);
    const gl::Program& prog = ss.program("edt_penumbra.comp", {{"PROPAGATED_WIDTH", "1"}});
    prog.use();
    ss.bind_gbuffer(prog, ctx.view, p.depth_threshold);
    ss.edt().nearest().bind(7);
    ss.site_width().bind(8);
    glProgramUniform1f(prog.id(), prog.location("u_beta"), p.beta);
    glProgramUniform1i(prog.id(), prog.location("u_edge_between_pixels"), p.edge_between_pixels ? 1 : 0);
    glBindImageTexture(0, ss.scratch(0).id(), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RG32F);
    dispatch_pixels(ss.width(), ss.height());
    glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT);
    gl::check_errors("edt_penumbra pass");
  }
  return ss.mean_filter(ss.scratch(0), p.filter_ws, p.max_filter_px, p.depth_threshold, ctx);
}

}  // namespace penumbra::shadows
