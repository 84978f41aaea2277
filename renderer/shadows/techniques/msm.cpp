#include "shadows/techniques/msm.h"

#include "gl/objects.h"
#include "shadows/settings.h"
#include "shadows/settings_rows.h"

namespace penumbra::shadows {
namespace {

const Setting<MsmParams> kTable[] = {
    PENUMBRA_RADIUS_ROWS(MsmParams, "box-blur radius of the moments"),
    PENUMBRA_REAL(MsmParams, moment_bias, "", 1e-9, 0.1, "moment bias alpha toward (0, 0.63, 0, 0.63)"),
    PENUMBRA_REAL(MsmParams, depth_bias, "depth", 0, 0.1, "receiver depth offset, depth in [-1, 1] over the light's depth range"),
    PENUMBRA_REAL(MsmParams, bleed_reduction, "", 0, 0.999, "light-bleeding reduction threshold"),
};

}  // namespace

std::span<const Setting<MsmParams>> settings_table(const MsmParams*) { return kTable; }

const TechniqueEntry& msm_technique() {
  static const TechniqueEntry entry{
      .name = "msm",
      .define = "TECHNIQUE_MSM",
      .radius = RadiusReading::fixed_filter,
      .pages = PageReading::none,
      .filter_radius = section_radius<&ShadowSettings::msm>,
      .set_filter_radius = set_section_radius<&ShadowSettings::msm>,
      // (z, z², z³, z⁴) of z in [-1, 1]; the far plane z = 1 has every moment 1.
      .moments = [](const ShadowSettings&) { return std::optional<MomentsLayout>({MomentsFormat::rgba32f, {1, 1, 1, 1}}); },
      .set_uniforms =
          [](const gl::Program& p, const ShadowSettings& s) {
            p.set("u_msm_moment_bias", s.msm.moment_bias);
            p.set("u_msm_depth_bias", s.msm.depth_bias);
            p.set("u_msm_bleed_reduction", s.msm.bleed_reduction);
          },
  };
  return entry;
}

}  // namespace penumbra::shadows
