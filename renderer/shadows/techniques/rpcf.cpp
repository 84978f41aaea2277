#include "shadows/techniques/rpcf.h"

#include "gl/objects.h"
#include "shadows/settings.h"
#include "shadows/settings_rows.h"

namespace penumbra::shadows {
namespace {

const Setting<RpcfParams> kTable[] = {
    PENUMBRA_RADIUS_ROWS(RpcfParams, "half side of the filter box"),
    PENUMBRA_INT(RpcfParams, max_grid_taps, "taps", 2, 256, "texels per axis integrated exactly before the box is strided"),
    PENUMBRA_INT(RpcfParams, max_search_texels, "texels", 1, 256, "texels walked along a silhouette step in each direction"),
};

}  // namespace

std::span<const Setting<RpcfParams>> settings_table(const RpcfParams*) { return kTable; }

const TechniqueEntry& rpcf_technique() {
  static const TechniqueEntry entry{
      .name = "rpcf",
      .define = "TECHNIQUE_RPCF",
      .radius = RadiusReading::fixed_filter,
      .pages = PageReading::none,
      .filter_radius = section_radius<&ShadowSettings::rpcf>,
      .set_filter_radius = set_section_radius<&ShadowSettings::rpcf>,
      .set_uniforms =
          [](const gl::Program& p, const ShadowSettings& s) {
            p.set("u_rbsm_max_search", s.rpcf.max_search_texels);
            p.set("u_rpcf_max_grid_taps", s.rpcf.max_grid_taps);
          },
  };
  return entry;
}

}  // namespace penumbra::shadows
