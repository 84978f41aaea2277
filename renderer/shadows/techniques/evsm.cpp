#include "shadows/techniques/evsm.h"

#include <algorithm>
#include <cmath>

#include "gl/objects.h"
#include "shadows/settings.h"
#include "shadows/settings_rows.h"

namespace penumbra::shadows {
namespace {

const Setting<EvsmParams> kTable[] = {
    PENUMBRA_RADIUS_ROWS(EvsmParams, "box-blur radius of the moments"),
    PENUMBRA_CHOICE(EvsmParams, format, MomentFormat, rows::kMomentFormats, "storage of the four warped moments"),
    PENUMBRA_REAL(EvsmParams, positive_exponent, "", 0, 42, "c+ of exp(c+ x); clamped to 42 (rgba32f) or 5.54 (rgba16f)"),
    PENUMBRA_REAL(EvsmParams, negative_exponent, "", 0, 42, "c- of -exp(-c- x); clamped like c+"),
    PENUMBRA_REAL(EvsmParams, min_variance, "depth^2", 0, 1, "variance floor before the warp"),
    PENUMBRA_REAL(EvsmParams, bleed_reduction, "", 0, 0.999, "light-bleeding reduction threshold"),
};

}  // namespace

std::span<const Setting<EvsmParams>> settings_table(const EvsmParams*) { return kTable; }

float evsm_exponent_limit(MomentFormat format) { return format == MomentFormat::rgba16f ? 5.54f : 42.0f; }

glm::vec2 evsm_exponents(const EvsmParams& p) {
  const float limit = evsm_exponent_limit(p.format);
  return {std::clamp(p.positive_exponent, 0.0f, limit), std::clamp(p.negative_exponent, 0.0f, limit)};
}

MomentsLayout evsm_layout(const EvsmParams& p) {
  // The far plane x = 1: (e^c+, e^2c+, -e^-c-, e^-2c-), as evsm_moments(1) in the shader.
  const glm::vec2 c = evsm_exponents(p);
  const float pos = std::exp(c.x), neg = -std::exp(-c.y);
  return {p.format == MomentFormat::rgba16f ? MomentsFormat::rgba16f : MomentsFormat::rgba32f,
          {pos, pos * pos, neg, neg * neg},
          /*direct_sums=*/true};
}

const TechniqueEntry& evsm_technique() {
  static const TechniqueEntry entry{
      .name = "evsm",
      .define = "TECHNIQUE_EVSM",
      .radius = RadiusReading::fixed_filter,
      .pages = PageReading::none,
      .filter_radius = section_radius<&ShadowSettings::evsm>,
      .set_filter_radius = set_section_radius<&ShadowSettings::evsm>,
      .moments = [](const ShadowSettings& s) { return std::optional<MomentsLayout>(evsm_layout(s.evsm)); },
      // The exponents serve the moments pass and the shading pass alike.
      .set_uniforms =
          [](const gl::Program& p, const ShadowSettings& s) {
            p.set("u_evsm_exponents", evsm_exponents(s.evsm));
            p.set("u_evsm_min_variance", s.evsm.min_variance);
            p.set("u_evsm_bleed_reduction", s.evsm.bleed_reduction);
          },
  };
  return entry;
}

}  // namespace penumbra::shadows
