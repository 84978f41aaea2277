// The C++/GLSL contract (renderer/shaders/shadow_contract.h, and the virtual shadow map's
// virtual_mark_contract.h), checked against what the driver compiled: every member of the std140
// ShadowFrame and VirtualFrame blocks sits at the offset the C++ struct puts it, no member is
// missing from either side, the blocks' sizes and bindings agree, the samplers sit on the
// contract's units, the renderer's link-time checks refuse a block that disagrees, and no value of
// the virtual map is a loose uniform again (set by name, a misspelt one dropped silently).
#include <cstddef>
#include <cstring>
#include <map>
#include <regex>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "gl/embedded_files.h"
#include "gl/shader_library.h"
#include "shadows/contract.h"
#include "shadows/settings.h"
#include "shadows/technique.h"
#include "shadows/virtual_shadow_map.h"

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

using virtual_mark::VirtualFrame;
#define MEMBER(name, glsl_name) {glsl_name, offsetof(VirtualFrame, name)}
const std::map<std::string, std::size_t> kVirtualMembers = {
    MEMBER(u_virtual_light_view, "u_virtual_light_view"),
    MEMBER(u_virtual_origin, "u_virtual_origin[0]"),
    MEMBER(u_mark_camera_position, "u_mark_camera_position"),
    MEMBER(u_mark_footprint_per_depth, "u_mark_footprint_per_depth"),
    MEMBER(u_mark_camera_forward, "u_mark_camera_forward"),
    MEMBER(u_mark_c_texels, "u_mark_c_texels"),
    MEMBER(u_mark_min_texel_px, "u_mark_min_texel_px"),
    MEMBER(u_mark_reach_texels, "u_mark_reach_texels"),
    MEMBER(u_virtual_texel0_ws, "u_virtual_texel0_ws"),
    MEMBER(u_virtual_page_texels, "u_virtual_page_texels"),
    MEMBER(u_virtual_pages_per_side, "u_virtual_pages_per_side"),
    MEMBER(u_virtual_levels, "u_virtual_levels"),
    MEMBER(u_virtual_pool_pages, "u_virtual_pool_pages"),
    MEMBER(u_virtual_near_ws, "u_virtual_near_ws"),
    MEMBER(u_virtual_far_ws, "u_virtual_far_ws"),
    MEMBER(u_virtual_tan_half_angle, "u_virtual_tan_half_angle"),
    MEMBER(u_virtual_search_scale, "u_virtual_search_scale"),
    MEMBER(u_virtual_min_penumbra_ws, "u_virtual_min_penumbra_ws"),
    MEMBER(u_virtual_search_bias_texels, "u_virtual_search_bias_texels"),
    MEMBER(u_virtual_bounds, "u_virtual_bounds"),
    MEMBER(u_virtual_search_receiver_plane, "u_virtual_search_receiver_plane"),
    MEMBER(u_mark_perspective, "u_mark_perspective"),
    MEMBER(u_mark_footprint_only, "u_mark_footprint_only"),
};
#undef MEMBER

gl::Program shading_program(const gl::ShaderLibrary& lib, std::string_view define) {
  return lib.program({{GL_VERTEX_SHADER, "shading.vert"}, {GL_FRAGMENT_SHADER, "shading.frag"}}, {{std::string(define), "1"}});
}

// The shading pass through the sun's virtual shadow map for technique `entry`.
gl::Program virtual_shading_program(const gl::ShaderLibrary& lib, const TechniqueEntry& entry) {
  return lib.program({{GL_VERTEX_SHADER, "shading.vert"}, {GL_FRAGMENT_SHADER, "shading.frag"}},
                     {{std::string(entry.define), "1"}, {"VIRTUAL_SHADOW_MAP", "1"}});
}

// Every program that reads the virtual map's frame: the shading through pages of each technique
// the registry says reads them, the marking's three passes and the tiles' bounds.
std::vector<std::pair<std::string, gl::Program>> virtual_programs(const gl::ShaderLibrary& lib) {
  std::vector<std::pair<std::string, gl::Program>> out;
  for (std::size_t i = 0; i < technique_names().size(); ++i) {
    const TechniqueEntry& entry = technique_entry(static_cast<Technique>(i));
    if (entry.pages != PageReading::none) out.emplace_back("shading.frag " + std::string(entry.name), virtual_shading_program(lib, entry));
  }
  for (int pass = 0; pass < 3; ++pass)
    out.emplace_back("virtual_mark.comp pass " + std::to_string(pass),
                     lib.program({{GL_COMPUTE_SHADER, "virtual_mark.comp"}}, {{"VIRTUAL_MARK_PASS", std::to_string(pass)}}));
  out.emplace_back("virtual_bounds.comp", lib.program({{GL_COMPUTE_SHADER, "virtual_bounds.comp"}}));
  return out;
}

// Name → offset of every active member of block `block_name` of `program`.
std::map<std::string, GLint> block_offsets(const gl::Program& program, const char* block_name = "ShadowFrame") {
  const GLuint block = glGetUniformBlockIndex(program.id(), block_name);
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

TEST(ShaderContractGl, EveryVirtualFrameMemberSitsWhereTheCppStructPutsIt) {
  const gl::ShaderLibrary lib;
  const auto programs = virtual_programs(lib);
  ASSERT_GE(programs.size(), 7u) << "PCF, PCSS and VSM read pages, three marking passes, the bounds";
  for (const auto& [what, p] : programs) {
    SCOPED_TRACE(what);
    const GLuint block = glGetUniformBlockIndex(p.id(), "VirtualFrame");
    ASSERT_NE(block, GL_INVALID_INDEX);
    const auto offsets = block_offsets(p, "VirtualFrame");
    EXPECT_EQ(offsets.size(), kVirtualMembers.size()) << "a member was added on one side only (virtual_mark_contract.h or this test's table)";
    for (const auto& [name, offset] : kVirtualMembers) {
      const auto it = offsets.find(name);
      ASSERT_NE(it, offsets.end()) << name << " is not in the GLSL block";
      EXPECT_EQ(static_cast<std::size_t>(it->second), offset) << name;
    }
    GLint size = 0, binding = -1;
    glGetActiveUniformBlockiv(p.id(), block, GL_UNIFORM_BLOCK_DATA_SIZE, &size);
    glGetActiveUniformBlockiv(p.id(), block, GL_UNIFORM_BLOCK_BINDING, &binding);
    EXPECT_EQ(static_cast<std::size_t>(size), sizeof(VirtualFrame));
    EXPECT_EQ(binding, contract::BLOCK_VIRTUAL_FRAME);
    EXPECT_NO_THROW(check_virtual_frame_block(p, what));
  }
  // One origin a level.
  const GLuint index = glGetProgramResourceIndex(programs.front().second.id(), GL_UNIFORM, "u_virtual_origin[0]");
  ASSERT_NE(index, GL_INVALID_INDEX);
  const GLenum props[] = {GL_ARRAY_SIZE, GL_ARRAY_STRIDE};
  GLint values[2] = {};
  glGetProgramResourceiv(programs.front().second.id(), GL_UNIFORM, index, 2, props, 2, nullptr, values);
  EXPECT_EQ(values[0], contract::VIRTUAL_MAX_LEVELS);
  EXPECT_EQ(values[1], 16);
}

// The bytes of the uniform buffer bound at BLOCK_VIRTUAL_FRAME.
std::vector<unsigned char> bound_virtual_frame() {
  GLint buffer = 0;
  glGetIntegeri_v(GL_UNIFORM_BUFFER_BINDING, contract::BLOCK_VIRTUAL_FRAME, &buffer);
  std::vector<unsigned char> bytes(sizeof(VirtualFrame));
  if (buffer == 0) return {};
  glGetNamedBufferSubData(static_cast<GLuint>(buffer), 0, static_cast<GLsizeiptr>(bytes.size()), bytes.data());
  return bytes;
}

bool same_bytes(const std::vector<unsigned char>& bytes, const VirtualFrame& frame) {
  return bytes.size() == sizeof frame && std::memcmp(bytes.data(), &frame, sizeof frame) == 0;
}

// The frame is written once while it stays the same (bind() again writes nothing) and again when it
// changes; the buffer bound is the one written, and it holds the struct's bytes.
TEST(ShaderContractGl, TheVirtualFrameBufferHoldsTheFrameAndWritesOnlyAChange) {
  adaptive::VirtualMapLayout layout;
  layout.levels = 5;
  VirtualMapView view;
  view.light_view = sun_light_view(glm::normalize(glm::vec3(-0.3f, -1.0f, -0.5f)));
  view.near_ws = 2, view.far_ws = 90;
  view.camera_xy = {12.5, -3.25};
  VirtualFrame frame{};
  set_virtual_view(frame, layout, view);
  EXPECT_EQ(frame.u_virtual_levels, 5);
  EXPECT_EQ(frame.u_virtual_light_view.columns[2][0], view.light_view[2][0]);  // column-major, as glm
  const adaptive::LightXY o = adaptive::level_origin(3, view.camera_xy, layout);
  EXPECT_EQ(frame.u_virtual_origin[3].x, static_cast<float>(o.x));
  EXPECT_EQ(frame.u_virtual_origin[3].y, static_cast<float>(o.y));
  EXPECT_EQ(frame.u_virtual_origin[5].x, 0.0f) << "no level 5";

  const VirtualFrameBuffer buffer;
  buffer.bind(frame);
  EXPECT_EQ(buffer.writes(), 1);
  EXPECT_TRUE(same_bytes(bound_virtual_frame(), frame));
  buffer.bind(frame);
  EXPECT_EQ(buffer.writes(), 1) << "an unchanged frame is not written again";
  frame.u_mark_c_texels = 3.47f;
  buffer.bind(frame);
  EXPECT_EQ(buffer.writes(), 2);
  EXPECT_TRUE(same_bytes(bound_virtual_frame(), frame));
  const VirtualFrameBuffer other;
  VirtualFrame zero{};
  other.bind(zero);
  EXPECT_TRUE(same_bytes(bound_virtual_frame(), zero)) << "the last bound buffer is the one read";
  EXPECT_EQ(glGetError(), static_cast<GLenum>(GL_NO_ERROR));
}

// The shape cannot drift back: no program that reads the virtual map has an active u_virtual_* or
// u_mark_* uniform outside a block but its samplers, and no shader declares one.
TEST(ShaderContractGl, TheVirtualMapHasNoLooseUniforms) {
  const gl::ShaderLibrary lib;
  for (const auto& [what, p] : virtual_programs(lib)) {
    SCOPED_TRACE(what);
    GLint count = 0;
    glGetProgramiv(p.id(), GL_ACTIVE_UNIFORMS, &count);
    int in_block = 0;
    for (GLuint u = 0; u < static_cast<GLuint>(count); ++u) {
      char name[128] = {};
      GLint block = -1, type = 0;
      glGetActiveUniformName(p.id(), u, sizeof name, nullptr, name);
      glGetActiveUniformsiv(p.id(), 1, &u, GL_UNIFORM_BLOCK_INDEX, &block);
      glGetActiveUniformsiv(p.id(), 1, &u, GL_UNIFORM_TYPE, &type);
      const std::string n = name;
      if (n.rfind("u_virtual_", 0) != 0 && n.rfind("u_mark_", 0) != 0) continue;
      in_block += block != -1;
      const bool opaque = type == GL_SAMPLER_2D || type == GL_INT_SAMPLER_2D || type == GL_SAMPLER_2D_SHADOW;
      EXPECT_TRUE(block != -1 || opaque) << n << " is a loose uniform: put it in the VirtualFrame block (virtual_mark_contract.h)";
    }
    EXPECT_EQ(in_block, static_cast<int>(kVirtualMembers.size()));
  }
  // Declared and unused, a loose uniform is not active: read the sources too.
  const std::regex loose(R"(uniform\s+(?!sampler|isampler|usampler|image|iimage|uimage)\w+\s+(u_(?:virtual|mark)_\w+))");
  int files = 0;
  for (const auto& f : embedded::shaders()) {
    const std::string text(f.text);
    ++files;
    for (std::sregex_iterator it(text.begin(), text.end(), loose), end; it != end; ++it)
      ADD_FAILURE() << f.name << " declares " << (*it)[1] << " as a loose uniform: put it in the VirtualFrame block";
  }
  EXPECT_GT(files, 20);
  // The pattern does find one.
  const std::string planted = "uniform float u_virtual_texel0_ws;\nlayout(binding = 9) uniform sampler2D u_virtual_pool;\n";
  EXPECT_EQ(std::distance(std::sregex_iterator(planted.begin(), planted.end(), loose), std::sregex_iterator()), 1);
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
  // The VirtualFrame block likewise.
  const std::string virtual_size = "vec4 v[" + std::to_string(sizeof(VirtualFrame) / 16) + "];";
  const gl::ShaderLibrary vlib({{"moved.frag", "layout(std140, binding = 0) uniform VirtualFrame { " + virtual_size +
                                                   " };\nout vec4 o;\nvoid main() { o = v[0]; }\n"},
                                {"short.frag", "layout(std140, binding = 1) uniform VirtualFrame { vec4 u_only; };\n"
                                               "out vec4 o;\nvoid main() { o = u_only; }\n"},
                                {"right.frag", "layout(std140, binding = 1) uniform VirtualFrame { " + virtual_size +
                                                   " };\nout vec4 o;\nvoid main() { o = v[0]; }\n"}});
  static_assert(sizeof(VirtualFrame) % 16 == 0);
  EXPECT_THROW(check_virtual_frame_block(vlib.program({{GL_FRAGMENT_SHADER, "moved.frag"}}), "moved"), std::runtime_error);
  EXPECT_THROW(check_virtual_frame_block(vlib.program({{GL_FRAGMENT_SHADER, "short.frag"}}), "short"), std::runtime_error);
  EXPECT_NO_THROW(check_virtual_frame_block(vlib.program({{GL_FRAGMENT_SHADER, "right.frag"}}), "right"));
}

}  // namespace
}  // namespace penumbra::shadows
