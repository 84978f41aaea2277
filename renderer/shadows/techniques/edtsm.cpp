#include "shadows/techniques/edtsm.h"

#include "shadows/screen_space.h"
#include "shadows/settings.h"
#include "shadows/settings_rows.h"

namespace penumbra::shadows {
namespace {

const Setting<EdtsmParams> kTable[] = {
    PENUMBRA_CHOICE(EdtsmParams, input, ShadowInput, rows::kInputs, rows::kInputHelp),
    PENUMBRA_REAL(EdtsmParams, penumbra_ws, "world", 0, 1e6, "P: fake-penumbra width; I = 1/2 -+ D/P for D <= P/2"),
    PENUMBRA_EDT_FILTER_ROWS(EdtsmParams),
};

// The post passes after the G-buffer:
//   sites        3x3 silhouette sites of the input shadows (edge-aware)
//   edt          exact EDT: nearest site per pixel
//   edt_penumbra I = 1/2 -+ D/P for D <= P/2, D in world units between G-buffer positions
//   mean_filter  separable edge-aware mean filter of width w_filter z_screen / z_eye pixels

const gl::Texture& run_edtsm(ScreenSpace& ss, const EdtsmParams& p, const PostPassContext& ctx) {
  ss.detect_sites({}, p.depth_threshold, ctx);
  const gl::Texture& penumbra = ss.edt_penumbra(false, p.edge_between_pixels, p.depth_threshold,
                                                [&](const gl::Program& prog) { prog.set("u_penumbra_ws", p.penumbra_ws); }, ctx);
  return ss.mean_filter(penumbra, p.filter_ws, p.max_filter_px, p.depth_threshold, ctx);
}

}  // namespace

std::span<const Setting<EdtsmParams>> settings_table(const EdtsmParams*) { return kTable; }

const TechniqueEntry& edtsm_technique() {
  static const TechniqueEntry entry{
      .name = "edtsm",
      .define = "SCREEN_SPACE_VISIBILITY",
      .radius = RadiusReading::none,
      .pages = PageReading::none,
      .pad_texels = 1,  // the revectorization reads the neighbours of every receiver texel
      .post = [](ScreenSpace& ss, const ShadowSettings& s, const PostPassContext& ctx) -> const gl::Texture& {
        return run_edtsm(ss, s.edtsm, ctx);
      },
      .rbsm_input = [](const ShadowSettings& s) { return s.edtsm.input == ShadowInput::rbsm; },
  };
  return entry;
}

}  // namespace penumbra::shadows
