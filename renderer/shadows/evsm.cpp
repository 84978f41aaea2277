#include "shadows/evsm.h"

#include <algorithm>
#include <cmath>

namespace penumbra::shadows {

float evsm_exponent_limit(MomentFormat format) { return format == MomentFormat::rgba16f ? 5.54f : 42.0f; }

glm::vec2 evsm_exponents(const EvsmParams& p) {
  const float limit = evsm_exponent_limit(p.format);
  return {std::clamp(p.positive_exponent, 0.0f, limit), std::clamp(p.negative_exponent, 0.0f, limit)};
}

MomentsLayout evsm_layout(const EvsmParams& p) {
  // The far plane x = 1: (e^c+, e^2c+, -e^-c-, e^-2c-), as evsm_moments(1) in the shader.
  const glm::vec2 c = evsm_exponents(p);
  const float pos = std::exp(c.x), neg = -std::exp(-c.y);
  return {p.format == MomentFormat::rgba16f ? static_cast<GLenum>(GL_RGBA16F) : static_cast<GLenum>(GL_RGBA32F),
          "shadow_evsm_moments.frag",
          {pos, pos * pos, neg, neg * neg},
          /*direct_sums=*/true};
}

void set_evsm_uniforms(const gl::Program& program, const EvsmParams& p) {
  const glm::vec2 c = evsm_exponents(p);
  glProgramUniform2f(program.id(), program.location("u_evsm_exponents"), c.x, c.y);
  glProgramUniform1f(program.id(), program.location("u_evsm_min_variance"), p.min_variance);
  glProgramUniform1f(program.id(), program.location("u_evsm_bleed_reduction"), p.bleed_reduction);
}

}  // namespace penumbra::shadows
