#include "shadows/techniques/erosion.h"

#include "gl/context.h"
#include "shadows/contract.h"
#include "shadows/scoped_pass.h"
#include "shadows/screen_space.h"
#include "shadows/settings.h"
#include "shadows/settings_rows.h"

#include <algorithm>

namespace penumbra::shadows {
namespace {

const Setting<ErosionParams> kTable[] = {
    PENUMBRA_INT(ErosionParams, taps, "taps", 1, 64, "Poisson taps of the PCF scaled by the eroded penumbra width"),
    PENUMBRA_INT(ErosionParams, blocker_taps, "taps", 1, 64, "Poisson taps of the blocker search at edge pixels"),
    PENUMBRA_REAL(ErosionParams, search_scale, "", 1, 8, "blocker-search radius over its geometric bound"),
    PENUMBRA_INT(ErosionParams, max_search_px, "px", 1, 4096, "largest erosion search radius on screen"),
    PENUMBRA_BOOL(ErosionParams, rotate, "rotate the PCF disk per pixel"),
    PENUMBRA_REAL(ErosionParams, depth_threshold, "", 0, 10, rows::kDepthThresholdHelp),
};

const gl::Texture& run_erosion(ScreenSpace& ss, const ErosionParams& p, const PostPassContext& ctx) {
  ScreenSpace::SiteSearch search;
  search.laplacian = true;
  search.blocker_search = true;
  search.blocker_taps = p.blocker_taps;
  search.search_scale = p.search_scale;
  ss.detect_sites(search, p.depth_threshold, ctx);

  gl::Texture& edges = ss.edges_mip();
  {
    ScopedPass pass(ctx.report, "erosion_minmax");
    const gl::Program& prog = ss.program("erosion_minmax.comp");
    prog.use();
    ss.bind_gbuffer(prog, ctx.view, p.depth_threshold);
    ss.sites().bind(contract::UNIT_POST_INPUT);
    ss.site_width().bind(contract::UNIT_POST_INPUT_2);
    int w = ss.width(), h = ss.height();
    for (int level = 0; level < edges.desc().levels; ++level) {
      glProgramUniform1i(prog.id(), prog.location("u_level"), level);
      glBindImageTexture(prog.binding("u_finer"), edges.id(), level > 0 ? level - 1 : 0, GL_FALSE, 0, GL_READ_ONLY, GL_RG32F);
      glBindImageTexture(prog.binding("u_coarser"), edges.id(), level, GL_FALSE, 0, GL_WRITE_ONLY, GL_RG32F);
      prog.dispatch_covering(w, h);
      glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT);
      w = std::max(1, w / 2);
      h = std::max(1, h / 2);
    }
    gl::check_errors("erosion_minmax pass");
  }
  {
    ScopedPass pass(ctx.report, "erosion");
    const gl::Program& prog = ss.program("erosion_search.comp");
    prog.use();
    ctx.set_technique_uniforms(prog);
    ss.bind_gbuffer(prog, ctx.view, p.depth_threshold);
    edges.bind(contract::UNIT_POST_INPUT);
    glProgramUniform1f(prog.id(), prog.location("u_pcss_search_scale"), p.search_scale);
    glProgramUniform1f(prog.id(), prog.location("u_max_search_px"), static_cast<float>(p.max_search_px));
    glBindImageTexture(prog.binding("u_eroded"), ss.scratch(0).id(), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RG32F);
    prog.dispatch_covering(ss.width(), ss.height());
    glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT);
    gl::check_errors("erosion pass");
  }
  return ss.scratch(0);
}

}  // namespace

std::span<const Setting<ErosionParams>> settings_table(const ErosionParams*) { return kTable; }

const TechniqueEntry& erosion_technique() {
  static const TechniqueEntry entry{
      .name = "erosion",
      .define = "TECHNIQUE_EROSION",
      .radius = RadiusReading::none,
      .pages = PageReading::none,
      .reference = ReferenceKind::area_light,
      .search_scale = [](const ShadowSettings& s) { return s.erosion.search_scale; },
      .pad_texels = 1,
      .poisson_taps = [](const ShadowSettings& s) { return std::max(s.erosion.taps, s.erosion.blocker_taps); },
      .set_uniforms =
          [](const gl::Program& p, const ShadowSettings& s) {
            p.set("u_taps", s.erosion.taps);
            p.set("u_rotate", s.erosion.rotate);
          },
      .post = [](ScreenSpace& ss, const ShadowSettings& s, const PostPassContext& ctx) -> const gl::Texture& {
        return run_erosion(ss, s.erosion, ctx);
      },
  };
  return entry;
}

}  // namespace penumbra::shadows
