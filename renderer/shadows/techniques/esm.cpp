#include "shadows/techniques/esm.h"

#include <algorithm>
#include <cmath>

#include "gl/objects.h"
#include "shadows/settings.h"
#include "shadows/settings_rows.h"

namespace penumbra::shadows {
namespace {

const Setting<EsmParams> kTable[] = {
    PENUMBRA_RADIUS_ROWS(EsmParams, "box-blur radius of exp(c z)"),
    PENUMBRA_REAL(EsmParams, exponent, "", 0, 1000, "c of exp(c z): sharper tests, less light leaking; clamped to 77 (float32 range)"),
};

}  // namespace

std::span<const Setting<EsmParams>> settings_table(const EsmParams*) { return kTable; }

float esm_exponent(const EsmParams& p) { return std::clamp(p.exponent, 0.0f, kEsmMaxExponent); }

const TechniqueEntry& esm_technique() {
  static const TechniqueEntry entry{
      .name = "esm",
      .define = "TECHNIQUE_ESM",
      .radius = RadiusReading::fixed_filter,
      .pages = PageReading::none,
      .filter_radius = section_radius<&ShadowSettings::esm>,
      .set_filter_radius = set_section_radius<&ShadowSettings::esm>,
      // exp(c t) of normalized linear depth t, one float; the far plane t = 1 reads exp(c). Summed
      // anew per window: a sliding sum's rounding follows the largest value in a line, exp(c).
      .moments =
          [](const ShadowSettings& s) {
            return std::optional<MomentsLayout>({MomentsFormat::r32f, {std::exp(esm_exponent(s.esm)), 0, 0, 0}, /*direct_sums=*/true});
          },
      // The exponent serves the moments pass and the shading pass alike.
      .set_uniforms = [](const gl::Program& p, const ShadowSettings& s) { p.set("u_esm_exponent", esm_exponent(s.esm)); },
  };
  return entry;
}

}  // namespace penumbra::shadows
