// The C++/GLSL contract (renderer/shaders/shadow_contract.h), checked against what the driver
// compiled: every member of the std140 ShadowFrame block sits at the offset the C++ struct puts it,
// no member is missing from either side, the block's size and binding agree, the samplers sit on
// the contract's units, and the renderer's link-time check refuses a block that disagrees.
#include <cstddef>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "gl/shader_library.h"
#include "shadows/contract.h"
#include "shadows/settings.h"
#include "shadows/technique.h"

namespace penumbra::shadows {
namespace {

using contract::ShadowFrame;

#define MEMBER(name, glsl_name) {glsl_name, offsetof(ShadowFrame, name)}
const std::map<std::string, std::size_t> kMembers = {
    MEMBER(u_view_projection, "u_view_projection"),
    MEMBER(u_camera_view, "u_camera_view"),
    MEMBER(u_light_view, "u_light_view"),
    MEMBER(u_cascade_view_projection, "u_cascade_view_projection[0]"),
    MEMBER(u_cascade_region, "u_cascade_region[0]"),
    MEMBER(u_cascade_res, "u_cascade_res"),
    MEMBER(u_cascade_extent_ws, "u_cascade_extent_ws"),
    MEMBER(u_cascade_far_ws, "u_cascade_far_ws"),
    MEMBER(u_light_direction, "u_light_direction"),
    MEMBER(u_light_near_ws, "u_light_near_ws"),
    MEMBER(u_light_position, "u_light_position"),
    MEMBER(u_light_far_ws, "u_light_far_ws"),
    MEMBER(u_light_color, "u_light_color"),
    MEMBER(u_light_s_xy, "u_light_s_xy"),
    MEMBER(u_camera_position, "u_camera_position"),
    MEMBER(u_light_tan_half_fov, "u_light_tan_half_fov"),
    MEMBER(u_camera_forward, "u_camera_forward"),
    MEMBER(u_rpdb_max, "u_rpdb_max"),
    MEMBER(u_spot_cos_outer, "u_spot_cos_outer"),
    MEMBER(u_spot_cos_inner, "u_spot_cos_inner"),
    MEMBER(u_ambient, "u_ambient"),
    MEMBER(u_normal_offset_texels, "u_normal_offset_texels"),
    MEMBER(u_depth_bias_texels, "u_depth_bias_texels"),
    MEMBER(u_cascade_blend, "u_cascade_blend"),
    MEMBER(u_filter_radius, "u_filter_radius"),
    MEMBER(u_cascade_count, "u_cascade_count"),
    MEMBER(u_light_perspective, "u_light_perspective"),
    MEMBER(u_receiver_plane_bias, "u_receiver_plane_bias"),
    MEMBER(u_filter_radius_world, "u_filter_radius_world"),
    MEMBER(u_show_cascades, "u_show_cascades"),
};
#undef MEMBER

gl::Program shading_program(const gl::ShaderLibrary& lib, std::string_view define) {
  return lib.program({{GL_VERTEX_SHADER, "shading.vert"}, {GL_FRAGMENT_SHADER, "shading.frag"}}, {{std::string(define), "1"}});
}

// Name → offset of every active member of the ShadowFrame block of `program`.
std::map<std::string, GLint> block_offsets(const gl::Program& program) {
  const GLuint block = glGetUniformBlockIndex(program.id(), "ShadowFrame");
  EXPECT_NE(block, GL_INVALID_INDEX);
  GLint count = 0;
  glGetActiveUniformBlockiv(program.id(), block, GL_UNIFORM_BLOCK_ACTIVE_UNIFORMS, &count);
  std::vector<GLint> indices(static_cast<std::size_t>(count));
  glGetActiveUniformBlockiv(program.id(), block, GL_UNIFORM_BLOCK_ACTIVE_UNIFORM_INDICES, indices.data());
  std::map<std::string, GLint> out;
  for (GLint i : indices) {
    const auto u = static_cast<GLuint>(i);
    char name[128] = {};
    glGetActiveUniformName(program.id(), u, sizeof name, nullptr, name);
    GLint offset = -1;
    glGetActiveUniformsiv(program.id(), 1, &u, GL_UNIFORM_OFFSET, &offset);
    out[name] = offset;
  }
  return out;
}

TEST(ShaderContractGl, EveryBlockMemberSitsWhereTheCppStructPutsIt) {
  const gl::ShaderLibrary lib;
  const gl::Program p = shading_program(lib, "TECHNIQUE_PCF");
  const auto offsets = block_offsets(p);
  EXPECT_EQ(offsets.size(), kMembers.size()) << "a member was added on one side only (shadow_contract.h or this test's table)";
  for (const auto& [name, offset] : kMembers) {
    const auto it = offsets.find(name);
    ASSERT_NE(it, offsets.end()) << name << " is not in the GLSL block";
    EXPECT_EQ(static_cast<std::size_t>(it->second), offset) << name;
  }
  GLint size = 0, binding = -1;
  const GLuint block = glGetUniformBlockIndex(p.id(), "ShadowFrame");
  glGetActiveUniformBlockiv(p.id(), block, GL_UNIFORM_BLOCK_DATA_SIZE, &size);
  glGetActiveUniformBlockiv(p.id(), block, GL_UNIFORM_BLOCK_BINDING, &binding);
  EXPECT_EQ(static_cast<std::size_t>(size), sizeof(ShadowFrame));
  EXPECT_EQ(binding, contract::BLOCK_SHADOW_FRAME);
}

TEST(ShaderContractGl, ArraysHoldMaxCascadesAndSamplersSitOnTheirUnits) {
  const gl::ShaderLibrary lib;
  const gl::Program p = shading_program(lib, "TECHNIQUE_VSM");
  const GLuint index = glGetProgramResourceIndex(p.id(), GL_UNIFORM, "u_cascade_view_projection[0]");
  ASSERT_NE(index, GL_INVALID_INDEX);
  const GLenum prop = GL_ARRAY_SIZE;
  GLint size = 0;
  glGetProgramResourceiv(p.id(), GL_UNIFORM, index, 1, &prop, 1, nullptr, &size);
  EXPECT_EQ(size, contract::MAX_CASCADES);
  const std::pair<const char*, int> samplers[] = {{"u_shadow_cmp", contract::UNIT_SHADOW_CMP},
                                                  {"u_shadow_cmp_nearest", contract::UNIT_SHADOW_CMP_NEAREST},
                                                  {"u_shadow_depth", contract::UNIT_SHADOW_DEPTH},
                                                  {"u_moments", contract::UNIT_MOMENTS}};
  for (const auto& [name, unit] : samplers) {
    const GLint loc = p.location(name);
    if (loc < 0) continue;  // not used by this variant
    GLint value = -1;
    glGetUniformiv(p.id(), loc, &value);
    EXPECT_EQ(value, unit) << name;
  }
  GLint moments_unit = -1;
  ASSERT_GE(p.location("u_moments"), 0) << "VSM reads the moments";
  glGetUniformiv(p.id(), p.location("u_moments"), &moments_unit);
  EXPECT_EQ(moments_unit, contract::UNIT_MOMENTS);
}

// Every technique's shading program and, for filtered-moments techniques, its moments program (one
// shadow_moments.frag, the technique's technique_moments()) compile and agree with the contract.
TEST(ShaderContractGl, EveryProgramWithTheBlockPassesTheLinkCheck) {
  const gl::ShaderLibrary lib;
  for (std::size_t i = 0; i < technique_names().size(); ++i) {
    const Technique t = static_cast<Technique>(i);
    const TechniqueEntry& entry = technique_entry(t);
    EXPECT_NO_THROW(check_shadow_frame_block(shading_program(lib, entry.define), entry.name));
    if (entry.moments) {  // the moments pass reads the depth range from the block too
      const gl::Program m = lib.program({{GL_VERTEX_SHADER, "shadow_depth.vert"}, {GL_FRAGMENT_SHADER, "shadow_moments.frag"}},
                                        {{std::string(entry.define), "1"}});
      EXPECT_NO_THROW(check_shadow_frame_block(m, entry.name));
      EXPECT_NE(glGetUniformBlockIndex(m.id(), "ShadowFrame"), GL_INVALID_INDEX) << entry.name;
    }
  }
  for (const char* comp : {"ss_sites.comp", "erosion_search.comp", "edt_penumbra.comp"})
    EXPECT_NO_THROW(check_shadow_frame_block(lib.program({{GL_COMPUTE_SHADER, comp}}), comp));
}

TEST(ShaderContractGl, TheLinkCheckRefusesABlockThatDisagrees) {
  // Same size at another binding point, and the right binding with another size.
  const std::string same_size = "vec4 v[" + std::to_string(sizeof(ShadowFrame) / 16) + "];";
  const gl::ShaderLibrary lib({{"moved.frag", "layout(std140, binding = 3) uniform ShadowFrame { " + same_size +
                                                  " };\nout vec4 o;\nvoid main() { o = v[0]; }\n"},
                               {"short.frag", "layout(std140, binding = 0) uniform ShadowFrame { vec4 u_only; };\n"
                                              "out vec4 o;\nvoid main() { o = u_only; }\n"},
                               {"none.frag", "out vec4 o;\nvoid main() { o = vec4(1.0); }\n"}});
  static_assert(sizeof(ShadowFrame) % 16 == 0);
  EXPECT_THROW(check_shadow_frame_block(lib.program({{GL_FRAGMENT_SHADER, "moved.frag"}}), "moved"), std::runtime_error);
  EXPECT_THROW(check_shadow_frame_block(lib.program({{GL_FRAGMENT_SHADER, "short.frag"}}), "short"), std::runtime_error);
  EXPECT_NO_THROW(check_shadow_frame_block(lib.program({{GL_FRAGMENT_SHADER, "none.frag"}}), "none"));
}

}  // namespace
}  // namespace penumbra::shadows
