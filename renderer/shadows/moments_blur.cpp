#include "shadows/moments_blur.h"

#include <algorithm>

namespace penumbra::shadows {

GLenum moments_gl_format(MomentsFormat format) {
  switch (format) {
    case MomentsFormat::r32f: return GL_R32F;
    case MomentsFormat::rg32f: return GL_RG32F;
    case MomentsFormat::rgba16f: return GL_RGBA16F;
    case MomentsFormat::rgba32f: return GL_RGBA32F;
  }
  return GL_RGBA32F;
}

std::vector<gl::ShaderDefine> moments_blur_defines(const MomentsLayout& layout, bool count_fetches) {
  std::vector<gl::ShaderDefine> defines = {{"MOMENTS_CHANNELS", std::to_string(channel_count(layout.format))},
                                           {"MOMENTS_FORMAT", image_format_qualifier(layout.format)}};
  if (layout.direct_sums) defines.push_back({"DIRECT_SUMS", "1"});
  if (count_fetches) defines.push_back({"COUNT_FETCHES_BINDING", std::to_string(kBlurFetchCounterBinding)});
  return defines;
}

float moments_blur_radius_texels(float radius_texels, int map_texels) { return std::min(radius_texels, static_cast<float>(map_texels)); }

void blur_moments_region(const gl::Program& blur, const MomentsLayout& layout, const gl::Texture& moments, const gl::Texture& scratch,
                         glm::ivec2 origin, int size, float radius_texels) {
  blur.use();
  glBindSampler(0, 0);
  blur.set("u_radius_texels", radius_texels);
  blur.set("u_origin", origin);
  blur.set("u_size", size);
  // Sliding sums: one invocation per line (x); direct sums: one per texel, x along the line and
  // y the line (vsm_blur.comp). The region is square, so both grids are size x (1 or size).
  const int lines_y = layout.direct_sums ? size : 1;
  const GLuint source = blur.binding("u_source"), target = blur.binding("u_target");
  const GLenum format = moments_gl_format(layout.format);
  const gl::Texture* from[2] = {&moments, &scratch};
  const gl::Texture* to[2] = {&scratch, &moments};
  for (int axis = 0; axis < 2; ++axis) {
    blur.set("u_axis", axis);
    from[axis]->bind(source);
    glBindImageTexture(target, to[axis]->id(), 0, GL_FALSE, 0, GL_WRITE_ONLY, format);
    blur.dispatch_covering(size, lines_y);
    glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
  }
}

}  // namespace penumbra::shadows
