#include "shadows/techniques/edtssm.h"

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
    PENUMBRA_EDT_FILTER_ROWS(EdtssmParams),
};

const gl::Texture& run_edtssm(ScreenSpace& ss, const EdtssmParams& p, const PostPassContext& ctx) {
  ScreenSpace::SiteSearch search;
  search.blocker_search = true;
  search.blocker_taps = p.blocker_taps;
  search.search_scale = p.search_scale;
  ss.detect_sites(search, p.depth_threshold, ctx);
  const gl::Texture& penumbra = ss.edt_penumbra(true, p.edge_between_pixels, p.depth_threshold,
                                                [&](const gl::Program& prog) { prog.set("u_beta", p.beta); }, ctx);
  return ss.mean_filter(penumbra, p.filter_ws, p.max_filter_px, p.depth_threshold, ctx);
}

}  // namespace

std::span<const Setting<EdtssmParams>> settings_table(const EdtssmParams*) { return kTable; }

const TechniqueEntry& edtssm_technique() {
  static const TechniqueEntry entry{
      .name = "edtssm",
      .define = "SCREEN_SPACE_VISIBILITY",
      .radius = RadiusReading::none,
      .pages = PageReading::none,
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
