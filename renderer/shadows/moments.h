#pragma once
// What a filtered-moments technique (VSM, MSM, EVSM, ...) tells the frame: the texture format of
// its moments and the moments of the far plane (the clear value, so that texels no caster covers
// read as "nothing in front"). The frame draws them in the `shadow_map` pass with
// shadow_moments.frag, which writes the technique_moments() of the technique's shadow_<name>.glsl,
// and box-blurs them in `vsm_blur` (shaders/vsm_blur.comp), whatever the format.
#include <epoxy/gl.h>

#include <array>

namespace penumbra::shadows {

struct MomentsLayout {
  GLenum format = GL_RG32F;  // sized internal format: GL_R32F, GL_RG32F, GL_RGBA32F or GL_RGBA16F
  std::array<float, 4> far_moments{};
  // Blur by summing each texel's window anew (cost proportional to the radius) instead of the
  // radius-independent sliding window, whose rounding error follows the largest moment in a line.
  bool direct_sums = false;
};

// Channels of a moments format (1, 2 or 4) and its GLSL image-format qualifier ("rgba16f", ...).
int channel_count(GLenum format);
const char* image_format_qualifier(GLenum format);

}  // namespace penumbra::shadows
