#include "shadows/techniques/edtssm.h"

#include "gl/context.h"
#include "shadows/scoped_pass.h"
#include "shadows/screen_space.h"
#include "shadows/settings.h"
#include "shadows/settings_rows.h"

namespace penumbra::shadows {
namespace {

const Setting<EdtssmParams> kTable[] = {
    PENUMBRA_CHOICE(EdtssmParams, input, ShadowInput, rows::kInputs, rows::kInputHelp),
    PENUMBRA_REAL(EdtssmParams, beta, "", 0, 1e6, "beta: penumbra scale; alpha = 1/2 -+ d / (beta w_p) for d <= beta w_p / 2"),
    PENUMBRA_INT(EdtssmParams, blocker_taps, "taps", 1, 64, "Poisson taps of the blocker search at silhouette pixels"),
    PENUMBRA_REAL(EdtssmParams, search_scale, "", 1, 8, "blocker-search radius over its geometric bound"),
    PENUMBRA_REAL(EdtssmParams, filter_ws, "world", 0, 1e6, "w_filter: edge-aware mean-filter width; on screen w z_screen / z_eye pixels"),
    PENUMBRA_REAL(EdtssmParams, depth_threshold, "", 0, 10, rows::kDepthThresholdHelp),
    PENUMBRA_INT(EdtssmParams, max_filter_px, "px", 1, 1024, "largest mean-filter width on screen"),
    PENUMBRA_BOOL(EdtssmParams, edge_between_pixels, rows::kEdgeHelp),
};

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

}  // namespace

std::span<const Setting<EdtssmParams>> settings_table(const EdtssmParams*) { return kTable; }

const TechniqueEntry& edtssm_technique() {
  static const TechniqueEntry entry{
      .name = "edtssm",
      .define = "SCREEN_SPACE_VISIBILITY",
      .radius = RadiusReading::none,
      .reference = ReferenceKind::area_light,
      .search_scale = [](const ShadowSettings& s) { return s.edtssm.search_scale; },
      .pad_texels = 1,
      .poisson_taps = [](const ShadowSettings& s) { return s.edtssm.blocker_taps; },
      .post = [](ScreenSpace& ss, const ShadowSettings& s, const PostPassContext& ctx) -> const gl::Texture& {
        return run_edtssm(ss, s.edtssm, ctx);
      },
      .rbsm_input = [](const ShadowSettings& s) { return s.edtssm.input == ShadowInput::rbsm; },
  };
  return entry;
}

}  // namespace penumbra::shadows
