#pragma once
// What a filtered-moments technique (VSM, MSM, EVSM, ...) tells the frame: the texture format of
// its moments and the moments of the far plane (the clear value, so that texels no caster covers
// read as "nothing in front"). The frame draws them in the `shadow_map` pass with
// shadow_moments.frag, which writes the technique_moments() of the technique's shadow_<name>.glsl,
// and box-blurs them in `vsm_blur` (shaders/vsm_blur.comp), whatever the format.
// GL-free: the frame planner and its tests include it without GL (the GL format: passes.cpp).
#include <array>

namespace penumbra::shadows {

// The moments texture's storage (a sized GL internal format of the same name).
enum class MomentsFormat { r32f, rg32f, rgba16f, rgba32f };

struct MomentsLayout {
  MomentsFormat format = MomentsFormat::rg32f;
  std::array<float, 4> far_moments{};
  // Blur by summing each texel's window anew (cost proportional to the radius) instead of the
  // radius-independent sliding window, whose rounding error follows the largest moment in a line.
  bool direct_sums = false;
};

// Channels of a moments format (1, 2 or 4) and its GLSL image-format qualifier ("rgba16f", ...).
int channel_count(MomentsFormat format);
// Bytes a texel of the format takes (4 per channel, 2 for rgba16f's).
int bytes_per_texel(MomentsFormat format);
const char* image_format_qualifier(MomentsFormat format);

}  // namespace penumbra::shadows
