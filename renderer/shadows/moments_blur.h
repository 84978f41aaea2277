#pragma once
// The exact box blur of a moments map (shaders/vsm_blur.comp), one square region of an atlas at a
// time: the program's defines, the radius it is given and its two dispatches. The frame's
// `vsm_blur` pass and the test of the blur's work (texel fetches counted by the shader) run this code.
#include <string>
#include <vector>

#include <epoxy/gl.h>
#include <glm/vec2.hpp>

#include <penumbra/gl/objects.h>
#include <penumbra/gl/shader_library.h>
#include <penumbra/shadows/moments.h>

namespace penumbra::shadows {

// The sized GL internal format of a moments texture (the planner's MomentsFormat has no GL in it).
GLenum moments_gl_format(MomentsFormat format);

// The defines of vsm_blur.comp for a layout. `count_fetches` adds a counter of the texels it fetches
// (a uint at offset 0 of the shader storage buffer bound at kBlurFetchCounterBinding): the blur's
// work, which tests bound instead of its time.
std::vector<gl::ShaderDefine> moments_blur_defines(const MomentsLayout& layout, bool count_fetches = false);
inline constexpr GLuint kBlurFetchCounterBinding = 7;

// The radius the shader is given for a filter of `radius_texels` on a map of `map_texels` per side:
// a window wider than the map is cut to the map's width. Beyond it only the edge texels' weights
// would grow (the source clamps to its edge), while a sliding sum's first window would cost r
// fetches (ESM at r = 1e6 texels took 30 s).
float moments_blur_radius_texels(float radius_texels, int map_texels);

// Blurs the size² region of `moments` at `origin` along x into the same region of `scratch`, then
// along y back into `moments`; `blur` is the program built with moments_blur_defines(layout).
void blur_moments_region(const gl::Program& blur, const MomentsLayout& layout, const gl::Texture& moments, const gl::Texture& scratch,
                         glm::ivec2 origin, int size, float radius_texels);

}  // namespace penumbra::shadows
