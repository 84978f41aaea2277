#include "shadows/techniques/vsm.h"

#include "gl/objects.h"
#include "shadows/settings.h"
#include "shadows/settings_rows.h"

namespace penumbra::shadows {
namespace {

const Setting<VsmParams> kTable[] = {
    PENUMBRA_RADIUS_ROWS(VsmParams, "box-blur radius of the moments"),
    PENUMBRA_REAL(VsmParams, min_variance, "depth^2", 0, 1, "variance floor"),
    PENUMBRA_REAL(VsmParams, bleed_reduction, "", 0, 0.999, "light-bleeding reduction threshold"),
};

}  // namespace

std::span<const Setting<VsmParams>> settings_table(const VsmParams*) { return kTable; }

const TechniqueEntry& vsm_technique() {
  static const TechniqueEntry entry{
      .name = "vsm",
      .define = "TECHNIQUE_VSM",
      .radius = RadiusReading::fixed_filter,
      .pages = PageReading::moments,
      .filter_radius = section_radius<&ShadowSettings::vsm>,
      .set_filter_radius = set_section_radius<&ShadowSettings::vsm>,
      // (t, t² + texel variance) of normalized linear depth t; the far plane t = 1.
      .moments = [](const ShadowSettings&) { return std::optional<MomentsLayout>({MomentsFormat::rg32f, {1, 1, 0, 0}}); },
      .set_uniforms =
          [](const gl::Program& p, const ShadowSettings& s) {
            p.set("u_vsm_min_variance", s.vsm.min_variance);
            p.set("u_vsm_bleed_reduction", s.vsm.bleed_reduction);
          },
  };
  return entry;
}

}  // namespace penumbra::shadows
