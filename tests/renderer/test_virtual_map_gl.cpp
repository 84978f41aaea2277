// The virtual shadow map's pool, page tables and cache (shadows/virtual_shadow_map.h) on the demo
// scene: a depth read through the tables (virtual_pages.glsl) equals the same texel of a full map
// of its level drawn directly, on every level and in slots at the pool's edges; a second frame
// draws nothing; a moved camera draws only the pages its windows gained; a moved light or caster
// redraws what it touched; a pool too small keeps the coarse levels and counts what is missing.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <functional>
#include <iterator>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "gl/embedded_files.h"
#include "gl/shader_library.h"
#include "gl_test_env.h"
#include "metrics/surface_probe.h"
#include "shadows/renderer.h"
#include "shadows/virtual_shadow_map.h"
#include "shaders/shadow_contract.h"

namespace penumbra {
namespace {

using adaptive::Page;
using adaptive::VirtualMapLayout;
using shadows::VirtualShadowMap;

// 3 levels of 8 × 8 pages of 32² texels, level 0's texel 1/32 m: windows of 8, 16 and 32 m (the
// demo's 20 m ground lies in level 2's). Binary fractions: windows move by whole pages exactly.
VirtualMapLayout small_layout() {
  VirtualMapLayout l;
  l.levels = 3;
  l.texel0_ws = 1.0 / 32;
  l.page_texels = 32;
  l.pages_per_side = 8;
  return l;
}

std::set<Page> every_page(const VirtualMapLayout& l) {
  std::set<Page> pages;
  for (int k = 0; k < l.levels; ++k)
    for (int x = 0; x < l.pages_per_side; ++x)
      for (int y = 0; y < l.pages_per_side; ++y) pages.insert({k, x, y});
  return pages;
}

struct Fixture {
  scene::Scene scene = scene::make_builtin_scene("demo");
  scene::GpuMeshes meshes{scene.objects};
  shadows::VirtualMapView view;
  Fixture() {
    view.light_view = shadows::sun_light_view(glm::normalize(glm::vec3(-0.3f, -1.0f, -0.5f)));
    shadows::light_depth_range(view.light_view, scene.bounds(), view.near_ws, view.far_ws);
    view.camera_xy = {0, 0};
  }
};

// A test's compute shader `name` (it may include the project's shaders, virtual_pages.glsl).
gl::Program compute_program(const std::string& name, const std::string& text) {
  std::vector<std::pair<std::string, std::string>> files;
  for (const auto& f : embedded::shaders()) files.emplace_back(std::string(f.name), std::string(f.text));
  files.emplace_back(name, text);
  return gl::ShaderLibrary(files).program({{GL_COMPUTE_SHADER, name}});
}

// Runs a comparison shader `p` (uniforms u_level and u_radius_texels, the single map of the level
// at texture unit `unit`, its output an n × n RGBA32F image at image unit 0) over level `level` of
// `virtual_map` for squares of 2.5 texels' radius and of 20 (wider than a page of small_layout), handing
// `check` each radius and the output read back, four floats a point.
void for_each_radius(const gl::Program& p, const VirtualShadowMap& virtual_map, int level, const gl::Texture& single, int unit, int n,
                     const std::function<void(float, const std::vector<float>&)>& check) {
  const gl::Texture out({GL_RGBA32F, n, n, 1}, "comparison output");
  virtual_map.bind();
  p.set("u_level", level);
  single.bind(unit);
  glBindSampler(unit, 0);
  for (const float r : {2.5f, 20.0f}) {
    SCOPED_TRACE("radius " + std::to_string(r) + " texels");
    p.set("u_radius_texels", r);
    glBindImageTexture(0, out.id(), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    p.dispatch_covering(n, n);
    glMemoryBarrier(GL_TEXTURE_UPDATE_BARRIER_BIT);
    std::vector<float> v(4 * static_cast<std::size_t>(n) * n);
    glGetTextureImage(out.id(), 0, GL_RGBA, GL_FLOAT, static_cast<GLsizei>(v.size() * sizeof(float)), v.data());
    check(r, v);
  }
}

// What virtual_pages.glsl reads, texel by texel over level `level`'s window: the depth, or -1 where
// virtual_fetch finds nothing; with `resident`, the level virtual_resident_level falls back to instead.
std::vector<float> read_through_tables(const VirtualShadowMap& virtual_map, int level, bool resident = false) {
  const gl::Program p = compute_program("probe.comp", R"(
#include "virtual_pages.glsl"
layout(local_size_x = 8, local_size_y = 8) in;
layout(binding = 0, r32f) uniform writeonly image2D u_out;
uniform int u_level;
uniform bool u_resident;
void main() {
  const ivec2 t = ivec2(gl_GlobalInvocationID.xy);
  if (any(greaterThanEqual(t, imageSize(u_out)))) return;
  float depth;
  float v = virtual_fetch(u_level, t, depth) ? depth : -1.0;
  if (u_resident) {  // the texel's centre in light space, then the finest resident level there
    const vec2 xy = virtual_origin(u_level) + (vec2(t) + 0.5) * virtual_texel_ws(u_level);
    v = float(virtual_resident_level(u_level, xy));
  }
  imageStore(u_out, t, vec4(v));
})");
  const int side = virtual_map.layout().page_texels * virtual_map.layout().pages_per_side;
  const gl::Texture out({GL_R32F, side, side, 1}, "probe output");
  virtual_map.bind();
  p.set("u_level", level);
  p.set("u_resident", resident);
  glBindImageTexture(0, out.id(), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_R32F);
  p.dispatch_covering(side, side);
  glMemoryBarrier(GL_TEXTURE_UPDATE_BARRIER_BIT);
  std::vector<float> v(static_cast<std::size_t>(side) * side);
  glGetTextureImage(out.id(), 0, GL_RED, GL_FLOAT, static_cast<GLsizei>(v.size() * sizeof(float)), v.data());
  return v;
}

// Level `level`'s whole window drawn directly into one map of its size (no pages, no culling);
// with `moments`, also VSM's moments (RG interleaved) as the pages draw them.
std::vector<float> full_map(const Fixture& f, const VirtualShadowMap& virtual_map, int level, std::vector<float>* moments = nullptr) {
  const int side = virtual_map.layout().page_texels * virtual_map.layout().pages_per_side;
  const gl::Texture depth({GL_DEPTH_COMPONENT32F, side, side, 1}, "full level map");
  gl::Texture moments_tex;
  std::vector<gl::Framebuffer::Attachment> a = {{&depth, GL_DEPTH_ATTACHMENT}};
  if (moments) {
    moments_tex = gl::Texture({GL_RG32F, side, side, 1}, "full level moments");
    a.push_back({&moments_tex, GL_COLOR_ATTACHMENT0});
  }
  const gl::Framebuffer fbo(a, "full level map");
  const gl::Program p = gl::ShaderLibrary().program(
      {{GL_VERTEX_SHADER, "virtual_page.vert"}, {GL_FRAGMENT_SHADER, moments ? "virtual_page_moments.frag" : "shadow_depth.frag"}});
  const adaptive::LightXY o = virtual_map.origin(level);
  const auto extent = static_cast<float>(side * virtual_map.layout().texel0_ws * std::ldexp(1.0, level));
  const auto x0 = static_cast<float>(o.x), y0 = static_cast<float>(o.y);
  p.set("u_clip_from_world", glm::ortho(x0, x0 + extent, y0, y0 + extent, f.view.near_ws, f.view.far_ws) * f.view.light_view);
  fbo.bind();
  glViewport(0, 0, side, side);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDepthMask(GL_TRUE);
  glDisable(GL_CULL_FACE);
  glClearDepth(1.0);
  glClear(GL_DEPTH_BUFFER_BIT);
  if (moments) {
    const float far_moments[4] = {1, 1, 0, 0};
    glClearBufferfv(GL_COLOR, 0, far_moments);
  }
  p.use();
  for (std::size_t i = 0; i < f.meshes.size(); ++i) {
    p.set("u_model", f.scene.objects[i].model);
    f.meshes[i].draw();
  }
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  std::vector<float> v(static_cast<std::size_t>(side) * side);
  glGetTextureImage(depth.id(), 0, GL_DEPTH_COMPONENT, GL_FLOAT, static_cast<GLsizei>(v.size() * sizeof(float)), v.data());
  if (moments) {
    moments->resize(2 * v.size());
    glGetTextureImage(moments_tex.id(), 0, GL_RG, GL_FLOAT, static_cast<GLsizei>(moments->size() * sizeof(float)), moments->data());
  }
  return v;
}

// full_map's depths as an R32F texture, which the comparison shaders read as the single map.
gl::Texture single_map(const Fixture& f, const VirtualShadowMap& virtual_map, int level) {
  const int side = virtual_map.layout().page_texels * virtual_map.layout().pages_per_side;
  const std::vector<float> direct = full_map(f, virtual_map, level);
  gl::Texture single({GL_R32F, side, side, 1}, "single map of the level");
  glTextureSubImage2D(single.id(), 0, 0, 0, side, side, GL_RED, GL_FLOAT, direct.data());
  return single;
}

TEST(VirtualMap, ATexelThroughTheTablesEqualsTheFullMapOfItsLevel) {
  Fixture f;
  const VirtualMapLayout layout = small_layout();
  VirtualShadowMap virtual_map(layout, 14);  // 196 slots for 192 pages: slots in the pool's last row and column are used
  const auto stats = virtual_map.update(every_page(layout), f.view, f.scene, f.meshes);
  EXPECT_EQ(stats.requested, 192);
  EXPECT_EQ(stats.drawn, 192);
  EXPECT_EQ(stats.missing, 0);
  EXPECT_EQ(stats.resident, 192);
  std::set<int> slots;
  for (const Page& p : every_page(layout)) slots.insert(virtual_map.slot_of(p));
  EXPECT_EQ(slots.size(), 192u);
  EXPECT_TRUE(slots.count(13) && slots.count(14 * 13)) << "the pool's last column and last row";
  for (int level = 0; level < layout.levels; ++level) {
    SCOPED_TRACE(level);
    const std::vector<float> paged = read_through_tables(virtual_map, level), direct = full_map(f, virtual_map, level);
    ASSERT_EQ(paged.size(), direct.size());
    std::size_t differ = 0, covered = 0;
    for (std::size_t i = 0; i < paged.size(); ++i) {
      ASSERT_GE(paged[i], 0.0f) << "texel " << i << " not found through the tables";
      differ += std::abs(paged[i] - direct[i]) > 1e-5f;
      covered += direct[i] < 1.0f;
    }
    EXPECT_GT(covered, paged.size() / 4) << "the scene is in the window";
    // The same triangles at the same sample points; a page's matrix differs from the full map's by
    // its offset, so a sample lying exactly on an edge may go either way.
    EXPECT_LE(differ, paged.size() / 1000) << differ << " of " << paged.size() << " texels differ";
  }
}

// PCF through the tables (virtual_pcf_box) against the same box filter on a single map of the level
// (the full map drawn directly): squares of 2.5 texels' radius at 128 × 128 points over level 1's
// window, a fifth of which cross a page border, with the receiver just behind the surface there,
// and of 20 texels (wider than a 32-texel page: up to three pages a side, the blocks read one by
// one); and PCSS's blocker search (virtual_blocker_search) over squares twice as wide, likewise, at
// every other point against a sloped receiver plane (each texel tested at its centre).
TEST(VirtualMap, PcfAndBlockerSearchAcrossPageBordersEqualASingleMapOfTheLevel) {
  Fixture f;
  const VirtualMapLayout layout = small_layout();
  VirtualShadowMap virtual_map(layout, 14);
  virtual_map.update(every_page(layout), f.view, f.scene, f.meshes);
  const int level = 1, side = layout.page_texels * layout.pages_per_side;
  const gl::Texture single = single_map(f, virtual_map, level);
  const gl::Program p = compute_program("pcf.comp", R"(
#include "virtual_pages.glsl"
layout(local_size_x = 8, local_size_y = 8) in;
layout(binding = 0, rgba32f) uniform writeonly image2D u_out;  // PCF paged, single; blockers paged, single
layout(binding = 13) uniform sampler2D u_single;
uniform int u_level;
uniform float u_radius_texels;
void main() {
  const ivec2 q = ivec2(gl_GlobalInvocationID.xy);
  if (any(greaterThanEqual(q, imageSize(u_out)))) return;
  const int side = u_virtual_page_texels * u_virtual_pages_per_side;
  const float t = virtual_texel_ws(u_level);
  const vec2 p = (vec2(q) + 0.37) * float(side) / vec2(imageSize(u_out));  // texel coordinates, off-centre
  const float receiver = texelFetch(u_single, ivec2(p), 0).r + 0.002;     // just behind the surface there
  bool found;
  const float paged = virtual_pcf_box(u_level, virtual_origin(u_level) + p * t, receiver, u_radius_texels * t, found);
  // The reference: the same square over the single map, texel by texel.
  const float r = u_radius_texels;
  const vec2 lo = p - r, hi = p + r;
  float sum = 0.0;
  for (int j = int(floor(lo.y)); j <= int(ceil(hi.y)) - 1; ++j)
    for (int i = int(floor(lo.x)); i <= int(ceil(hi.x)) - 1; ++i) {
      const float w = max(0.0, min(float(i + 1), hi.x) - max(float(i), lo.x)) * max(0.0, min(float(j + 1), hi.y) - max(float(j), lo.y));
      const bool inside = i >= 0 && j >= 0 && i < side && j < side;
      sum += w * (inside && receiver <= texelFetch(u_single, ivec2(i, j), 0).r ? 1.0 : 0.0);
    }
  const bool whole = all(greaterThanEqual(lo, vec2(0.0))) && all(lessThanEqual(hi, vec2(side)));
  // PCSS's blocker search over a square twice as wide, through the tables and on the single map;
  // at odd columns of points the receiver is a plane rising 7e-4 a texel along x, falling 4e-4 along y.
  const vec2 gradient = (q.x & 1) == 1 ? vec2(7e-4, -4e-4) / t : vec2(0.0);
  const vec2 step = gradient * t;
  int blockers;
  bool searched;
  const float mean = virtual_blocker_search(u_level, virtual_origin(u_level) + p * t, receiver, gradient, 2.0 * r * t, blockers, searched);
  float ref_sum = 0.0;
  int ref_count = 0;
  for (int j = int(floor(p.y - 2.0 * r)); j <= int(ceil(p.y + 2.0 * r)) - 1; ++j)
    for (int i = int(floor(p.x - 2.0 * r)); i <= int(ceil(p.x + 2.0 * r)) - 1; ++i) {
      const float d = texelFetch(u_single, ivec2(i, j), 0).r;
      const float row = receiver + (float(j) + 0.5 - p.y) * step.y;
      if (d < row + (float(i) + 0.5 - p.x) * step.x) ref_sum += d, ++ref_count;
    }
  const bool whole_search = all(greaterThanEqual(p - 2.0 * r, vec2(0.0))) && all(lessThanEqual(p + 2.0 * r, vec2(side)));
  imageStore(u_out, q, vec4(found ? paged : -1.0, whole ? sum / (4.0 * r * r) : -1.0,
                            searched ? mean + float(blockers) : -1.0,
                            whole_search ? (ref_count > 0 ? ref_sum / float(ref_count) : 1.0) + float(ref_count) : -1.0));
})");
  const int n = 128;
  for_each_radius(p, virtual_map, level, single, 13, n, [&](float r, const std::vector<float>& v) {
    int compared = 0, across = 0, partial = 0, searched = 0, with_blockers = 0;
    float worst = 0, worst_search = 0, worst_sloped = 0;
    double sloped_blockers = 0, sloped_flips = 0;
    for (int q = 0; q < n * n; ++q) {
      // The blocker search: mean blocker depth + blocker count, through the tables and on the map.
      const float search_paged = v[4 * q + 2], search_single = v[4 * q + 3];
      if (search_single >= 0) {
        ASSERT_GE(search_paged, 0.0f) << "point " << q << ": a texel under the search was not found";
        ++searched;
        with_blockers += search_single >= 1.0f + 1.0f;  // one blocker or more (the mean is below 1)
        // Count + mean in one float (up to ~6,600 + 1): a different count shows as 1 or more.
        const float difference = std::abs(search_paged - search_single);
        if (q % 2 == 0) {
          worst_search = std::max(worst_search, difference / std::max(1.0f, search_single));
        } else {  // against the plane: a texel where it meets a surface may fall either side by rounding
          worst_sloped = std::max(worst_sloped, difference);
          sloped_blockers += std::floor(search_single);
          sloped_flips += std::round(difference);
        }
      }
      const float paged = v[4 * q], single_map = v[4 * q + 1];
      if (single_map < 0) {  // the square leaves the window: the tables say so instead of guessing
        EXPECT_EQ(paged, -1.0f) << "point " << q;
        continue;
      }
      ASSERT_GE(paged, 0.0f) << "point " << q << ": a texel under the square was not found";
      ++compared;
      worst = std::max(worst, std::abs(paged - single_map));
      partial += single_map > 0.01f && single_map < 0.99f;
      const float x = (static_cast<float>(q % n) + 0.37f) * static_cast<float>(side) / n,
                  y = (static_cast<float>(q / n) + 0.37f) * static_cast<float>(side) / n;
      const auto crosses = [&](float c) { return std::floor((c - r) / 32) != std::floor((c + r) / 32); };
      across += crosses(x) || crosses(y);
    }
    // The share of points whose square (and search) lies inside the window.
    const auto inside = [&](float half) { return std::pow((static_cast<float>(side) - 2 * half) / static_cast<float>(side), 2.0f); };
    EXPECT_GT(compared, static_cast<float>(n * n) * inside(r) * 0.95f);
    EXPECT_GT(across, compared / 6) << "squares across a page border";
    EXPECT_GT(partial, compared / 50) << "penumbrae, not only 0 and 1";
    EXPECT_LE(worst, 1.0f / 255) << "largest difference " << worst;
    EXPECT_GT(searched, static_cast<float>(n * n) * inside(2 * r) * 0.95f);
    EXPECT_GT(with_blockers, searched / 20) << "searches that find blockers";
    // Relative: rounding of the sum shows as ~1e-6, a different count as 1 / count or more.
    EXPECT_LE(worst_search, 2e-5f) << "the same blockers, the same mean depth";
    // Against the sloped plane: the same blockers but for a texel or two on the plane itself.
    EXPECT_LE(worst_sloped, 2.5f) << "blocker counts differ by more than rounding";
    EXPECT_LE(sloped_flips, 1e-4 * sloped_blockers) << "of " << sloped_blockers << " blockers";
    ::testing::Test::RecordProperty("largest_difference_x1e6_radius_" + std::to_string(static_cast<int>(r)), static_cast<int>(worst * 1e6f));
  });
}

// The tiles' bounds (virtual_bounds.comp): every texel of every page lies between its tile's two
// planes, and on the demo's ground, tilted in light space, most tiles are one plane, their bounds
// a rounding apart; tiles over an edge are wide.
TEST(VirtualMap, TileBoundsHoldEveryTexelAndHugAPlanarGround) {
  Fixture f;
  const VirtualMapLayout layout = small_layout();
  VirtualShadowMap virtual_map(layout, 14);
  ASSERT_TRUE(virtual_map.bounds()) << "on by default for a depth pool";
  virtual_map.update(every_page(layout), f.view, f.scene, f.meshes);
  const int side = 14 * layout.page_texels, tile = shadows::contract::VIRTUAL_BOUNDS_TILE, tiles = side / tile;
  std::vector<float> depth(static_cast<std::size_t>(side) * side), bounds(4 * static_cast<std::size_t>(tiles) * tiles);
  glGetTextureImage(virtual_map.pool().id(), 0, GL_DEPTH_COMPONENT, GL_FLOAT, static_cast<GLsizei>(depth.size() * sizeof(float)), depth.data());
  glGetTextureImage(virtual_map.bounds_pool().id(), 0, GL_RGBA, GL_FLOAT, static_cast<GLsizei>(bounds.size() * sizeof(float)), bounds.data());
  int checked = 0, planar = 0, wide = 0;
  for (const Page& page : every_page(layout)) {
    const int slot = virtual_map.slot_of(page);
    ASSERT_GE(slot, 0);
    for (int ty = 0; ty < layout.page_texels / tile; ++ty)
      for (int tx = 0; tx < layout.page_texels / tile; ++tx) {
        const int cx = (slot % 14) * layout.page_texels + tx * tile, cy = (slot / 14) * layout.page_texels + ty * tile;
        const float* b = &bounds[4 * (static_cast<std::size_t>(cy / tile) * tiles + static_cast<std::size_t>(cx / tile))];
        for (int j = 0; j < tile; ++j)
          for (int i = 0; i < tile; ++i) {
            const float d = depth[static_cast<std::size_t>(cy + j) * side + static_cast<std::size_t>(cx + i)];
            const float plane = b[2] * (static_cast<float>(i) + 0.5f - 0.5f * tile) + b[3] * (static_cast<float>(j) + 0.5f - 0.5f * tile);
            ASSERT_GE(d, b[0] + plane - 1e-6f) << "slot " << slot << " tile " << tx << "," << ty << " texel " << i << "," << j;
            ASSERT_LE(d, b[1] + plane + 1e-6f) << "slot " << slot << " tile " << tx << "," << ty << " texel " << i << "," << j;
          }
        ++checked;
        planar += b[1] - b[0] < 1e-5f && (b[2] != 0 || b[3] != 0);  // a tilted plane, not the clear
        wide += b[1] - b[0] > 1e-3f;
      }
  }
  EXPECT_EQ(checked, 192 * 4);
  EXPECT_GT(planar, checked / 4) << "the ground's tiles";
  EXPECT_GT(wide, 0) << "tiles over a caster's edge";

  virtual_map.set_bounds(false);
  EXPECT_FALSE(virtual_map.bounds());
  EXPECT_EQ(virtual_map.update(every_page(layout), f.view, f.scene, f.meshes).drawn, 0) << "turning them off keeps the pages";
  virtual_map.set_bounds(true);
  EXPECT_EQ(virtual_map.update(every_page(layout), f.view, f.scene, f.meshes).drawn, 192) << "pages drawn without bounds have none";
}

// The bounds decide a square only where the filter would say the same: box PCF and PCSS's search
// through the tables with and without them, at 128 × 128 points over level 1's window, squares of
// 3.5 texels (the rule's c) at receivers on the surface's own plane just in front of it (even
// columns: mostly lit, most squares decided lit) and far behind everything (odd columns: umbra).
TEST(VirtualMap, TileBoundsDecideOnlyWhatTheFilterFinds) {
  Fixture f;
  const VirtualMapLayout layout = small_layout();
  VirtualShadowMap virtual_map(layout, 14);
  virtual_map.update(every_page(layout), f.view, f.scene, f.meshes);
  const int level = 1;
  const gl::Texture single = single_map(f, virtual_map, level);
  const gl::Program p = compute_program("bounds.comp", R"(
#include "virtual_pages.glsl"
layout(local_size_x = 8, local_size_y = 8) in;
layout(binding = 0, rgba32f) uniform writeonly image2D u_out;  // PCF, decided (1 lit, 0 umbra, -1 no), search mean + count, searched
layout(binding = 13) uniform sampler2D u_single;
uniform int u_level;
const float R = 3.5;
void main() {
  const ivec2 q = ivec2(gl_GlobalInvocationID.xy);
  if (any(greaterThanEqual(q, imageSize(u_out)))) return;
  const int side = u_virtual_page_texels * u_virtual_pages_per_side;
  const float t = virtual_texel_ws(u_level);
  const vec2 p = (vec2(q) + 0.37) * float(side) / vec2(imageSize(u_out));
  const ivec2 c = clamp(ivec2(p), ivec2(1), ivec2(side - 2));
  // The surface's plane at p from its neighbours (normalized depth per texel), the receiver on it.
  const vec2 per_texel = 0.5 * vec2(texelFetch(u_single, c + ivec2(1, 0), 0).r - texelFetch(u_single, c - ivec2(1, 0), 0).r,
                                    texelFetch(u_single, c + ivec2(0, 1), 0).r - texelFetch(u_single, c - ivec2(0, 1), 0).r);
  const bool behind = (q.x & 1) == 1;
  // In front: below the plane by the half texel a 2 × 2 block's shared corner lies from its texels'
  // centres (the filter tests each block there), and 1e-4.
  const float bias = 0.5 * (abs(per_texel.x) + abs(per_texel.y)) + 1e-4;
  const float receiver = behind ? 1.01 : texelFetch(u_single, c, 0).r + dot(p - vec2(c) - 0.5, per_texel) - bias;
  const vec2 gradient = behind ? vec2(0.0) : per_texel / t;
  const vec2 xy = virtual_origin(u_level) + p * t;
  bool found;
  const float pcf = virtual_pcf_box(u_level, xy, receiver, gradient, R * t, found);
  // The decision virtual_pcf_box takes, taken again.
  const vec2 lo = p - R, hi = p + R;
  const ivec2 first = ivec2(floor(lo)) & ~1, last = ivec2(ceil(hi)) - 1;
  VirtualSquare sq;
  float decided = -1.0;
  if (virtual_square(u_level, first, last, sq)) {
    const vec2 gap = virtual_tile_gap(sq, first, last, p, receiver, gradient * t);
    const float corner = 0.5 * (abs(gradient.x) + abs(gradient.y)) * t + VIRTUAL_GAP_EPSILON;
    decided = gap.x >= corner ? 1.0 : gap.y < -corner ? 0.0 : -1.0;
  }
  int blockers;
  bool searched;
  const float mean = virtual_blocker_search(u_level, xy, receiver, gradient, R * t, blockers, searched);
  imageStore(u_out, q, vec4(found ? pcf : -1.0, decided, mean + float(blockers), searched ? 1.0 : 0.0));
})");
  const int n = 128;
  const gl::Texture out({GL_RGBA32F, n, n, 1}, "bounds comparison");
  const shadows::VirtualFrameBuffer frame_buffer;  // the map's frame with its bounds on or off
  const auto run = [&](bool bounds) {
    virtual_map.bind();
    shadows::VirtualFrame frame = virtual_map.frame();
    frame.u_virtual_bounds = bounds;
    frame_buffer.bind(frame);
    p.set("u_level", level);
    single.bind(13);
    glBindSampler(13, 0);
    glBindImageTexture(0, out.id(), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    p.dispatch_covering(n, n);
    glMemoryBarrier(GL_TEXTURE_UPDATE_BARRIER_BIT);
    std::vector<float> v(4 * static_cast<std::size_t>(n) * n);
    glGetTextureImage(out.id(), 0, GL_RGBA, GL_FLOAT, static_cast<GLsizei>(v.size() * sizeof(float)), v.data());
    return v;
  };
  const std::vector<float> with = run(true), without = run(false);
  int lit = 0, umbra = 0, open = 0, in_front = 0, behind = 0, searched = 0;
  float worst = 0;
  for (int q = 0; q < n * n; ++q) {
    const float* a = &with[4 * static_cast<std::size_t>(q)];
    const float* b = &without[4 * static_cast<std::size_t>(q)];
    ASSERT_EQ(a[0] < 0, b[0] < 0) << "point " << q;
    EXPECT_EQ(b[1], -1.0f) << "point " << q << ": without bounds nothing is decided";
    if (a[0] < 0) continue;
    worst = std::max(worst, std::abs(a[0] - b[0]));
    if (a[1] == 1.0f) {
      EXPECT_GE(b[0], 1.0f - 1e-5f) << "point " << q << ": decided lit, the filter says " << b[0];
    } else if (a[1] == 0.0f) {
      EXPECT_EQ(b[0], 0.0f) << "point " << q << ": decided umbra, the filter says " << b[0];
    }
    lit += a[1] == 1.0f, umbra += a[1] == 0.0f, open += a[1] < 0;
    ((q % n) % 2 == 0 ? in_front : behind) += 1;
    if (a[3] == 1.0f) {
      ++searched;
      EXPECT_EQ(a[2], b[2]) << "point " << q << ": the search's blockers and mean";
    }
  }
  RecordProperty("decided_lit_umbra_open", std::to_string(lit) + " " + std::to_string(umbra) + " " + std::to_string(open));
  EXPECT_LE(worst, 1e-5f) << "sums of weights round; nothing else differs";
  EXPECT_GT(lit, in_front / 2) << "the ground in front of its own plane, lit";
  EXPECT_GT(umbra, behind * 9 / 10) << "behind everything";
  EXPECT_GT(open, 0) << "penumbrae and edges, filtered";
  EXPECT_GT(searched, n * n / 2);
}

// VSM through the tables (virtual_moments_box) against the same box over a single map of the level's
// moments drawn directly: squares of 2.5 and 20 texels' radius (up to three pages a side) at
// 128 × 128 points over level 1's window, both moments.
TEST(VirtualMap, VsmMomentsAcrossPageBordersEqualASingleMapOfTheLevel) {
  Fixture f;
  const VirtualMapLayout layout = small_layout();
  VirtualShadowMap virtual_map(layout, 14, VirtualShadowMap::Content::depth_and_moments);
  virtual_map.update(every_page(layout), f.view, f.scene, f.meshes);
  const int level = 1, side = layout.page_texels * layout.pages_per_side;
  std::vector<float> moments;
  full_map(f, virtual_map, level, &moments);
  const gl::Texture single({GL_RG32F, side, side, 1}, "single moments map of the level");
  glTextureSubImage2D(single.id(), 0, 0, 0, side, side, GL_RG, GL_FLOAT, moments.data());
  const gl::Program p = compute_program("moments.comp", R"(
#include "virtual_pages.glsl"
layout(local_size_x = 8, local_size_y = 8) in;
layout(binding = 0, rgba32f) uniform writeonly image2D u_out;  // paged (t, t²), single (t, t²)
layout(binding = 14) uniform sampler2D u_single;
uniform int u_level;
uniform float u_radius_texels;
void main() {
  const ivec2 q = ivec2(gl_GlobalInvocationID.xy);
  if (any(greaterThanEqual(q, imageSize(u_out)))) return;
  const int side = u_virtual_page_texels * u_virtual_pages_per_side;
  const float t = virtual_texel_ws(u_level);
  const vec2 p = (vec2(q) + 0.37) * float(side) / vec2(imageSize(u_out));
  bool found;
  const vec2 paged = virtual_moments_box(u_level, virtual_origin(u_level) + p * t, u_radius_texels * t, found);
  const float r = u_radius_texels;
  const vec2 lo = p - r, hi = p + r;
  vec2 sum = vec2(0.0);
  for (int j = int(floor(lo.y)); j <= int(ceil(hi.y)) - 1; ++j)
    for (int i = int(floor(lo.x)); i <= int(ceil(hi.x)) - 1; ++i) {
      const float w = max(0.0, min(float(i + 1), hi.x) - max(float(i), lo.x)) * max(0.0, min(float(j + 1), hi.y) - max(float(j), lo.y));
      sum += w * texelFetch(u_single, ivec2(i, j), 0).rg;
    }
  const bool whole = all(greaterThanEqual(lo, vec2(0.0))) && all(lessThanEqual(hi, vec2(side)));
  imageStore(u_out, q, vec4(found ? paged : vec2(-1.0), whole ? sum / (4.0 * r * r) : vec2(-1.0)));
})");
  const int n = 128;
  for_each_radius(p, virtual_map, level, single, 14, n, [&](float r, const std::vector<float>& v) {
    int compared = 0, differ = 0, below_far = 0;
    float worst = 0;
    for (int q = 0; q < n * n; ++q) {
      const float* o = &v[4 * static_cast<std::size_t>(q)];
      if (o[2] < 0) {
        EXPECT_EQ(o[0], -1.0f) << "point " << q << ": the square leaves the window";
        continue;
      }
      ASSERT_GE(o[0], 0.0f) << "point " << q << ": a texel under the square was not found";
      ++compared;
      below_far += o[2] < 0.999f;
      const float d = std::max(std::abs(o[0] - o[2]), std::abs(o[1] - o[3]));
      worst = std::max(worst, d);
      differ += d > 1e-5f;
    }
    EXPECT_GT(compared, n * n / 3);
    EXPECT_GT(below_far, compared / 4) << "casters under the squares, not only the far plane";
    // The same moments summed in another order (~1e-7); a texel whose sample lies exactly on a
    // triangle's edge may be drawn on the other side in a page, as in the depth test above.
    EXPECT_LE(differ, compared / 200) << differ << " points differ by more than 1e-5; worst " << worst;
    ::testing::Test::RecordProperty("worst_moment_difference_x1e6_radius_" + std::to_string(static_cast<int>(r)), static_cast<int>(worst * 1e6f));
  });
}

TEST(VirtualMap, PagesStayCachedAndOnlyWhatChangedIsDrawn) {
  Fixture f;
  const VirtualMapLayout layout = small_layout();
  VirtualShadowMap virtual_map(layout, 14);
  virtual_map.update(every_page(layout), f.view, f.scene, f.meshes);
  // The same view again: nothing drawn.
  auto stats = virtual_map.update(every_page(layout), f.view, f.scene, f.meshes);
  EXPECT_EQ(stats.drawn, 0);
  EXPECT_EQ(stats.cached, 192);
  EXPECT_EQ(stats.triangles, 0u);
  // The camera moves 4 m (a page of level 2): the windows scroll by 4, 2 and 1 pages, gaining
  // 32 + 16 + 8 pages; the others are where they were, in light space, and stay.
  f.view.camera_xy = {4, 0};
  stats = virtual_map.update(every_page(layout), f.view, f.scene, f.meshes);
  EXPECT_EQ(stats.drawn, 56);
  EXPECT_EQ(stats.cached, 136);
  EXPECT_EQ(stats.evicted, 52) << "4 free slots, then the pages the windows left";
  EXPECT_EQ(stats.missing, 0);
  const std::vector<float> paged = read_through_tables(virtual_map, 1), direct = full_map(f, virtual_map, 1);
  std::size_t differ = 0;
  for (std::size_t i = 0; i < paged.size(); ++i) differ += !(std::abs(paged[i] - direct[i]) <= 1e-5f);
  EXPECT_LE(differ, paged.size() / 1000) << "after scrolling, the tables still point at the right depths";
  // A caster moves: only the pages over its old (or new) bounds are redrawn.
  const scene::Object& box = f.scene.objects[1];
  virtual_map.invalidate(box.mesh->bounds().transformed(box.model));
  stats = virtual_map.update(every_page(layout), f.view, f.scene, f.meshes);
  EXPECT_GT(stats.invalidated, 0);
  EXPECT_EQ(stats.drawn, stats.invalidated);
  EXPECT_LT(stats.drawn, 192 / 4) << "a box touches a few pages per level";
  // The light moves: every page is redrawn (and the 4 the windows left, still cached, dropped).
  EXPECT_EQ(stats.resident, 196);
  f.view.light_view = shadows::sun_light_view(glm::normalize(glm::vec3(0.3f, -1.0f, -0.4f)));
  stats = virtual_map.update(every_page(layout), f.view, f.scene, f.meshes);
  EXPECT_EQ(stats.drawn, 192);
  EXPECT_EQ(stats.invalidated, 196);
  EXPECT_EQ(stats.resident, 192);
}

// An object moves (the box, 2 m across the ground): invalidating its old and its new bounds
// redraws those pages only, and every level read through the tables equals a full map of the moved
// scene; a map that was not told keeps the box where it was.
TEST(VirtualMap, AMovedObjectRedrawsItsPagesAndNoStaleDepthRemains) {
  Fixture f;
  const VirtualMapLayout layout = small_layout();
  VirtualShadowMap told(layout, 14), not_told(layout, 14);
  told.update(every_page(layout), f.view, f.scene, f.meshes);
  not_told.update(every_page(layout), f.view, f.scene, f.meshes);
  scene::Object& box = f.scene.objects[1];
  ASSERT_EQ(box.name, "box");
  const scene::Aabb before = box.mesh->bounds().transformed(box.model);
  box.model = glm::translate(glm::mat4(1), glm::vec3(2, 0, 1)) * box.model;
  const scene::Aabb after = box.mesh->bounds().transformed(box.model);
  told.invalidate(before);
  told.invalidate(after);
  const auto stats = told.update(every_page(layout), f.view, f.scene, f.meshes);
  EXPECT_GT(stats.drawn, 0);
  EXPECT_LT(stats.drawn, 192 / 3) << "only the pages over the box's old and new places";
  EXPECT_EQ(not_told.update(every_page(layout), f.view, f.scene, f.meshes).drawn, 0);
  for (int level = 0; level < layout.levels; ++level) {
    SCOPED_TRACE(level);
    const std::vector<float> direct = full_map(f, told, level), paged = read_through_tables(told, level),
                             stale = read_through_tables(not_told, level);
    std::size_t differ = 0, stale_differ = 0;
    for (std::size_t i = 0; i < direct.size(); ++i) {
      differ += !(std::abs(paged[i] - direct[i]) <= 1e-5f);
      stale_differ += !(std::abs(stale[i] - direct[i]) <= 1e-5f);
    }
    EXPECT_LE(differ, direct.size() / 1000);
    EXPECT_GT(stale_differ, direct.size() / 1000) << "the test sees a stale page";
  }
}

// Pages cull casters by clusters of at most scene::kClusterTriangles triangles, not by whole units:
// every page holds exactly the depths it held when culled by units (a cluster dropped covers none
// of its texels), and fewer triangles are drawn (the demo's sphere, 2304 triangles in one unit,
// no longer goes whole into each of the pages it touches).
TEST(VirtualMap, ClustersDrawTheSameDepthsWithFewerTrianglesThanUnits) {
  Fixture f;  // its meshes: clusters of kClusterTriangles
  const scene::GpuMeshes whole_units(f.scene.objects, 0);
  const VirtualMapLayout layout = small_layout();
  VirtualShadowMap by_units(layout, 14), by_clusters(layout, 14);
  const auto units = by_units.update(every_page(layout), f.view, f.scene, whole_units);
  const auto clusters = by_clusters.update(every_page(layout), f.view, f.scene, f.meshes);
  EXPECT_EQ(units.drawn, 192);
  EXPECT_EQ(clusters.drawn, 192);
  for (int level = 0; level < layout.levels; ++level) {
    SCOPED_TRACE(level);
    const std::vector<float> a = read_through_tables(by_units, level), b = read_through_tables(by_clusters, level);
    ASSERT_EQ(a.size(), b.size());
    std::size_t differ = 0, covered = 0;
    for (std::size_t i = 0; i < a.size(); ++i) differ += a[i] != b[i], covered += a[i] < 1.0f;
    EXPECT_EQ(differ, 0u) << "of " << a.size() << " texels";
    EXPECT_GT(covered, a.size() / 4) << "the scene is in the window";
  }
  EXPECT_LT(clusters.triangles, units.triangles / 2) << clusters.triangles << " against " << units.triangles;
  EXPECT_GT(clusters.draws, units.draws) << "more, shorter ranges";
  // Drawn by units, the sphere alone goes whole into each page it touches: at least its 2304
  // triangles per page of level 0 under it.
  EXPECT_GT(units.triangles, 4u * 2304u);
}

// A pool too small for what the frame asks keeps a coarse floor: the pages of the finest level
// whose pages under every requested one fit (with the requested pages coarser than it), so that
// each texel of a requested page finds a level, never nothing; what is missing is counted. A pool
// that cannot hold even the coarsest level under the request is refused, saying the side that would.
TEST(VirtualMap, APoolTooSmallKeepsACoarseFloorUnderEveryRequestedPage) {
  Fixture f;
  const VirtualMapLayout layout = small_layout();
  {
    VirtualShadowMap virtual_map(layout, 3);  // 9 slots for 192 pages: level 2 alone is 64
    try {
      virtual_map.update(every_page(layout), f.view, f.scene, f.meshes);
      ADD_FAILURE() << "a pool of 9 slots took every page";
    } catch (const shadows::PoolTooSmall& e) {
      EXPECT_EQ(e.pages(), 64);
      const std::string what = e.what();
      EXPECT_EQ(what.rfind("--map.virtual_pool_pages 3: ", 0), 0u) << what;
      EXPECT_NE(what.find("give at least 8"), std::string::npos) << what;
    }
  }
  // Four pages of level 0 around the camera (at a page corner of every level) and four of level 1:
  // 8 pages for 4 slots. Level 1's four hold level 0's squares: they are the floor, level 0 is missing.
  std::set<Page> around;
  for (const int x : {3, 4})
    for (const int y : {3, 4}) around.insert({0, x, y}), around.insert({1, x, y});
  VirtualShadowMap four(layout, 2);
  const auto stats = four.update(around, f.view, f.scene, f.meshes);
  EXPECT_EQ(stats.floor_level, 1);
  EXPECT_EQ(stats.floor, 0) << "the floor's pages were asked for";
  EXPECT_EQ(stats.missing, 4);
  EXPECT_EQ(stats.resident, 4);
  for (const Page& p : around) EXPECT_EQ(four.slot_of(p) >= 0, p.level == 1) << p.level << " " << p.x << " " << p.y;

  // Two level-0 pages away from the pages' corners, in a pool of one slot: one page of level 2
  // (4 m) holds both, where level 1 needs four. The floor page was not asked for; the asked ones
  // are missing.
  VirtualShadowMap one(layout, 1);
  const std::set<Page> apart = {{0, 5, 5}, {0, 6, 5}};  // [1, 3] x [1, 2] m
  const auto single = one.update(apart, f.view, f.scene, f.meshes);
  EXPECT_EQ(single.floor_level, 2);
  EXPECT_EQ(single.floor, 1);
  EXPECT_EQ(single.missing, 2);
  EXPECT_EQ(single.resident, 1);
  EXPECT_EQ(one.slot_of({2, 4, 4}), 0);
  // Every texel of the asked pages finds level 2 through the tables; none finds nothing.
  const std::vector<float> level0 = read_through_tables(one, 0, true);
  const int n = layout.page_texels, side = n * layout.pages_per_side;
  for (const Page& p : apart)
    for (int y = p.y * n; y < (p.y + 1) * n; ++y)
      for (int x = p.x * n; x < (p.x + 1) * n; ++x)
        ASSERT_EQ(level0[static_cast<std::size_t>(y) * side + x], 2.0f) << "texel " << x << ", " << y;
}

// Marking on the GPU against adaptive::mark_pages on the CPU, by the rule and by the footprint,
// on the town's street (frame 120) at 320 × 180: the same pages and the same pixels per level but
// for pixels exactly on a boundary (float against double).
TEST(VirtualMap, MarkingOnTheGpuEqualsTheCpuReference) {
  scene::Scene s = scene::make_builtin_scene("outdoor");
  const scene::Camera camera = s.camera_path.at(s.camera, 120);
  const int w = 320, h = 180;
  metrics::SurfaceProbe probe(s);
  const io::ImageF surface = probe.render(camera, w, h);
  gl::Texture texture({GL_RGBA32F, w, h, 1}, "surface");
  glTextureSubImage2D(texture.id(), 0, 0, 0, w, h, GL_RGBA, GL_FLOAT, surface.pixels.data());
  shadows::VirtualMapView view;
  view.light_view = shadows::sun_light_view(s.light.direction);
  shadows::light_depth_range(view.light_view, s.bounds(), view.near_ws, view.far_ws);
  const glm::vec3 c = glm::vec3(view.light_view * glm::vec4(camera.position, 1));
  view.camera_xy = {c.x, c.y};
  const adaptive::VirtualMapLayout layout;  // 12 levels from 5 mm, 64² pages of 128² texels
  const double radius = 0.12;
  const glm::vec3 forward = glm::normalize(camera.target - camera.position);
  const double per_px = 2 * std::tan(glm::radians(camera.fov_y_deg) / 2) / h;
  std::vector<adaptive::PixelRequest> requests;
  for (std::size_t p = 0; p < surface.pixels.size() / 4; ++p) {
    if (surface.pixels[4 * p + 3] <= 0) continue;
    const glm::vec3 world(surface.pixels[4 * p], surface.pixels[4 * p + 1], surface.pixels[4 * p + 2]);
    const glm::vec3 l = glm::vec3(view.light_view * glm::vec4(world, 1));
    requests.push_back({{l.x, l.y}, std::max(0.0, static_cast<double>(glm::dot(world - camera.position, forward))) * per_px, radius});
  }
  ASSERT_GT(requests.size(), static_cast<std::size_t>(w * h / 2));
  const shadows::PageMarker marker(layout);
  for (const adaptive::Marking m : {adaptive::Marking::rule, adaptive::Marking::footprint}) {
    SCOPED_TRACE(std::string(adaptive::to_string(m)));
    adaptive::MarkOptions options;
    options.marking = m;
    const adaptive::MarkResult cpu = adaptive::mark_pages(requests, view.camera_xy, layout, options);
    const adaptive::MarkResult gpu = marker.mark(texture, camera, h, view, radius, options);
    std::vector<Page> only_one;
    std::set_symmetric_difference(cpu.pages.begin(), cpu.pages.end(), gpu.pages.begin(), gpu.pages.end(), std::back_inserter(only_one));
    EXPECT_GT(cpu.pages.size(), 50u);
    EXPECT_LE(only_one.size(), cpu.pages.size() / 100) << only_one.size() << " of " << cpu.pages.size() << " pages differ";
    ASSERT_EQ(gpu.pixels_per_level.size(), cpu.pixels_per_level.size());
    std::int64_t moved = 0;
    for (std::size_t k = 0; k < cpu.pixels_per_level.size(); ++k) moved += std::abs(gpu.pixels_per_level[k] - cpu.pixels_per_level[k]);
    EXPECT_LE(moved, static_cast<std::int64_t>(requests.size() / 200)) << "pixels on another level";
    // The tiles of the pages both marked: the same but for squares whose edge float rounding puts
    // across a tile's border.
    int tile_bits = 0, tiles_differ = 0;
    for (const Page& p : cpu.pages) {
      if (!gpu.pages.count(p)) continue;
      ASSERT_TRUE(cpu.tiles.count(p) && gpu.tiles.count(p));
      tile_bits += std::popcount(cpu.tiles.at(p));
      tiles_differ += std::popcount(cpu.tiles.at(p) ^ gpu.tiles.at(p));
    }
    EXPECT_GT(tile_bits, static_cast<int>(cpu.pages.size()));
    EXPECT_LE(tiles_differ, tile_bits / 100) << tiles_differ << " of " << tile_bits << " tiles differ";
    const std::string name(adaptive::to_string(m));
    ::testing::Test::RecordProperty(name + "_tiles_differ", tiles_differ);
    ::testing::Test::RecordProperty(name + "_pages_cpu", static_cast<int>(cpu.pages.size()));
    ::testing::Test::RecordProperty(name + "_pages_differ", static_cast<int>(only_one.size()));
    ::testing::Test::RecordProperty(name + "_pixels_moved", static_cast<int>(moved));
    EXPECT_EQ(gpu.unmarked, cpu.unmarked);
  }
}

// PCSS's blocker search through the pages runs in the marking (virtual_mark.comp's penumbra pass),
// whose reads the shading's count used to miss: counting it again (what Renderer::count_shading_reads
// now does) tallies at least a table read and a depth gather for every pixel whose search ran, and
// changes nothing a later marking reads.
TEST(VirtualMap, ThePcssSearchsReadsInTheMarkingAreCounted) {
  Fixture f;
  const VirtualMapLayout layout = small_layout();
  VirtualShadowMap map(layout, 14);
  map.update(every_page(layout), f.view, f.scene, f.meshes);
  const int w = 160, h = 90;
  metrics::SurfaceProbe probe(f.scene);
  const io::ImageF surface = probe.render(f.scene.camera, w, h);
  gl::Texture texture({GL_RGBA32F, w, h, 1}, "surface");
  glTextureSubImage2D(texture.id(), 0, 0, 0, w, h, GL_RGBA, GL_FLOAT, surface.pixels.data());
  shadows::VirtualPcss pcss;
  pcss.tan_half_angle = std::tan(glm::radians(f.scene.light.size) / 2);
  pcss.min_penumbra_ws = 0.01f;
  const adaptive::MarkOptions options;
  const shadows::PageMarker marker(layout);
  const gl::Texture radii({GL_R32F, w, h, 1}, "radii");
  const adaptive::MarkResult before = marker.mark_pcss_filter(texture, f.scene.camera, h, map, pcss, options, nullptr, &radii);
  std::vector<float> radius(static_cast<std::size_t>(w) * h);
  glGetTextureImage(radii.id(), 0, GL_RED, GL_FLOAT, static_cast<GLsizei>(radius.size() * sizeof(float)), radius.data());
  const auto searched = static_cast<std::uint64_t>(std::count_if(radius.begin(), radius.end(), [](float r) { return r >= 0; }));
  ASSERT_GT(searched, static_cast<std::uint64_t>(w * h / 2)) << "most pixels' searches find their level resident";

  const gl::Buffer reads(sizeof(shadows::contract::ShadowReadsResult), nullptr, GL_DYNAMIC_STORAGE_BIT);
  const std::uint32_t zero = 0;
  glClearNamedBufferData(reads.id(), GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, shadows::contract::BUFFER_SHADOW_READS, reads.id());
  marker.count_pcss_search_reads(texture, f.scene.camera, h, map, pcss, options);
  shadows::contract::ShadowReadsResult raw{};
  glGetNamedBufferSubData(reads.id(), 0, sizeof raw, &raw);
  std::uint64_t pixels = 0, instructions = 0, texels = 0, bytes = 0;
  for (int i = 0; i < shadows::contract::SHADOW_READ_SLOTS; ++i)
    pixels += raw.read_pixels[i], instructions += raw.read_instructions[i], texels += raw.read_texels[i], bytes += raw.read_bytes[i];
  EXPECT_EQ(pixels, 0u) << "the shading counts the pixels";
  EXPECT_GE(instructions, 2 * searched) << "a table read and a gather at least per search";
  EXPECT_GE(texels, 5 * searched) << "a table texel and a gather's four";
  EXPECT_GE(bytes, 4 * texels) << "4-byte table entries and depths, 16-byte tile bounds";
  ::testing::Test::RecordProperty("search_instructions_per_searched_pixel", static_cast<int>(instructions / searched));

  // Nothing a later frame reads changed: the same marking again gives the same pages and radii.
  const adaptive::MarkResult after = marker.mark_pcss_filter(texture, f.scene.camera, h, map, pcss, options, nullptr, &radii);
  EXPECT_EQ(after.pages, before.pages);
  std::vector<float> radius_after(radius.size());
  glGetTextureImage(radii.id(), 0, GL_RED, GL_FLOAT, static_cast<GLsizei>(radius_after.size() * sizeof(float)), radius_after.data());
  EXPECT_EQ(radius_after, radius);
}

// PCSS's blocker search through the pages tests each texel against the receiver's plane (the
// marker takes it from neighbouring pixels): a receiver tilted 70° from the light, with nothing
// in front of it, finds no blocker on its own surface; tested against one depth less the same
// bias, most of it shadows itself. A box over the plane is still found.
TEST(VirtualMap, PcssSearchTestsAgainstTheReceiverPlaneAndFindsOnlyRealBlockers) {
  const glm::vec3 light_dir = glm::normalize(glm::vec3(-0.3f, -1.0f, -0.5f));
  const glm::vec3 across = glm::normalize(glm::cross(light_dir, glm::vec3(1, 0, 0)));
  const float tilt = glm::radians(70.0f);
  const glm::vec3 normal = std::cos(tilt) * -light_dir + std::sin(tilt) * across;  // 70° from the light
  const glm::vec3 e1 = glm::normalize(glm::cross(normal, glm::vec3(0, 0, 1))), e2 = glm::cross(e1, normal);
  glm::mat4 model(1);  // the plane's +y along `normal`
  model[0] = glm::vec4(e1, 0), model[1] = glm::vec4(normal, 0), model[2] = glm::vec4(e2, 0);
  scene::Scene plane_scene;
  plane_scene.objects.push_back({"slope", std::make_shared<scene::MeshData>(scene::make_plane(30, 30)), model, glm::vec3(0.7f)});
  plane_scene.light.direction = light_dir;
  scene::Scene with_box = plane_scene;  // a 2 m box 3 m in front of the slope, toward the light
  with_box.objects.push_back({"box", std::make_shared<scene::MeshData>(scene::make_box(glm::vec3(2))),
                              glm::translate(glm::mat4(1), -light_dir * 3.0f), glm::vec3(0.7f)});

  // The slope as a camera above it sees it: 128 × 128 points over its middle 16 m.
  const int w = 128, h = 128;
  std::vector<float> points(4 * static_cast<std::size_t>(w) * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const glm::vec3 p = (static_cast<float>(x) / (w - 1) - 0.5f) * 16.0f * e1 + (static_cast<float>(y) / (h - 1) - 0.5f) * 16.0f * e2;
      const std::size_t i = 4 * (static_cast<std::size_t>(y) * w + x);
      points[i] = p.x, points[i + 1] = p.y, points[i + 2] = p.z, points[i + 3] = 1;
    }
  const gl::Texture surface({GL_RGBA32F, w, h, 1}, "slope points");
  glTextureSubImage2D(surface.id(), 0, 0, 0, w, h, GL_RGBA, GL_FLOAT, points.data());
  scene::Camera camera;
  camera.position = normal * 20.0f;
  camera.target = glm::vec3(0);
  const VirtualMapLayout layout;
  const shadows::PageMarker marker(layout);
  adaptive::MarkOptions options;
  const gl::Texture radii({GL_R32F, w, h, 1}, "penumbrae");

  // Pixels whose search found blockers (penumbra > 0), for a scene and a search.
  const auto blocked = [&](const scene::Scene& sc, bool receiver_plane) {
    const scene::GpuMeshes meshes(sc.objects);
    shadows::VirtualMapView view;
    view.light_view = shadows::sun_light_view(light_dir);
    shadows::light_depth_range(view.light_view, sc.bounds(), view.near_ws, view.far_ws);
    view.camera_xy = {0, 0};
    shadows::VirtualPcss pcss;
    pcss.tan_half_angle = std::tan(glm::radians(0.5f));
    pcss.min_penumbra_ws = 0.01f;
    pcss.search_bias_texels = 0.5f;
    pcss.receiver_plane = receiver_plane;
    VirtualShadowMap virtual_map(layout, 32);
    const adaptive::MarkResult search = marker.mark_pcss_search(surface, camera, h, view, pcss, options);
    virtual_map.update(search.pages, view, sc, meshes);
    marker.mark_pcss_filter(surface, camera, h, virtual_map, pcss, options, nullptr, &radii);
    glMemoryBarrier(GL_TEXTURE_UPDATE_BARRIER_BIT);
    std::vector<float> r(static_cast<std::size_t>(w) * h);
    glGetTextureImage(radii.id(), 0, GL_RED, GL_FLOAT, static_cast<GLsizei>(r.size() * sizeof(float)), r.data());
    EXPECT_EQ(std::count(r.begin(), r.end(), -1.0f), 0) << "every search found its pages";
    return std::count_if(r.begin(), r.end(), [](float v) { return v > 0; });
  };
  EXPECT_EQ(blocked(plane_scene, true), 0) << "the slope is not its own blocker";
  const auto flat = blocked(plane_scene, false);
  EXPECT_GT(flat, w * h / 2) << "against one depth, the slope shadows itself";
  const auto under_box = blocked(with_box, true);
  RecordProperty("self_blocked_without_the_plane", static_cast<int>(flat));
  RecordProperty("blocked_by_the_box", static_cast<int>(under_box));
  EXPECT_GT(under_box, 50) << "the box's shadow on the slope";
  EXPECT_LT(under_box, w * h / 4);
}

// The renderer's box PCF through the virtual map (map.virtual_pages) on the demo scene: every
// pixel is shaded on the level its pages were marked on, and the image agrees with the same filter
// on one fine fitted map (4096²): mean difference 0.0022 at 320 × 180. The footprint's marking asks
// for more pages.
shadows::ShadowSettings virtual_pcf(shadows::VirtualPages marking) {
  shadows::ShadowSettings s;
  s.technique = shadows::Technique::pcf;
  s.pcf.kernel = shadows::Kernel::grid;
  s.pcf.radius = 0.12f;
  s.pcf.radius_unit = shadows::RadiusUnit::world;
  s.map.virtual_min_texel_px = 1;
  s.map.virtual_pages = marking;
  return s;
}

// PCSS (grid kernel) through the virtual map by the rule, the pixel floor at 1.
shadows::ShadowSettings virtual_pcss() {
  shadows::ShadowSettings s;
  s.technique = shadows::Technique::pcss;
  s.pcss.kernel = shadows::Kernel::grid;
  s.map.virtual_min_texel_px = 1;
  s.map.virtual_pages = shadows::VirtualPages::rule;
  return s;
}

TEST(VirtualMap, RendererShadesPcfThroughThePagesLikeAFineMap) {
  shadows::Renderer r;
  r.set_scene(scene::make_builtin_scene("demo"));
  const int w = 320, h = 180;
  const shadows::FrameInfo rule = r.render(virtual_pcf(shadows::VirtualPages::rule), w, h);
  const io::ImageF paged = r.read_visibility();
  ASSERT_TRUE(rule.virtual_map.has_value());
  const auto& v = *rule.virtual_map;
  EXPECT_EQ(rule.passes, (std::vector<std::string>{"virtual_positions", "virtual_mark", "virtual_admit", "virtual_draw", "virtual_bounds",
                                                    "virtual_table", "shading"}));
  EXPECT_GT(v.pages.requested, 0);
  EXPECT_EQ(v.pages.drawn, v.pages.requested) << "the first frame draws every page it marks";
  EXPECT_EQ(v.pages.missing, 0);
  EXPECT_GT(v.at_level, static_cast<std::uint64_t>(w * h / 2)) << "the ground fills most of the view";
  EXPECT_EQ(v.coarser, 0u);
  EXPECT_EQ(v.none, 0u);
  // A page: its 128² depths and the bounds of its 8 × 8 tiles (four floats each).
  EXPECT_EQ(v.resident_bytes, static_cast<std::uint64_t>(v.pages.resident) * (128 * 128 * 4 + 8 * 8 * 16));

  shadows::ShadowSettings fine = virtual_pcf(shadows::VirtualPages::off);
  fine.map.resolution_texels = 4096;
  r.render(fine, w, h);
  const io::ImageF single = r.read_visibility();
  double sum = 0, worst = 0;
  int partial = 0;
  for (std::size_t p = 0; p < paged.pixels.size(); ++p) {
    ASSERT_TRUE(std::isfinite(paged.pixels[p]) && paged.pixels[p] >= 0 && paged.pixels[p] <= 1) << p;
    const double d = std::abs(static_cast<double>(paged.pixels[p]) - single.pixels[p]);
    sum += d, worst = std::max(worst, d);
    partial += paged.pixels[p] > 0.05f && paged.pixels[p] < 0.95f;
  }
  const double mean = sum / static_cast<double>(paged.pixels.size());
  RecordProperty("mean_abs_vs_fine_map", std::to_string(mean));
  RecordProperty("largest_vs_fine_map", std::to_string(worst));
  EXPECT_GT(partial, w * h / 100) << "penumbrae, not only lit and shadowed";
  EXPECT_LT(mean, 0.01) << "the same filter on a finer texel grid";

  // Back to the pages after a frame of maps (the camera targets were made anew twice): the same
  // image and the same pixels, each shaded once.
  const shadows::FrameInfo again = r.render(virtual_pcf(shadows::VirtualPages::rule), w, h);
  EXPECT_EQ(again.virtual_map->at_level, v.at_level);
  EXPECT_EQ(r.read_visibility().pixels, paged.pixels);

  // At 960 × 540 a pixel's footprint is finer than r / c near the camera: the footprint's marking
  // asks for finer levels there, so more pages; the rule's floor is the same footprint, so never fewer.
  const int rule_pages = r.render(virtual_pcf(shadows::VirtualPages::rule), 960, 540).virtual_map->pages.requested;
  const int footprint_pages = r.render(virtual_pcf(shadows::VirtualPages::footprint), 960, 540).virtual_map->pages.requested;
  RecordProperty("pages_rule_vs_footprint_960x540", std::to_string(rule_pages) + " vs " + std::to_string(footprint_pages));
  EXPECT_GT(footprint_pages, rule_pages);
}

// PCSS through the pages on the demo scene: the pages of each pixel's blocker search are marked
// and drawn first, then those of the penumbra it finds; every pixel finds its pages, and the image
// agrees with PCSS's box filter on one fine fitted map (whose search is a Poisson disk: the
// penumbrae differ a little; mean difference 0.0043 at 320 × 180).
// The virtual map's steps are the frame's passes, each timed: PCF marks once, PCSS twice (its
// search's round suffixed), late marks read the previous frame's before the update and mark after
// it; every step the frame lists has one sample in the timer, and nothing else is timed.
TEST(VirtualMap, ItsStepsAreNamedPassesEachTimed) {
  shadows::Renderer r;
  r.set_scene(scene::make_builtin_scene("demo"));
  const int w = 160, h = 90;
  const shadows::ShadowSettings pcss = virtual_pcss();
  shadows::ShadowSettings late = virtual_pcf(shadows::VirtualPages::rule);
  late.map.virtual_marks_late = true;
  const std::vector<std::string> update = {"virtual_admit", "virtual_draw", "virtual_bounds", "virtual_table"};
  auto with = [](std::vector<std::string> head, const std::vector<std::string>& tail) {
    head.insert(head.end(), tail.begin(), tail.end());
    return head;
  };
  std::vector<std::string> pcss_steps = {"virtual_positions", "virtual_mark_search"};
  for (const std::string& u : update) pcss_steps.push_back(u + "_search");
  pcss_steps.push_back("virtual_mark");
  pcss_steps = with(pcss_steps, update);
  pcss_steps.push_back("shading");
  const struct {
    shadows::ShadowSettings settings;
    std::vector<std::string> passes;
  } cases[] = {
      {virtual_pcf(shadows::VirtualPages::rule), with(with({"virtual_positions", "virtual_mark"}, update), {"shading"})},
      {pcss, pcss_steps},
      {late, with(with({"virtual_positions", "virtual_read"}, update), {"virtual_mark", "shading"})},
  };
  for (const auto& c : cases) {
    gl::PassTimer timer(false);
    const shadows::FrameInfo info = r.render(c.settings, w, h, &timer);
    EXPECT_EQ(info.passes, c.passes) << shadows::technique_entry(c.settings.technique).name;
    const std::vector<gl::PassStats> stats = timer.stats();
    for (const std::string& pass : c.passes) {
      const auto it = std::find_if(stats.begin(), stats.end(), [&](const gl::PassStats& st) { return st.pass == pass; });
      ASSERT_NE(it, stats.end()) << pass << " was not timed";
      EXPECT_EQ(it->samples, 1) << pass;
      EXPECT_GE(it->median_ms, 0.0) << pass;
    }
    EXPECT_EQ(stats.size(), c.passes.size()) << "nothing timed that the frame does not list";
  }
}

// Issue 47: the virtual map's work counted per step, not per pass, so the pages' raster is not
// mixed with the camera's: virtual_draw submits exactly the triangles the map says it drew into
// pages, virtual_positions rasterizes the camera's pixels, the marking is compute alone. The
// shading through the pages reads each pixel's page table before its depths.
TEST(VirtualMap, ItsWorkIsCountedPerStepAndItsReadsPerPixel) {
  shadows::Renderer r;
  r.set_scene(scene::make_builtin_scene("demo"));
  r.set_count_work(true);
  const int w = 160, h = 90;
  for (const shadows::ShadowSettings& s : {virtual_pcf(shadows::VirtualPages::rule), virtual_pcss()}) {
    const std::string name(shadows::technique_entry(s.technique).name);
    const shadows::FrameInfo info = r.render(s, w, h);
    ASSERT_EQ(info.work.size(), info.passes.size()) << name;
    std::uint64_t draw_primitives = 0;
    for (std::size_t i = 0; i < info.work.size(); ++i) {
      const shadows::PassWork& p = info.work[i];
      EXPECT_EQ(p.pass, info.passes[i]);
      if (p.pass.starts_with("virtual_draw")) draw_primitives += p.primitives;
      if (p.pass.starts_with("virtual_mark")) {
        EXPECT_GT(p.compute_invocations, 0u) << p.pass;
        EXPECT_EQ(p.primitives, 0u) << p.pass;
      }
      if (p.pass == "virtual_positions") {
        EXPECT_GE(p.fragments, static_cast<std::uint64_t>(w * h / 2)) << name;
      }
    }
    EXPECT_EQ(draw_primitives, info.virtual_map->pages.triangles) << name << ": what the map counted as drawn into its pages";
    const shadows::ShadowReads reads = r.count_shading_reads();
    EXPECT_GE(reads.pixels, static_cast<std::uint64_t>(w * h / 2)) << name;
    EXPECT_GT(reads.per_pixel(reads.instructions), 1.0) << name << ": a table read, then the depths";
    if (name == "pcss") {  // its blocker search runs in the marking: 1.6 a pixel without it, 20.1 with (dae15a7)
      EXPECT_GT(reads.per_pixel(reads.instructions), 8.0) << "the blocker search's reads in the marking are counted too";
    }
  }
}

TEST(VirtualMap, RendererShadesPcssThroughThePagesOfItsSearchAndItsPenumbra) {
  shadows::Renderer r;
  r.set_scene(scene::make_builtin_scene("demo"));
  const int w = 320, h = 180;
  shadows::ShadowSettings s = virtual_pcss();
  const shadows::FrameInfo info = r.render(s, w, h);
  const io::ImageF paged = r.read_visibility();
  ASSERT_TRUE(info.virtual_map.has_value());
  const auto& v = *info.virtual_map;
  EXPECT_GT(v.search_pages, 0);
  EXPECT_GT(v.pages.requested, v.search_pages) << "the penumbrae's pages beside the searches'";
  EXPECT_EQ(v.pages.drawn - v.pages.widened, v.pages.requested) << "each drawn once, and the search's again for the penumbrae's tiles";
  EXPECT_EQ(v.coarser, 0u);
  EXPECT_EQ(v.none, 0u);
  EXPECT_GT(v.at_level, static_cast<std::uint64_t>(w * h / 2));

  s.map.virtual_pages = shadows::VirtualPages::off;
  s.map.resolution_texels = 4096;
  r.render(s, w, h);
  const io::ImageF single = r.read_visibility();
  double sum = 0;
  int shadowed = 0;
  for (std::size_t p = 0; p < paged.pixels.size(); ++p) {
    ASSERT_TRUE(std::isfinite(paged.pixels[p]) && paged.pixels[p] >= 0 && paged.pixels[p] <= 1) << p;
    sum += std::abs(static_cast<double>(paged.pixels[p]) - single.pixels[p]);
    shadowed += paged.pixels[p] < 0.5f;
  }
  const double mean = sum / static_cast<double>(paged.pixels.size());
  RecordProperty("mean_abs_vs_fine_map", std::to_string(mean));
  EXPECT_GT(shadowed, w * h / 50) << "the demo's casters shadow the ground";
  EXPECT_LT(mean, 0.02);
}

// The tiles' bounds change no image: PCF and PCSS through the pages on the demo scene with and
// without them (map.virtual_bounds), within the rounding of the filters' sums of weights.
TEST(VirtualMap, RendererImageIsTheSameWithOrWithoutTileBounds) {
  shadows::Renderer r;
  r.set_scene(scene::make_builtin_scene("demo"));
  const shadows::ShadowSettings pcss = virtual_pcss();
  for (shadows::ShadowSettings s : {virtual_pcf(shadows::VirtualPages::rule), pcss}) {
    SCOPED_TRACE(s.technique == shadows::Technique::pcf ? "pcf" : "pcss");
    s.map.virtual_bounds = true;
    const shadows::FrameInfo with = r.render(s, 320, 180);
    const io::ImageF a = r.read_visibility();
    s.map.virtual_bounds = false;
    const shadows::FrameInfo without = r.render(s, 320, 180);
    const io::ImageF b = r.read_visibility();
    EXPECT_EQ(with.virtual_map->pages.requested, without.virtual_map->pages.requested);
    EXPECT_EQ(with.virtual_map->at_level, without.virtual_map->at_level);
    EXPECT_LT(without.virtual_map->resident_bytes, with.virtual_map->resident_bytes) << "the bounds are counted";
    ASSERT_EQ(a.pixels.size(), b.pixels.size());
    float worst = 0;
    int shadowed = 0;
    for (std::size_t p = 0; p < a.pixels.size(); ++p) {
      worst = std::max(worst, std::abs(a.pixels[p] - b.pixels[p]));
      shadowed += b.pixels[p] < 0.5f;
    }
    EXPECT_LE(worst, 1e-5f);
    EXPECT_GT(shadowed, 320 * 180 / 50) << "shadows to compare";
  }
}

// VSM through the pages (moments drawn beside the depths, box-filtered at lookup on the marked
// level) on the demo scene against VSM on one fine fitted map (4096², moments blurred by the same
// world radius): the same shadows, penumbrae included, the pool holding moments.
TEST(VirtualMap, RendererShadesVsmThroughThePagesLikeAFineMap) {
  shadows::Renderer r;
  r.set_scene(scene::make_builtin_scene("demo"));
  const int w = 320, h = 180;
  shadows::ShadowSettings s;
  s.technique = shadows::Technique::vsm;
  s.vsm.radius = 0.12f;
  s.vsm.radius_unit = shadows::RadiusUnit::world;
  s.map.virtual_min_texel_px = 1;
  s.map.virtual_pages = shadows::VirtualPages::rule;
  const shadows::FrameInfo info = r.render(s, w, h);
  const io::ImageF paged = r.read_visibility();
  ASSERT_TRUE(info.virtual_map.has_value());
  EXPECT_EQ(info.passes, (std::vector<std::string>{"virtual_positions", "virtual_mark", "virtual_admit", "virtual_draw", "virtual_table",
                                                    "shading"}))
      << "no moments atlas, no blur pass; moments pools have no depth bounds";
  EXPECT_EQ(info.virtual_map->coarser, 0u);
  EXPECT_EQ(info.virtual_map->none, 0u);
  EXPECT_GT(info.virtual_map->at_level, static_cast<std::uint64_t>(w * h / 2));

  s.map.virtual_pages = shadows::VirtualPages::off;
  s.map.resolution_texels = 4096;
  r.render(s, w, h);
  const io::ImageF single = r.read_visibility();
  double sum = 0;
  int partial = 0, shadowed = 0;
  for (std::size_t p = 0; p < paged.pixels.size(); ++p) {
    ASSERT_TRUE(std::isfinite(paged.pixels[p]) && paged.pixels[p] >= 0 && paged.pixels[p] <= 1) << p;
    sum += std::abs(static_cast<double>(paged.pixels[p]) - single.pixels[p]);
    partial += paged.pixels[p] > 0.05f && paged.pixels[p] < 0.95f;
    shadowed += paged.pixels[p] < 0.5f;
  }
  const double mean = sum / static_cast<double>(paged.pixels.size());
  RecordProperty("mean_abs_vs_fine_map", std::to_string(mean));
  EXPECT_GT(shadowed, w * h / 50) << "the demo's casters shadow the ground";
  EXPECT_GT(partial, w * h / 100) << "penumbrae, not only lit and shadowed";
  EXPECT_LT(mean, 0.01);
}

// The cache across frames: a second frame of the same view draws nothing, uncached it draws every
// page again; a caster moved between frames redraws only the pages over its two places, with no
// stale depth left; a pool of one slot cannot hold the view: pixels fall back to a coarser level or are
// lit, counted, and the image stays finite.
TEST(VirtualMap, RendererCachesPagesRedrawsAMovedCasterAndCountsWhatAFullPoolCannotHold) {
  shadows::Renderer r;
  r.set_scene(scene::make_builtin_scene("demo"));
  const int w = 160, h = 90;
  shadows::ShadowSettings s = virtual_pcf(shadows::VirtualPages::rule);
  const auto first = r.render(s, w, h).virtual_map->pages;
  const auto second = r.render(s, w, h).virtual_map->pages;
  EXPECT_EQ(second.drawn, 0);
  EXPECT_EQ(second.cached, first.requested);
  s.map.virtual_cache = false;
  const auto uncached = r.render(s, w, h).virtual_map->pages;
  EXPECT_EQ(uncached.drawn, uncached.requested);
  s.map.virtual_cache = true;
  r.render(s, w, h);

  // A caster moves between frames (the box, 1.5 m along x): the renderer drops the pages over its
  // old and its new place and redraws only those; the image equals one drawn with no cache at all.
  auto& objects = r.scene().objects;
  const auto box = std::find_if(objects.begin(), objects.end(), [](const scene::Object& o) { return o.name == "box"; });
  ASSERT_NE(box, objects.end());
  box->model = glm::translate(glm::mat4(1), glm::vec3(1.5f, 0, 0)) * box->model;
  const auto moved = r.render(s, w, h).virtual_map->pages;
  const io::ImageF cached_image = r.read_visibility();
  EXPECT_GT(moved.invalidated, 0);
  EXPECT_GT(moved.drawn, 0);
  EXPECT_LT(moved.drawn, moved.requested) << "pages away from the box stay";
  s.map.virtual_cache = false;
  r.render(s, w, h);
  const io::ImageF fresh = r.read_visibility();
  float worst = 0;
  for (std::size_t p = 0; p < fresh.pixels.size(); ++p) worst = std::max(worst, std::abs(fresh.pixels[p] - cached_image.pixels[p]));
  EXPECT_EQ(worst, 0.0f) << "no stale page under the moved box";
  s.map.virtual_cache = true;

  // A pool of 4 slots cannot hold the view: the demo's ground straddles the light-space origin, a
  // page corner of every level, and the floor is the four pages of a coarse level around it.
  // Pixels whose pages are missing read it; none is shaded lit for want of a page, and the shadow
  // stays where the full pool puts it.
  s.map.virtual_cache = false;
  r.render(s, w, h);
  const io::ImageF full = r.read_visibility();
  s.map.virtual_pool_pages = 2;
  const shadows::FrameInfo small = r.render(s, w, h);
  const auto& v = *small.virtual_map;
  EXPECT_EQ(v.pages.resident, 4);
  EXPECT_GT(v.pages.floor_level, 0);
  EXPECT_EQ(v.pages.missing + 4, v.pages.requested + v.pages.floor);
  EXPECT_GT(v.coarser, 0u) << "pixels whose pages the pool could not hold";
  EXPECT_EQ(v.none, 0u) << "a pixel shaded lit for want of a page";
  EXPECT_NE(shadows::missing_pages_warning(v.pages, v.pool_pages_per_side), "");
  const io::ImageF floor = r.read_visibility();
  int dark_full = 0, dark_floor = 0;
  for (std::size_t p = 0; p < full.pixels.size(); ++p) {
    ASSERT_TRUE(std::isfinite(floor.pixels[p]) && floor.pixels[p] >= 0 && floor.pixels[p] <= 1);
    dark_full += full.pixels[p] < 0.5f, dark_floor += floor.pixels[p] < 0.5f;
  }
  EXPECT_GT(dark_full, 30);
  EXPECT_GT(dark_floor, dark_full / 2) << "the shadows went with the missing pages";
  // One slot cannot hold even the coarsest level's four pages there: refused, not shaded lit.
  s.map.virtual_pool_pages = 1;
  EXPECT_THROW(r.render(s, w, h), shadows::PoolTooSmall);
}

// Issue 47: with map.virtual_marks_late a frame draws the pages the previous frame marked, read a
// frame late: no read-back of this frame's GPU work is waited for (counted: zero, against one or
// two without). The first frame after a cut has no marks: every pixel reads the coarse floor over
// the sun's region, none is shaded lit, every value finite; the next frame reads the first one's
// marks and draws what the same-frame marking draws, and the image is that image.
TEST(VirtualMap, MarksReadAFrameLateWaitForNothingAndTheFirstFrameIsCoarseNotLit) {
  for (const bool pcss : {false, true}) {
    SCOPED_TRACE(pcss ? "pcss" : "pcf");
    shadows::ShadowSettings s = pcss ? virtual_pcss() : virtual_pcf(shadows::VirtualPages::rule);
    const int w = 160, h = 90;
    shadows::Renderer same_frame;
    same_frame.set_scene(scene::make_builtin_scene("demo"));
    const shadows::FrameInfo now = same_frame.render(s, w, h);
    EXPECT_EQ(now.virtual_map->sync_reads, pcss ? 3 : 2) << "the marks and the shaded pixels' counts, read at once";
    const io::ImageF reference = same_frame.read_visibility();

    s.map.virtual_marks_late = true;
    shadows::Renderer late;
    late.set_scene(scene::make_builtin_scene("demo"));
    const shadows::FrameInfo cut = late.render(s, w, h);
    const auto& v = *cut.virtual_map;
    EXPECT_EQ(v.sync_reads, 0);
    EXPECT_TRUE(v.marks_late);
    EXPECT_GT(v.region_floor, 0);
    EXPECT_EQ(v.pages.requested, v.region_floor) << "no marks yet: the floor alone";
    EXPECT_FALSE(v.shaded_of_previous_frame);
    const io::ImageF first = late.read_visibility();
    int dark = 0;
    for (float p : first.pixels) {
      ASSERT_TRUE(std::isfinite(p) && p >= 0 && p <= 1);
      dark += p < 0.5f;
    }
    EXPECT_GT(dark, w * h / 100) << "the first frame keeps its shadows, coarse";

    const shadows::FrameInfo second = late.render(s, w, h);
    const auto& v2 = *second.virtual_map;
    EXPECT_EQ(v2.sync_reads, 0);
    EXPECT_TRUE(v2.shaded_of_previous_frame);
    const std::uint64_t surface = now.virtual_map->at_level + now.virtual_map->coarser;
    EXPECT_EQ(v2.at_level + v2.coarser, surface) << "the first frame's pixels, counted";
    EXPECT_GT(v2.coarser, 0u) << "pixels read the floor, coarser than their own level";
    EXPECT_EQ(v2.none, 0u) << "none shaded lit for want of a page";
    // The camera stands still: the second frame draws what the first marked, and besides it the
    // floor. PCSS's first marks searched the floor alone, so its penumbrae settle a frame later.
    EXPECT_LE(v2.pages.requested, now.virtual_map->pages.requested + v2.region_floor);
    if (!pcss) {
      EXPECT_GE(v2.pages.requested, now.virtual_map->pages.requested);
    }
    late.render(s, w, h);
    const io::ImageF settled = late.read_visibility();
    const shadows::FrameInfo fourth = late.render(s, w, h);
    EXPECT_EQ(fourth.virtual_map->coarser, 0u) << "the third frame's pixels all found their own level";
    EXPECT_EQ(fourth.virtual_map->at_level, surface);
    double diff = 0;
    for (std::size_t p = 0; p < settled.pixels.size(); ++p) diff = std::max(diff, std::abs(double(settled.pixels[p]) - reference.pixels[p]));
    // PCF's settled frame is the same-frame marking's image. PCSS's searches read the pages then
    // resident: a frame late that is more of them (the previous frame's penumbrae besides the
    // searches'), and a few penumbrae come out a little different.
    EXPECT_LT(diff, pcss ? 1e-3 : 1e-6) << "a settled frame is the same-frame marking's image";
  }
}

// Uncached (map.virtual_cache false), a frame is drawn anew: its image is the same whatever the
// renderer drew before it (other views, whose pages took other slots of the pool), to the bit.
TEST(VirtualMap, AnUncachedFrameIsTheSameAfterAnyOtherFrames) {
  const scene::Scene town = scene::make_builtin_scene("outdoor");
  const scene::Camera here = town.camera_path.at(town.camera, 120), elsewhere = town.camera_path.at(town.camera, 240);
  const int w = 240, h = 135;
  for (const bool pcss : {false, true}) {
    SCOPED_TRACE(pcss ? "pcss" : "pcf");
    shadows::ShadowSettings s = pcss ? virtual_pcss() : virtual_pcf(shadows::VirtualPages::rule);
    s.map.virtual_cache = false;
    shadows::Renderer first;
    first.set_scene(town);
    first.scene().camera = here;
    first.render(s, w, h);
    const io::ImageF expected = first.read_visibility();

    shadows::Renderer after;
    after.set_scene(town);
    after.scene().camera = elsewhere;
    after.render(s, w, h);
    after.scene().camera = here;
    after.render(s, w, h);
    const io::ImageF got = after.read_visibility();
    ASSERT_EQ(got.pixels.size(), expected.pixels.size());
    int differ = 0;
    for (std::size_t p = 0; p < got.pixels.size(); ++p) differ += got.pixels[p] != expected.pixels[p];
    EXPECT_EQ(differ, 0) << "of " << got.pixels.size() << " pixels";
  }
}

// map.virtual_page_tiles: an uncached frame draws each page with the casters over the tiles its
// pixels marked only (PCSS's search pages drawn again for the penumbrae's tiles). The image is the
// same to the bit as with whole pages, while fewer triangles are drawn: over three frames of the
// street at 240 × 135, 56 % fewer for PCF and PCSS (at 960 × 540 one frame draws 295 292 -> 240 612
// for PCF and 934 052 -> 519 068 for PCSS). Cached frames draw whole pages either way (drawing a
// page again for each new tile had cost 13 % (PCF) and 20 % (PCSS) fewer triangles here, but ten
// times more along the main job's walk).
TEST(VirtualMap, PagesDrawnByTheirMarkedTilesGiveTheSameImageWithFewerTriangles) {
  const scene::Scene town = scene::make_builtin_scene("outdoor");
  const int w = 240, h = 135;
  for (const bool pcss : {false, true}) {
    for (const bool cached : {false, true}) {
      SCOPED_TRACE(std::string(pcss ? "pcss" : "pcf") + (cached ? ", cached" : ", uncached"));
      shadows::ShadowSettings s = pcss ? virtual_pcss() : virtual_pcf(shadows::VirtualPages::rule);
      s.map.virtual_cache = cached;
      std::int64_t triangles[2] = {0, 0};
      std::vector<io::ImageF> images[2];
      for (const bool tiles : {false, true}) {
        s.map.virtual_page_tiles = tiles;
        shadows::Renderer r;
        r.set_scene(town);
        for (const int frame : {120, 126, 132}) {  // a walking camera: cached pages asked for new tiles
          r.scene().camera = town.camera_path.at(town.camera, frame);
          const shadows::FrameInfo info = r.render(s, w, h);
          ASSERT_TRUE(info.virtual_map.has_value());
          EXPECT_EQ(info.virtual_map->pages.missing, 0);
          triangles[tiles] += info.virtual_map->pages.triangles;
          images[tiles].push_back(r.read_visibility());
        }
      }
      for (std::size_t f = 0; f < images[0].size(); ++f) {
        ASSERT_EQ(images[1][f].pixels.size(), images[0][f].pixels.size());
        int differ = 0;
        for (std::size_t p = 0; p < images[0][f].pixels.size(); ++p) differ += images[1][f].pixels[p] != images[0][f].pixels[p];
        EXPECT_EQ(differ, 0) << "frame " << f << ": of " << images[0][f].pixels.size() << " pixels";
      }
      if (cached) {
        EXPECT_EQ(triangles[1], triangles[0]) << "cached pages are drawn whole";
      } else {
        EXPECT_LT(triangles[1], triangles[0] * 0.6) << triangles[1] << " against " << triangles[0];
      }
      ::testing::Test::RecordProperty(std::string(pcss ? "pcss" : "pcf") + (cached ? "_cached" : "") + "_triangles_whole", static_cast<int>(triangles[0]));
      ::testing::Test::RecordProperty(std::string(pcss ? "pcss" : "pcf") + (cached ? "_cached" : "") + "_triangles_tiles", static_cast<int>(triangles[1]));
    }
  }
}

// Uncached (map.virtual_cache false), late marks keep the region floor resident: from the second
// frame on its pages are cached, not drawn again, and a frame draws the triangles of the pages its
// marks asked for, no more than the same-frame marking draws (before, the floor was redrawn every
// frame and doubled the triangles on the street).
TEST(VirtualMap, UncachedLateMarksKeepTheFloorAndDrawNoMoreThanSameFrameMarks) {
  shadows::ShadowSettings s = virtual_pcf(shadows::VirtualPages::rule);
  s.map.virtual_cache = false;
  s.map.virtual_page_tiles = false;  // whole pages, as late marks draw them
  const int w = 160, h = 90;
  shadows::Renderer same_frame;
  same_frame.set_scene(scene::make_builtin_scene("demo"));
  same_frame.render(s, w, h);
  const shadows::FrameInfo now = same_frame.render(s, w, h);
  EXPECT_EQ(now.virtual_map->pages.cached, 0) << "uncached: every page drawn every frame";
  s.map.virtual_marks_late = true;
  shadows::Renderer late;
  late.set_scene(scene::make_builtin_scene("demo"));
  const shadows::FrameInfo cut = late.render(s, w, h);
  EXPECT_EQ(cut.virtual_map->pages.drawn, cut.virtual_map->region_floor);
  for (int frame = 1; frame < 4; ++frame) {
    const shadows::FrameInfo f = late.render(s, w, h);
    const auto& v = *f.virtual_map;
    SCOPED_TRACE(frame);
    EXPECT_EQ(v.sync_reads, 0);
    EXPECT_GE(v.pages.cached, v.region_floor) << "the floor stays resident";
    EXPECT_LE(v.pages.drawn, now.virtual_map->pages.drawn) << "the marked pages alone are drawn";
    EXPECT_LE(v.pages.triangles, now.virtual_map->pages.triangles);
    EXPECT_GT(v.pages.triangles, 0u);
  }
  // A cut: the last frame's marks lie where the camera was; the next frame draws the floor alone.
  late.camera_cut();
  const shadows::FrameInfo after_cut = late.render(s, w, h);
  EXPECT_EQ(after_cut.virtual_map->pages.requested, after_cut.virtual_map->region_floor);
  EXPECT_EQ(after_cut.virtual_map->pages.drawn, 0) << "the floor was resident";
  const int requested = late.render(s, w, h).virtual_map->pages.requested;  // the cut frame's marks and the floor
  EXPECT_GE(requested, now.virtual_map->pages.requested) << "the frame after it reads the cut frame's marks";
  EXPECT_LE(requested, now.virtual_map->pages.requested + after_cut.virtual_map->region_floor);
}

TEST(VirtualMap, BadLayoutsAreRefused) {
  VirtualMapLayout l = small_layout();
  l.levels = shadows::contract::VIRTUAL_MAX_LEVELS + 1;
  EXPECT_THROW(VirtualShadowMap(l, 4), std::invalid_argument);
  l = small_layout();
  EXPECT_THROW(VirtualShadowMap(l, 0), std::invalid_argument);
  Fixture f;
  VirtualShadowMap virtual_map(small_layout(), 4);
  EXPECT_THROW(virtual_map.update({{0, 8, 0}}, f.view, f.scene, f.meshes), std::invalid_argument) << "page outside the window";
}

// The shading reads the filter's square around the surface point moved along its normal
// (map.normal_offset_texels): the marking marks each square that much wider, so that the pages
// and tiles that square reads are its own (a page only other pixels' tiles drew would hold no
// casters where it reads; a page nobody marked would send it to a coarser level). Before the reach
// was marked, an offset of 4 texels read tiles nobody had drawn: 3 pixels of the street differed
// from whole pages.
TEST(VirtualMap, EveryPixelReadsItsOwnLevelWhateverTheNormalOffset) {
  const scene::Scene town = scene::make_builtin_scene("outdoor");
  const int w = 240, h = 135;
  for (const bool pcss : {false, true}) {
    for (const float offset : {0.75f, 4.0f}) {
      SCOPED_TRACE(std::string(pcss ? "pcss" : "pcf") + ", normal offset " + std::to_string(offset));
      shadows::ShadowSettings s = pcss ? virtual_pcss() : virtual_pcf(shadows::VirtualPages::rule);
      s.map.virtual_cache = false;
      s.map.normal_offset_texels = offset;
      std::vector<io::ImageF> images;
      for (const bool tiles : {false, true}) {
        s.map.virtual_page_tiles = tiles;
        shadows::Renderer r;
        r.set_scene(town);
        r.scene().camera = town.camera_path.at(town.camera, 126);
        const shadows::FrameInfo info = r.render(s, w, h);
        ASSERT_TRUE(info.virtual_map.has_value());
        EXPECT_EQ(info.virtual_map->pages.missing, 0);
        EXPECT_GT(info.virtual_map->at_level, 0u);
        EXPECT_EQ(info.virtual_map->coarser, 0u) << "pixels that read a coarser level than they asked for";
        images.push_back(r.read_visibility());
      }
      int differ = 0;
      for (std::size_t p = 0; p < images[0].pixels.size(); ++p) differ += images[1].pixels[p] != images[0].pixels[p];
      EXPECT_EQ(differ, 0) << "tiles against whole pages, of " << images[0].pixels.size() << " pixels";
    }
  }
}

}  // namespace
}  // namespace penumbra
