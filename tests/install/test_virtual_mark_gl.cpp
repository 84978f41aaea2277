// The page marking Penumbra installs for engines (share/penumbra/shaders/virtual_mark.comp, written
// by cmake/Install.cmake into build/install/shaders/ and compiled into this binary), used as an
// engine would use it, through raw GL calls and nothing of Penumbra's shader loading:
//   - it compiles alone on the driver for each VIRTUAL_MARK_PASS with `#version 450 core` and the
//     define before it (no #include left to expand);
//   - the driver's work-group size, image units, storage binding, marks-buffer offsets, texture
//     units and VirtualFrame block (binding, size) equal <penumbra/shaders/virtual_mark_contract.h>,
//     whose numbers equal the renderer's shaders/shadow_contract.h, and the frame's values are in
//     the block, not in loose uniforms;
//   - dispatched with the block filled as docs/virtual-pages-in-your-engine.md says, on a ground
//     plane seen in perspective, it marks the pages adaptive::mark_pages marks on the CPU (decoded
//     with the contract's virtual_mark_page_of_bit), by the rule and by the footprint.
#include <gtest/gtest.h>

#include <epoxy/gl.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <iterator>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include <penumbra/shaders/virtual_mark_contract.h>

#include "adaptive/virtual_pages.h"
#include "gl/embedded_files.h"
#include "shaders/shadow_contract.h"
#include "shadows/virtual_shadow_map.h"

namespace penumbra {
namespace embedded {
std::span<const EmbeddedFile> installed_shaders();  // (cmake/EmbedFiles.cmake)
}  // namespace embedded
namespace {

namespace vm = shadows::virtual_mark;
namespace contract = shadows::contract;

// share/penumbra/shaders/virtual_mark.comp as the build writes it (build/install/shaders/),
// compiled into this binary (tests/install/CMakeLists.txt).
std::string installed_text() {
  for (const embedded::EmbeddedFile& f : embedded::installed_shaders())
    if (f.name == "virtual_mark.comp") return std::string(f.text);
  ADD_FAILURE() << "virtual_mark.comp is not embedded";
  return "";
}

// A compute program of the installed text, with only what an engine puts before it.
struct RawProgram {
  GLuint id = 0;
  std::string log;
  // The installed file as an engine compiles it: its own #version and the pass's define first.
  explicit RawProgram(int pass)
      : RawProgram("#version 450 core\n#define VIRTUAL_MARK_PASS " + std::to_string(pass) + "\n" + installed_text()) {}
  explicit RawProgram(const std::string& text) {
    const char* source = text.c_str();
    const GLuint shader = glCreateShader(GL_COMPUTE_SHADER);
    glShaderSource(shader, 1, &source, nullptr);
    glCompileShader(shader);
    GLint ok = 0;
    glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
    char buffer[8192] = {};
    if (!ok) {
      glGetShaderInfoLog(shader, sizeof buffer, nullptr, buffer);
      log = std::string("compile: ") + buffer;
      glDeleteShader(shader);
      return;
    }
    id = glCreateProgram();
    glAttachShader(id, shader);
    glLinkProgram(id);
    glDeleteShader(shader);
    glGetProgramiv(id, GL_LINK_STATUS, &ok);
    if (!ok) {
      glGetProgramInfoLog(id, sizeof buffer, nullptr, buffer);
      log = std::string("link: ") + buffer;
      glDeleteProgram(id);
      id = 0;
    }
  }
  ~RawProgram() {
    if (id) glDeleteProgram(id);
  }
  RawProgram(const RawProgram&) = delete;
  RawProgram& operator=(const RawProgram&) = delete;

  GLint location(const char* name) const { return glGetUniformLocation(id, name); }
  // The value a sampler or image uniform holds after linking: its layout(binding = ...).
  GLint unit_of(const char* name) const {
    GLint v = -1;
    glGetUniformiv(id, location(name), &v);
    return v;
  }
  // A buffer variable's property (GL_OFFSET, GL_ARRAY_SIZE, GL_ARRAY_STRIDE); -1 when not active.
  GLint buffer_variable(const char* name, GLenum property) const {
    const GLuint index = glGetProgramResourceIndex(id, GL_BUFFER_VARIABLE, name);
    if (index == GL_INVALID_INDEX) return -1;
    GLint v = -1;
    glGetProgramResourceiv(id, GL_BUFFER_VARIABLE, index, 1, &property, 1, nullptr, &v);
    return v;
  }
};

TEST(InstalledVirtualMark, IsSelfContainedAndCompilesAloneForEveryPass) {
  const std::string text = installed_text();
  ASSERT_GT(text.size(), 1000u);
  std::istringstream lines(text);
  for (std::string line; std::getline(lines, line);) {
    const auto first = line.find_first_not_of(" \t");
    if (first == std::string::npos || line[first] != '#') continue;
    const std::string directive = line.substr(first);
    EXPECT_EQ(directive.rfind("#version", 0), std::string::npos) << "an engine puts its own #version first: " << line;
    // Angle-bracket includes are C++'s, under #ifdef __cplusplus; a quoted one would need Penumbra's loader.
    EXPECT_EQ(directive.find("include \""), std::string::npos) << "not inlined: " << line;
  }
  for (int pass = 0; pass < 3; ++pass) {
    SCOPED_TRACE("VIRTUAL_MARK_PASS " + std::to_string(pass));
    const RawProgram p(pass);
    EXPECT_NE(p.id, 0u) << p.log;
  }
  // Without the define it refuses to compile, naming it.
  const RawProgram without("#version 450 core\n" + text);
  EXPECT_EQ(without.id, 0u);
  EXPECT_EQ(without.log.rfind("compile: ", 0), 0u) << without.log;
  EXPECT_NE(without.log.find("VIRTUAL_MARK_PASS"), std::string::npos) << without.log;
}

TEST(InstalledVirtualMark, TheDriverSeesTheContractsBindingsAndBufferLayout) {
  // The contract's numbers are the renderer's.
  EXPECT_EQ(vm::VIRTUAL_MARK_MAX_LEVELS, contract::VIRTUAL_MAX_LEVELS);
  EXPECT_EQ(vm::VIRTUAL_UNIT_POOL, contract::UNIT_VIRTUAL_POOL);
  EXPECT_EQ(vm::VIRTUAL_UNIT_TABLE, contract::UNIT_VIRTUAL_TABLE);
  EXPECT_EQ(vm::VIRTUAL_UNIT_BOUNDS, contract::UNIT_VIRTUAL_BOUNDS);
  EXPECT_EQ(vm::VIRTUAL_FRAME_BLOCK, contract::BLOCK_VIRTUAL_FRAME);
  // The bit of a page and back, over a window of 5² pages.
  for (int level = 0; level < 3; ++level)
    for (int y = 0; y < 5; ++y)
      for (int x = 0; x < 5; ++x) {
        const vm::Page p = vm::virtual_mark_page_of_bit(vm::virtual_mark_page_bit(level, x, y, 5), 5);
        EXPECT_TRUE(p.level == level && p.x == x && p.y == y) << level << " " << x << " " << y;
      }
  EXPECT_EQ(vm::virtual_mark_page_bit_words(12, 64), 12u * 64 * 64 / 32);
  EXPECT_EQ(vm::virtual_mark_buffer_words(12, 64), static_cast<std::size_t>(vm::VIRTUAL_MARK_WORD_PAGE_BITS) + 12 * 64 * 64 / 32 + 2 * 12 * 64 * 64)
      << "the counts, a bit per page, then two tile words per page";
  EXPECT_EQ(vm::virtual_mark_tile_word(0, 0, 12, 64), 12u * 64 * 64 / 32);
  EXPECT_EQ(vm::virtual_mark_tile_word(5, 4, 12, 64), 12u * 64 * 64 / 32 + 11) << "page 5's upper four tile rows";

  for (int pass = 0; pass < 3; ++pass) {
    SCOPED_TRACE("VIRTUAL_MARK_PASS " + std::to_string(pass));
    const RawProgram p(pass);
    ASSERT_NE(p.id, 0u) << p.log;
    GLint group[3] = {};
    glGetProgramiv(p.id, GL_COMPUTE_WORK_GROUP_SIZE, group);
    EXPECT_EQ(group[0], vm::VIRTUAL_MARK_GROUP_SIZE);
    EXPECT_EQ(group[1], vm::VIRTUAL_MARK_GROUP_SIZE);
    EXPECT_EQ(group[2], 1);

    const GLuint block = glGetProgramResourceIndex(p.id, GL_SHADER_STORAGE_BLOCK, "Marks");
    ASSERT_NE(block, GL_INVALID_INDEX);
    const GLenum binding_property = GL_BUFFER_BINDING;
    GLint binding = -1;
    glGetProgramResourceiv(p.id, GL_SHADER_STORAGE_BLOCK, block, 1, &binding_property, 1, nullptr, &binding);
    EXPECT_EQ(binding, vm::VIRTUAL_MARK_BUFFER);
    constexpr int word = 4;
    EXPECT_EQ(p.buffer_variable("u_pixels_per_level[0]", GL_OFFSET), vm::VIRTUAL_MARK_WORD_PIXELS_PER_LEVEL * word);
    EXPECT_EQ(p.buffer_variable("u_pixels_per_level[0]", GL_ARRAY_SIZE), vm::VIRTUAL_MARK_MAX_LEVELS);
    EXPECT_EQ(p.buffer_variable("u_pixels_per_level[0]", GL_ARRAY_STRIDE), word);
    EXPECT_EQ(p.buffer_variable("u_unmarked", GL_OFFSET), vm::VIRTUAL_MARK_WORD_UNMARKED * word);
    EXPECT_EQ(p.buffer_variable("u_page_bits[0]", GL_OFFSET), vm::VIRTUAL_MARK_WORD_PAGE_BITS * word);
    EXPECT_EQ(p.buffer_variable("u_page_bits[0]", GL_ARRAY_STRIDE), word);

    const GLuint frame = glGetUniformBlockIndex(p.id, "VirtualFrame");
    ASSERT_NE(frame, GL_INVALID_INDEX);
    GLint frame_size = 0, frame_binding = -1;
    glGetActiveUniformBlockiv(p.id, frame, GL_UNIFORM_BLOCK_DATA_SIZE, &frame_size);
    glGetActiveUniformBlockiv(p.id, frame, GL_UNIFORM_BLOCK_BINDING, &frame_binding);
    EXPECT_EQ(frame_size, static_cast<GLint>(sizeof(vm::VirtualFrame)));
    EXPECT_EQ(frame_binding, vm::VIRTUAL_FRAME_BLOCK);
    // Outside the block the shader has only what differs between dispatches, and its samplers and images.
    GLint count = 0;
    glGetProgramiv(p.id, GL_ACTIVE_UNIFORMS, &count);
    std::set<std::string> loose;
    for (GLuint u = 0; u < static_cast<GLuint>(count); ++u) {
      char name[128] = {};
      GLint in_block = -1, type = 0;
      glGetActiveUniformName(p.id, u, sizeof name, nullptr, name);
      glGetActiveUniformsiv(p.id, 1, &u, GL_UNIFORM_BLOCK_INDEX, &in_block);
      glGetActiveUniformsiv(p.id, 1, &u, GL_UNIFORM_TYPE, &type);
      const bool opaque = type == GL_SAMPLER_2D || type == GL_INT_SAMPLER_2D || type == GL_IMAGE_2D;
      if (in_block == -1 && !opaque) loose.insert(name);
    }
    for (const std::string& name : loose)
      EXPECT_TRUE(name == "u_radius_ws" || name == "u_write_levels" || name == "u_write_radii") << name << " is a loose uniform";

    EXPECT_EQ(p.unit_of("u_surface"), vm::VIRTUAL_MARK_IMAGE_SURFACE);
    EXPECT_EQ(p.unit_of("u_levels"), vm::VIRTUAL_MARK_IMAGE_LEVELS);
    EXPECT_EQ(p.unit_of("u_radii"), vm::VIRTUAL_MARK_IMAGE_RADII);
    if (pass == 2) {  // the blocker search reads the pages; passes 0 and 1 read no texture
      for (const char* name : {"u_virtual_pool", "u_virtual_table", "u_virtual_tile_bounds"}) ASSERT_NE(p.location(name), -1) << name;
      EXPECT_EQ(p.unit_of("u_virtual_pool"), vm::VIRTUAL_UNIT_POOL);
      EXPECT_EQ(p.unit_of("u_virtual_table"), vm::VIRTUAL_UNIT_TABLE);
      EXPECT_EQ(p.unit_of("u_virtual_tile_bounds"), vm::VIRTUAL_UNIT_BOUNDS);
      EXPECT_EQ(p.location("u_virtual_pool_cmp"), -1) << "the marking now reads the comparison pool: add its unit to the contract";
      EXPECT_EQ(p.location("u_virtual_moments"), -1) << "the marking now reads the moments pool: add its unit to the contract";
    }
  }
}

// A ground plane (y = 0, 40 m square) seen from 3 m up, 8 m back, through a 60° lens: each
// pixel's world point (w = 1), or w = 0 where the ray misses the plane.
struct Ground {
  static constexpr int width = 256, height = 192;
  glm::vec3 eye{0.3f, 3.0f, 8.0f}, target{0.1f, 0.0f, 0.0f};
  float fov_y_rad = glm::radians(60.0f);
  std::vector<float> points = std::vector<float>(4 * static_cast<std::size_t>(width) * height, 0.0f);
  Ground() {
    const glm::vec3 forward = glm::normalize(target - eye);
    const glm::vec3 right = glm::normalize(glm::cross(forward, glm::vec3(0, 1, 0))), up = glm::cross(right, forward);
    const float half_h = std::tan(fov_y_rad / 2), half_w = half_h * width / height;
    for (int y = 0; y < height; ++y)
      for (int x = 0; x < width; ++x) {
        const float u = (2 * (x + 0.5f) / width - 1) * half_w, v = (2 * (y + 0.5f) / height - 1) * half_h;
        const glm::vec3 ray = forward + u * right + v * up;
        if (ray.y >= -1e-4f) continue;
        const glm::vec3 hit = eye + ray * (-eye.y / ray.y);
        if (std::abs(hit.x) > 20 || std::abs(hit.z) > 20) continue;
        float* p = &points[4 * (static_cast<std::size_t>(y) * width + x)];
        p[0] = hit.x, p[1] = hit.y, p[2] = hit.z, p[3] = 1;
      }
  }
  glm::vec3 forward() const { return glm::normalize(target - eye); }
  // A pixel's world size per unit of view depth.
  float footprint_per_depth() const { return 2 * std::tan(fov_y_rad / 2) / height; }
};

TEST(InstalledVirtualMark, MarksThePagesTheCpuReferenceMarks) {
  const Ground ground;
  // 6 levels of 16² pages of 32² texels from 1/64 m: windows of 8 m to 256 m.
  adaptive::VirtualMapLayout layout;
  layout.levels = 6;
  layout.texel0_ws = 1.0 / 64;
  layout.page_texels = 32;
  layout.pages_per_side = 16;
  const glm::mat4 light_view = shadows::sun_light_view(glm::normalize(glm::vec3(-0.3f, -1.0f, -0.5f)));
  const adaptive::LightXY camera_xy = shadows::light_xy(light_view, ground.eye);
  const float radius_ws = 0.2f;

  const RawProgram p(0);
  ASSERT_NE(p.id, 0u) << p.log;
  GLuint surface = 0, marks = 0;
  glCreateTextures(GL_TEXTURE_2D, 1, &surface);
  glTextureStorage2D(surface, 1, GL_RGBA32F, Ground::width, Ground::height);
  glTextureSubImage2D(surface, 0, 0, 0, Ground::width, Ground::height, GL_RGBA, GL_FLOAT, ground.points.data());
  const std::size_t words = vm::virtual_mark_buffer_words(layout.levels, layout.pages_per_side);
  glCreateBuffers(1, &marks);
  glNamedBufferStorage(marks, static_cast<GLsizeiptr>(words * sizeof(std::uint32_t)), nullptr, GL_DYNAMIC_STORAGE_BIT);

  // The VirtualFrame block as docs/virtual-pages-in-your-engine.md fills it, in a uniform buffer of
  // the engine's own; then the dispatch's uniforms by name.
  vm::VirtualFrame frame{};
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) frame.u_virtual_light_view.columns[c][r] = light_view[c][r];  // column-major, as glm and GL
  for (int k = 0; k < layout.levels; ++k) {
    const adaptive::LightXY o = adaptive::level_origin(k, camera_xy, layout);
    frame.u_virtual_origin[k] = {static_cast<float>(o.x), static_cast<float>(o.y), 0, 0};
  }
  frame.u_virtual_texel0_ws = static_cast<float>(layout.texel0_ws);
  frame.u_virtual_page_texels = layout.page_texels;
  frame.u_virtual_pages_per_side = layout.pages_per_side;
  frame.u_virtual_levels = layout.levels;
  frame.u_mark_camera_position = {ground.eye.x, ground.eye.y, ground.eye.z};
  const glm::vec3 forward = ground.forward();
  frame.u_mark_camera_forward = {forward.x, forward.y, forward.z};
  frame.u_mark_perspective = 1;
  frame.u_mark_footprint_per_depth = ground.footprint_per_depth();
  frame.u_mark_min_texel_px = 0.7071f;  // the CPU reference's default (adaptive::MarkOptions)
  GLuint frame_buffer = 0;
  glCreateBuffers(1, &frame_buffer);
  glNamedBufferStorage(frame_buffer, sizeof frame, nullptr, GL_DYNAMIC_STORAGE_BIT);
  glBindBufferBase(GL_UNIFORM_BUFFER, vm::VIRTUAL_FRAME_BLOCK, frame_buffer);
  glProgramUniform1f(p.id, p.location("u_radius_ws"), radius_ws);
  glProgramUniform1i(p.id, p.location("u_write_levels"), 0);
  glProgramUniform1i(p.id, p.location("u_write_radii"), 0);

  // The CPU reference's requests: each surface point's light-space xy and footprint.
  std::vector<adaptive::PixelRequest> requests;
  for (std::size_t i = 0; i < ground.points.size() / 4; ++i) {
    if (ground.points[4 * i + 3] <= 0) continue;
    const glm::vec3 world(ground.points[4 * i], ground.points[4 * i + 1], ground.points[4 * i + 2]);
    const adaptive::LightXY l = shadows::light_xy(light_view, world);
    const double depth = std::max(0.0f, glm::dot(world - ground.eye, forward));
    requests.push_back({l, depth * ground.footprint_per_depth(), radius_ws});
  }
  ASSERT_GT(requests.size(), static_cast<std::size_t>(Ground::width * Ground::height / 3));

  std::set<adaptive::Page> by_rule;
  for (const adaptive::Marking m : {adaptive::Marking::rule, adaptive::Marking::footprint}) {
    SCOPED_TRACE(std::string(adaptive::to_string(m)));
    adaptive::MarkOptions options;
    options.marking = m;
    options.c_texels = 3.47;
    options.reach_texels = 0.75;  // the renderer's normal offset (map.normal_offset_texels)
    frame.u_mark_c_texels = static_cast<float>(options.c_texels);
    frame.u_mark_reach_texels = static_cast<float>(options.reach_texels);
    frame.u_mark_footprint_only = m == adaptive::Marking::footprint;
    glNamedBufferSubData(frame_buffer, 0, sizeof frame, &frame);
    const std::uint32_t zero = 0;
    glClearNamedBufferData(marks, GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, vm::VIRTUAL_MARK_BUFFER, marks);
    glBindImageTexture(vm::VIRTUAL_MARK_IMAGE_SURFACE, surface, 0, GL_FALSE, 0, GL_READ_ONLY, GL_RGBA32F);
    glUseProgram(p.id);
    const auto groups = [](int n) { return static_cast<GLuint>((n + vm::VIRTUAL_MARK_GROUP_SIZE - 1) / vm::VIRTUAL_MARK_GROUP_SIZE); };
    glDispatchCompute(groups(Ground::width), groups(Ground::height), 1);
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    std::vector<std::uint32_t> m_words(words);
    glGetNamedBufferSubData(marks, 0, static_cast<GLsizeiptr>(words * sizeof(std::uint32_t)), m_words.data());
    ASSERT_EQ(glGetError(), static_cast<GLenum>(GL_NO_ERROR));

    std::set<adaptive::Page> gpu;
    for (std::size_t w = vm::VIRTUAL_MARK_WORD_PAGE_BITS; w < vm::VIRTUAL_MARK_WORD_PAGE_BITS + vm::virtual_mark_page_bit_words(layout.levels, layout.pages_per_side); ++w)
      for (int b = 0; b < 32; ++b)
        if (m_words[w] >> b & 1u) {
          const auto bit = static_cast<vm::uint>((w - vm::VIRTUAL_MARK_WORD_PAGE_BITS) * 32 + static_cast<std::size_t>(b));
          const vm::Page page = vm::virtual_mark_page_of_bit(bit, layout.pages_per_side);
          gpu.insert({page.level, page.x, page.y});
        }
    const adaptive::MarkResult cpu = adaptive::mark_pages(requests, camera_xy, layout, options);
    std::vector<adaptive::Page> only_one;
    std::set_symmetric_difference(cpu.pages.begin(), cpu.pages.end(), gpu.begin(), gpu.end(), std::back_inserter(only_one));
    EXPECT_GT(cpu.pages.size(), 30u);
    EXPECT_LE(only_one.size(), cpu.pages.size() / 100) << only_one.size() << " of " << cpu.pages.size() << " pages differ";
    std::int64_t moved = 0, levels_used = 0;
    for (int k = 0; k < layout.levels; ++k) {
      const std::int64_t counted = m_words[static_cast<std::size_t>(vm::VIRTUAL_MARK_WORD_PIXELS_PER_LEVEL + k)];
      moved += std::abs(counted - cpu.pixels_per_level[static_cast<std::size_t>(k)]);
      levels_used += counted > 0;
    }
    EXPECT_LE(moved, static_cast<std::int64_t>(requests.size() / 200)) << "pixels on another level";
    EXPECT_GE(levels_used, 3) << "the plane spans levels";
    EXPECT_EQ(static_cast<std::int64_t>(m_words[vm::VIRTUAL_MARK_WORD_UNMARKED]), cpu.unmarked);
    const std::string name(adaptive::to_string(m));
    ::testing::Test::RecordProperty(name + "_pages_cpu", static_cast<int>(cpu.pages.size()));
    ::testing::Test::RecordProperty(name + "_pages_differ", static_cast<int>(only_one.size()));
    ::testing::Test::RecordProperty(name + "_pixels_moved", static_cast<int>(moved));
    ::testing::Test::RecordProperty(name + "_levels_used", static_cast<int>(levels_used));
    if (m == adaptive::Marking::rule) by_rule = gpu;
    else EXPECT_NE(gpu, by_rule) << "the rule and the footprint marked the same pages: the test does not tell them apart";
  }
  glDeleteBuffers(1, &frame_buffer);
  glDeleteBuffers(1, &marks);
  glDeleteTextures(1, &surface);
}

}  // namespace
}  // namespace penumbra
