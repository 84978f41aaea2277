#include "shadows/techniques/edtsm.h"

#include "gl/context.h"
#include "shadows/scoped_pass.h"
#include "shadows/screen_space.h"
#include "shadows/settings.h"
#include "shadows/settings_rows.h"

namespace penumbra::shadows {
namespace {

const Setting<EdtsmParams> kTable[] = {
    PENUMBRA_CHOICE(EdtsmParams, input, ShadowInput, rows::kInputs, rows::kInputHelp),
    PENUMBRA_REAL(EdtsmParams, penumbra_ws, "world", 0, 1e6, "P: fake-penumbra width; I = 1/2 -+ D/P for D <= P/2"),
    PENUMBRA_REAL(EdtsmParams, filter_ws, "world", 0, 1e6, "w_filter: edge-aware mean-filter width; on screen w z_screen / z_eye pixels"),
    PENUMBRA_REAL(EdtsmParams, depth_threshold, "", 0, 10, rows::kDepthThresholdHelp),
    PENUMBRA_INT(EdtsmParams, max_filter_px, "px", 1, 1024, "largest mean-filter width on screen"),
    PENUMBRA_BOOL(EdtsmParams, edge_between_pixels, rows::kEdgeHelp),
};

// The post passes after the G-buffer:
//   sites        3x3 silhouette sites of the input shadows (edge-aware)
//   edt          exact EDT: nearest site per pixel
//   edt_penumbra I = 1/2 -+ D/P for D <= P/2, D in world units between G-buffer positions
//   mean_filter  separable edge-aware mean filter of width w_filter z_screen / z_eye pixels

const gl::Texture& run_edtsm(ScreenSpace& ss, const EdtsmParams& p, const PostPassContext& ctx) {
  ss.detect_sites({}, p.depth_threshold, ctx);
  {
    ScopedPass pass(ctx.timer, "edt", *ctx.passes);
    ss.edt().compute(ss.sites());
  }
  {
    ScopedPass pass(ctx.timer, "edt_penumbra", *ctx.passes);
    const gl::Program& prog = ss.program("edt_penumbra.comp");
    prog.use();
    ss.bind_gbuffer(prog, ctx.view, p.depth_threshold);
    ss.edt().nearest().bind(7);
    glProgramUniform1f(prog.id(), prog.location("u_penumbra_ws"), p.penumbra_ws);
    glProgramUniform1i(prog.id(), prog.location("u_edge_between_pixels"), p.edge_between_pixels ? 1 : 0);
    glBindImageTexture(0, ss.scratch(0).id(), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RG32F);
    dispatch_pixels(ss.width(), ss.height());
    glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT);
    gl::check_errors("edt_penumbra pass");
  }
  return ss.mean_filter(ss.scratch(0), p.filter_ws, p.max_filter_px, p.depth_threshold, ctx);
}

}  // namespace

std::span<const Setting<EdtsmParams>> settings_table(const EdtsmParams*) { return kTable; }

const TechniqueEntry& edtsm_technique() {
  static const TechniqueEntry entry{
      .name = "edtsm",
      .define = "SCREEN_SPACE_VISIBILITY",
      .radius = RadiusReading::none,
      .pad_texels = 1,  // the revectorization reads the neighbours of every receiver texel
      .post = [](ScreenSpace& ss, const ShadowSettings& s, const PostPassContext& ctx) -> const gl::Texture& {
        return run_edtsm(ss, s.edtsm, ctx);
      },
      .rbsm_input = [](const ShadowSettings& s) { return s.edtsm.input == ShadowInput::rbsm; },
  };
  return entry;
}

}  // namespace penumbra::shadows
