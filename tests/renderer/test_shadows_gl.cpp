// The shadow techniques against analytic expectations (label `gl`: needs an OpenGL 4.5 context;
// Mesa llvmpipe through EGL is enough).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "gl/timer.h"
#include "gl_test_env.h"
#include "scene/scene.h"
#include "shadows/frame_plan.h"
#include "shadows/renderer.h"
#include "shadows/settings_rows.h"

namespace penumbra {
namespace {

using shadows::Kernel;
using shadows::ShadowSettings;
using shadows::Technique;
using test::column_means;
using test::crossing;
using test::look_down;
using test::pixel_to_world;
using test::render_visibility;
using test::settings;

// Distance (world units) between the first column above `lo` and the last column below `hi`
// of an increasing profile.
double transition_width(const std::vector<double>& profile, double lo, double hi, float ws_per_px) {
  int first = -1, last = -1;
  for (int i = 0; i < static_cast<int>(profile.size()); ++i) {
    if (first < 0 && profile[static_cast<std::size_t>(i)] > lo) first = i;
    if (profile[static_cast<std::size_t>(i)] < hi) last = i;
  }
  return (last - first + 1) * static_cast<double>(ws_per_px);
}

// ---- 1. hard shadow footprint ------------------------------------------------------------------

class HardShadow : public ::testing::TestWithParam<bool> {};

TEST_P(HardShadow, FootprintMatchesTheAnalyticSquareWithinOneTexel) {
  const bool fit = GetParam();
  scene::Scene s = scene::make_square_scene(2, 1);
  look_down(s, {0, 0}, 2);
  const int n = 400, res = 256;
  shadows::Renderer r;
  r.set_scene(s);
  const auto info = r.render(settings(Technique::hard, res, fit), n, n);
  const io::ImageF vis = r.read_visibility();
  const float texel = info.light.texel_ws(0, res);
  int checked = 0, wrong = 0;
  for (int y = 0; y < n; ++y) {
    for (int x = 0; x < n; ++x) {
      const float wx = pixel_to_world(x, n, 0, 2), wz = pixel_to_world(y, n, 0, 2);
      const float edge_distance = std::abs(std::max(std::abs(wx), std::abs(wz)) - 1.0f);
      if (edge_distance <= texel) continue;  // the staircase may fall either way within one texel
      const bool inside = std::abs(wx) < 1 && std::abs(wz) < 1;
      ++checked;
      if (vis.at(x, y) != (inside ? 0.0f : 1.0f)) ++wrong;
    }
  }
  EXPECT_GT(checked, n * n / 2);
  EXPECT_EQ(wrong, 0) << "texel " << texel << " ws, fitted " << info.light.fitted;
  if (fit) {
    EXPECT_GT(info.light.s_xy, 1.5f);  // the view covers far less than the 10×10 ground
  }
}

INSTANTIATE_TEST_SUITE_P(Fitting, HardShadow, ::testing::Values(false, true),
                         [](const auto& p) { return p.param ? "fitted" : "unfitted"; });

// ---- 2. PCF across a straight edge -------------------------------------------------------------

struct EdgeCase {
  Kernel kernel;
  float radius_texels;
};

class PcfEdge : public ::testing::TestWithParam<EdgeCase> {};

TEST_P(PcfEdge, HalfAtTheEdgeMonotoneAndTwoRadiiWide) {
  const auto [kernel, radius] = GetParam();
  // Unfitted map over the 10×10 ground: 250 texels put the square's edge x = 1 on a texel border.
  scene::Scene s = scene::make_square_scene(2, 1);
  const float half = 0.5f;
  look_down(s, {1, 0}, half);
  const int n = 400, res = 250;
  const float texel = 10.0f / res, ws_per_px = 2 * half / n;
  ShadowSettings st = settings(Technique::pcf, res, false);
  st.pcf.kernel = kernel;
  st.pcf.radius = radius;
  const io::ImageF vis = render_visibility(s, st, n);
  ASSERT_TRUE(test::all_finite_in(vis, 0, 1));
  const auto profile = column_means(vis, n / 2 - 100, n / 2 + 100);  // z in ±0.25, far from corners
  const float x0 = 1 - half;
  EXPECT_NEAR(crossing(profile, 0.5, x0, ws_per_px), 1.0, 0.1 * texel);
  for (std::size_t i = 1; i < profile.size(); ++i) EXPECT_GE(profile[i], profile[i - 1] - 0.01) << "column " << i;
  EXPECT_LT(profile.front(), 0.01);
  EXPECT_GT(profile.back(), 0.99);
  const double width = transition_width(profile, 0.01, 0.99, ws_per_px);
  EXPECT_NEAR(width, 2 * radius * texel, texel) << "transition " << width / texel << " texels for r = " << radius;
}

INSTANTIATE_TEST_SUITE_P(Kernels, PcfEdge,
                         ::testing::Values(EdgeCase{Kernel::grid, 1.0f}, EdgeCase{Kernel::grid, 2.5f},
                                           EdgeCase{Kernel::grid, 4.0f}, EdgeCase{Kernel::poisson, 2.5f},
                                           EdgeCase{Kernel::poisson, 4.0f}, EdgeCase{Kernel::disk, 2.5f},
                                           EdgeCase{Kernel::disk, 4.0f}),
                         [](const auto& p) {
                           return std::string(p.param.kernel == Kernel::grid ? "grid" : p.param.kernel == Kernel::disk ? "disk" : "poisson") + "_r" +
                                  std::to_string(static_cast<int>(p.param.radius_texels * 10));
                         });

TEST(PcfGrid, LinearRampForABoxFilter) {
  // The coverage-weighted box turns a texel-aligned step into an exactly linear ramp.
  scene::Scene s = scene::make_square_scene(2, 1);
  look_down(s, {1, 0}, 0.5f);
  const int n = 400, res = 250;
  const float texel = 10.0f / res, ws_per_px = 1.0f / n, radius = 3.0f;
  ShadowSettings st = settings(Technique::pcf, res, false);
  st.pcf.kernel = Kernel::grid;
  st.pcf.radius = radius;
  shadows::Renderer r;
  r.set_scene(s);
  r.render(st, n, n);
  const auto profile = column_means(r.read_visibility(), 150, 250);
  for (int i = 0; i < n; ++i) {
    const double x = 0.5 + (i + 0.5) * ws_per_px;
    const double expected = std::clamp((x - 1.0) / (2 * radius * texel) + 0.5, 0.0, 1.0);
    EXPECT_NEAR(profile[static_cast<std::size_t>(i)], expected, 2e-3) << "x = " << x;
  }
}

// ---- 3. PCSS -------------------------------------------------------------------------------------

TEST(Pcss, PenumbraMatchesTheParallelPlanesFormula) {
  const float light_height = 10, light_width = 1;
  double previous = 0;
  for (float blocker_height : {2.0f, 3.0f, 5.0f}) {
    scene::Scene s = scene::make_two_planes_scene(blocker_height, light_height, light_width);
    const float half = 1.0f;
    look_down(s, {0, 0}, half);
    const int n = 800;
    const float ws_per_px = 2 * half / n;
    ShadowSettings st = settings(Technique::pcss, 2048, true);
    st.pcss.kernel = Kernel::grid;
    st.pcss.min_penumbra_ws = 0;
    const io::ImageF vis = render_visibility(s, st, n);
    ASSERT_TRUE(test::all_finite_in(vis, 0, 1));
    const auto profile = column_means(vis, n / 2 - 50, n / 2 + 50);
    // 10-90 % of a linear ramp is 80 % of its full width.
    const double x10 = crossing(profile, 0.1, -half, ws_per_px), x90 = crossing(profile, 0.9, -half, ws_per_px);
    const double measured = (x90 - x10) / 0.8;
    const double z_r = light_height, z_b = light_height - blocker_height;
    const double expected = light_width * (z_r - z_b) / z_b;
    EXPECT_NEAR(measured, expected, 0.1 * expected) << "blocker at " << blocker_height;
    RecordProperty("penumbra_ws_h" + std::to_string(static_cast<int>(blocker_height)), std::to_string(measured) + " vs " + std::to_string(expected));
    EXPECT_GT(measured, previous) << "penumbra must widen as the blocker rises";
    previous = measured;
    EXPECT_NEAR(crossing(profile, 0.5, -half, ws_per_px), 0.0, 0.05 * expected) << "centred on the blocker's edge";
    // Far from the blocker nothing is found: fully lit, exactly.
    for (int x = n - 20; x < n; ++x) EXPECT_EQ(vis.at(x, n / 2), 1.0f);
  }
}

// The min-max depth pyramid PCSS bounds its search with (depth_minmax pass): after a frame that
// moved the maps within a larger atlas (stale texels around them), every pyramid texel bounds
// the depths of the map texels under it (min below, max above), is exact where its block lies
// inside one map with its guard band, and says (0, 1) where it cannot know.
TEST(PcssHierarchy, PyramidBoundsEveryMapTexelAndIsExactInsideAMap) {
  scene::Scene s = scene::load_scene("demo");
  shadows::Renderer r;
  r.set_scene(s);
  ShadowSettings st = settings(Technique::pcss, 512, true);
  st.map.cascades = 3;
  st.adaptive.enabled = true;  // sub-rectangles of a 3 x 256^2 atlas: room for stale texels
  st.adaptive.max_texels = 256;
  st.adaptive.shrink_delay_frames = 0;
  st.pcss.hierarchical = true;
  r.render(st, 320, 180);
  r.scene().camera.position = r.scene().camera.target + 0.4f * (r.scene().camera.position - r.scene().camera.target);
  const shadows::FrameInfo info = r.render(st, 320, 180);
  ASSERT_NE(r.depth_minmax_texture(), 0u);
  const int w = info.atlas_width, h = info.atlas_height;
  std::vector<float> depth(static_cast<std::size_t>(w) * h);
  glGetTextureImage(r.shadow_map_texture(), 0, GL_DEPTH_COMPONENT, GL_FLOAT, static_cast<GLsizei>(depth.size() * sizeof(float)),
                    depth.data());
  // Each map's region with its guard band, as the shadow-map pass drew and cleared it.
  std::vector<glm::ivec4> regions;
  for (const auto& c : info.cascades) {
    const int g = shadows::kGuardTexels;
    regions.push_back({c.atlas_x - g, c.atlas_y - g, c.atlas_x + c.resolution_texels + g, c.atlas_y + c.resolution_texels + g});
  }
  auto in_map = [&](int x, int y) {
    for (const auto& g : regions)
      if (x >= g.x && x < g.z && y >= g.y && y < g.w) return true;
    return false;
  };
  GLint levels = 0;
  glGetTextureParameteriv(r.depth_minmax_texture(), GL_TEXTURE_IMMUTABLE_LEVELS, &levels);
  ASSERT_GE(levels, 8);
  long exact = 0, bounded = 0, unknown = 0;
  for (int k = 0; k < levels; ++k) {
    GLint lw = 0, lh = 0;
    glGetTextureLevelParameteriv(r.depth_minmax_texture(), k, GL_TEXTURE_WIDTH, &lw);
    glGetTextureLevelParameteriv(r.depth_minmax_texture(), k, GL_TEXTURE_HEIGHT, &lh);
    std::vector<glm::vec2> level(static_cast<std::size_t>(lw) * lh);
    glGetTextureImage(r.depth_minmax_texture(), k, GL_RG, GL_FLOAT, static_cast<GLsizei>(level.size() * sizeof(glm::vec2)), level.data());
    const int block = 2 << k;
    for (int by = 0; by < lh; ++by)
      for (int bx = 0; bx < lw; ++bx) {
        float lo = 1, hi = 0;
        bool any = false, inside_one = false;
        for (const auto& g : regions)
          inside_one |= bx * block >= g.x && (bx + 1) * block <= g.z && by * block >= g.y && (by + 1) * block <= g.w;
        for (int y = by * block; y < std::min((by + 1) * block, h); ++y)
          for (int x = bx * block; x < std::min((bx + 1) * block, w); ++x)
            if (in_map(x, y)) {
              const float d = depth[static_cast<std::size_t>(y) * w + x];
              lo = std::min(lo, d), hi = std::max(hi, d), any = true;
            }
        const glm::vec2 v = level[static_cast<std::size_t>(by) * lw + bx];
        if (!any) continue;  // nothing a lookup reads
        ASSERT_LE(v.x, lo) << "level " << k << " block " << bx << "," << by;
        ASSERT_GE(v.y, hi) << "level " << k << " block " << bx << "," << by;
        if (inside_one) {
          ASSERT_EQ(v.x, lo) << "level " << k << " block " << bx << "," << by;
          ASSERT_EQ(v.y, hi) << "level " << k << " block " << bx << "," << by;
          ++exact;
        } else {
          ++(v == glm::vec2(0, 1) ? unknown : bounded);
        }
      }
  }
  EXPECT_GT(exact, 1000);
  EXPECT_GT(unknown, 0) << "blocks across a map's edge must not claim to know";
  RecordProperty("blocks", std::to_string(exact) + " exact, " + std::to_string(bounded) + " bounded, " + std::to_string(unknown) + " unknown");
}

// The bounds change what PCSS costs, not what it shows: wherever the full blocker search found a
// blocker the hierarchical image equals it (lit and umbra decided by the pyramid, the clamp to the
// minimum penumbra taken without a search, are the search's own answers); where the sparse
// Poisson search found none and called the pixel lit, the filter at the minimum penumbra may see
// blockers it missed (darker, never lighter). Every kernel, the demo scene with cascades, and the
// two planes with a wide penumbra.
TEST(PcssHierarchy, ImageEqualsTheFullSearchWhereTheSearchFoundBlockers) {
  for (const std::string name : {"demo", "two-planes"}) {
    for (Kernel k : {Kernel::grid, Kernel::poisson, Kernel::disk}) {
      SCOPED_TRACE(name + " " + std::string(shadows::rows::kKernels[static_cast<int>(k)]));
      scene::Scene s = scene::load_scene(name);
      ShadowSettings full = settings(Technique::pcss, 1024, true);
      full.pcss.kernel = k;
      full.pcss.min_penumbra_ws = 0.05f;
      full.map.cascades = name == "demo" ? 3 : 1;
      full.pcss.hierarchical = false;
      ShadowSettings hier = full;
      hier.pcss.hierarchical = true;
      const int n = 256;
      const io::ImageF a = render_visibility(s, full, n), b = render_visibility(s, hier, n);
      ASSERT_TRUE(test::all_finite_in(b, 0, 1));
      int shadowed = 0, darker = 0;
      for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
          const float va = a.at(x, y), vb = b.at(x, y);
          if (va < 1) {
            ++shadowed;
            ASSERT_NEAR(vb, va, 1e-5) << "pixel " << x << "," << y;
          } else if (vb < va - 1e-3f) {
            ++darker;
          } else {
            ASSERT_NEAR(vb, va, 1e-3) << "pixel " << x << "," << y;  // a filter's weights sum to 1 within rounding
          }
        }
      EXPECT_GT(shadowed, n * n / 50);
      EXPECT_LT(darker, n * n / 100) << "only pixels whose blockers the sparse search missed";
    }
  }
}

// ---- 4. VSM ------------------------------------------------------------------------------------

TEST(Vsm, TwoDepthsGiveTheChebyshevBoundAndMatchBoxPcf) {
  // One blocker depth and one receiver depth: with coverage f of the blocker in the filter box,
  // μ = f d1 + (1-f) d2, σ² = f(1-f)(d2-d1)², and the bound at t = d2 is exactly 1 - f — the
  // same value the box PCF of equal radius computes.
  scene::Scene s = scene::make_square_scene(2, 1);
  look_down(s, {1, 0}, 0.5f);
  const int n = 400, res = 250;
  ShadowSettings vsm = settings(Technique::vsm, res, false);
  vsm.vsm.radius = 3;
  vsm.vsm.bleed_reduction = 0;
  vsm.vsm.min_variance = 1e-9f;
  ShadowSettings pcf = settings(Technique::pcf, res, false);
  pcf.pcf.kernel = Kernel::grid;
  pcf.pcf.radius = 3;
  shadows::Renderer r;
  r.set_scene(s);
  r.render(vsm, n, n);
  const io::ImageF v = r.read_visibility();
  ASSERT_TRUE(test::all_finite_in(v, 0, 1));
  r.render(pcf, n, n);
  const io::ImageF p = r.read_visibility();
  const auto pv = column_means(v, 150, 250), pp = column_means(p, 150, 250);
  const double texel_over_box = 1.0 / (2 * 3.0);
  for (std::size_t i = 0; i < pv.size(); ++i) EXPECT_NEAR(pv[i], pp[i], 0.5 * texel_over_box) << "column " << i;
  EXPECT_NEAR(crossing(pv, 0.5, 0.5f, 1.0f / n), 1.0, 0.04 * 0.25);
}

TEST(Vsm, ChebyshevBoundIsFiniteForDegenerateMoments) {
  // Zero variance, receiver in front, receiver behind, huge blur, bleeding at its maximum.
  scene::Scene s = scene::make_square_scene(2, 1);
  look_down(s, {0, 0}, 2);
  for (float radius : {0.0f, 0.4f, 1.0f, 300.0f}) {
    for (float bleed : {0.0f, 0.999f}) {
      ShadowSettings st = settings(Technique::vsm, 128, true);
      st.vsm.radius = radius;
      st.vsm.bleed_reduction = bleed;
      st.vsm.min_variance = 0;
      shadows::Renderer r;
      r.set_scene(s);
      r.render(st, 64, 64);
      EXPECT_TRUE(test::all_finite_in(r.read_visibility(), 0, 1)) << "radius " << radius << " bleed " << bleed;
    }
  }
}

// ---- 6. extreme cases --------------------------------------------------------------------------

// Renders at a small size and checks both outputs are finite.
void expect_finite_render(const scene::Scene& s, const ShadowSettings& st, const std::string& what) {
  shadows::Renderer r;
  r.set_scene(s);
  r.render(st, 96, 64);
  EXPECT_TRUE(test::all_finite_in(r.read_visibility(), 0, 1)) << what;
  const io::Image8 c = r.read_color();
  EXPECT_EQ(c.pixels.size(), 96u * 64u * 4u) << what;
}

std::vector<ShadowSettings> every_technique(int resolution) {
  std::vector<ShadowSettings> out;
  for (auto name : shadows::technique_names()) {
    const Technique t = shadows::technique_from_string(name);
    for (Kernel k : {Kernel::grid, Kernel::poisson, Kernel::disk}) {
      if (k != Kernel::poisson && t != Technique::pcf && t != Technique::pcss) continue;
      ShadowSettings st = settings(t, resolution, true);
      st.pcf.kernel = k;
      st.pcss.kernel = k;
      out.push_back(st);
    }
  }
  ShadowSettings half_float = settings(Technique::evsm, resolution, true);
  half_float.evsm.format = shadows::MomentFormat::rgba16f;
  out.push_back(half_float);
  return out;
}

TEST(Extremes, NearFarRatioOf1e5) {
  scene::Scene s = scene::make_builtin_scene("demo");
  s.camera.near_ws = 1e-3f;
  s.camera.far_ws = 100;
  for (const auto& st : every_technique(512)) expect_finite_render(s, st, shadows::describe(st));
}

TEST(Extremes, LightAt89DegreesFromTheNormal) {
  scene::Scene s = scene::make_builtin_scene("demo");
  s.light.direction = glm::normalize(glm::vec3(std::cos(glm::radians(1.0f)), -std::sin(glm::radians(1.0f)), 0));
  for (const auto& st : every_technique(512)) expect_finite_render(s, st, shadows::describe(st));
  scene::Scene spot = scene::make_two_planes_scene(3, 10, 1);
  spot.light.position = {-20, 0.35f, 0};
  spot.light.direction = glm::normalize(glm::vec3(1, -0.0175f, 0));
  for (const auto& st : every_technique(512)) expect_finite_render(spot, st, "spot " + shadows::describe(st));
}

TEST(Extremes, FilterRadiusZeroAndThousandTexels) {
  const scene::Scene s = scene::make_builtin_scene("demo");
  for (float radius : {0.0f, 1000.0f}) {
    for (auto st : every_technique(512)) {
      st.pcf.radius = radius;
      st.vsm.radius = radius;
      st.rpcf.radius = radius;
      st.msm.radius = radius;
      st.evsm.radius = radius;
      expect_finite_render(s, st, shadows::describe(st));
    }
  }
  scene::Scene big_light = s;
  big_light.light.size = 89;  // PCSS search over almost the whole map
  for (const auto& st : every_technique(512)) expect_finite_render(big_light, st, "huge light " + shadows::describe(st));
}

TEST(Extremes, ResolutionOneTexel) {
  const scene::Scene s = scene::make_builtin_scene("demo");
  for (const auto& st : every_technique(1)) expect_finite_render(s, st, shadows::describe(st));
}

TEST(Extremes, EmptySceneAndNothingVisible) {
  const scene::Scene empty = scene::make_builtin_scene("empty");
  for (const auto& st : every_technique(256)) expect_finite_render(empty, st, "empty " + shadows::describe(st));
  scene::Scene away = scene::make_builtin_scene("box");
  away.camera.target = away.camera.position + glm::vec3(0, 1, 0.1f);  // looking at the sky
  for (const auto& st : every_technique(256)) expect_finite_render(away, st, "sky " + shadows::describe(st));
}

TEST(Extremes, DegenerateTriangles) {
  scene::Scene s = scene::make_builtin_scene("box");
  scene::MeshData junk;
  const glm::vec3 p(0, 3, 0);
  junk.vertices = {{p, {0, 1, 0}}, {p, {0, 1, 0}}, {p + glm::vec3(1, 0, 0), {0, 0, 0}}, {p + glm::vec3(2, 0, 0), {0, 1, 0}}};
  junk.indices = {0, 1, 2, 0, 2, 3, 1, 1, 1};  // repeated vertex, collinear, single point; a zero normal
  s.objects.push_back({"junk", std::make_shared<const scene::MeshData>(junk), glm::mat4(1), {1, 1, 1}});
  s.objects.push_back({"flat", std::make_shared<const scene::MeshData>(scene::make_box({1, 0, 1})),
                       glm::scale(glm::mat4(1), glm::vec3(1, 0, 1)), {1, 1, 1}});  // zero-height, singular model
  for (const auto& st : every_technique(256)) expect_finite_render(s, st, shadows::describe(st));
}

TEST(Extremes, MaximumTextureSizeIsRenderedOrRefusedClearly) {
  const int max_size = test::GlEnvironment::info().max_texture_size;
  const scene::Scene s = scene::make_builtin_scene("box");
  ShadowSettings st = settings(Technique::pcf, max_size, true);
  try {
    expect_finite_render(s, st, "pcf at GL_MAX_TEXTURE_SIZE " + std::to_string(max_size));
  } catch (const std::runtime_error& e) {
    // Allowed only as a clear out-of-memory report naming the pass or texture.
    EXPECT_NE(std::string(e.what()).find("memory"), std::string::npos) << e.what();
  }
  st.map.resolution_texels = max_size + 1;
  shadows::Renderer r;
  r.set_scene(s);
  try {
    r.render(st, 32, 32);
    ADD_FAILURE() << "a map larger than GL_MAX_TEXTURE_SIZE must be refused";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("GL_MAX_TEXTURE_SIZE"), std::string::npos) << e.what();
  }
}

// Issue 28: the pass timer called glFinish around every pass even when it used GL timer queries,
// serialising on a GPU the frame it measured. One method per timer: wall clock (software GL) or
// queries, never both, and each pass's numbers say which.
TEST(PassTimer, OneMethodPerTimerAndQueriesWithoutWallClock) {
  scene::Scene s = scene::make_builtin_scene("demo");
  shadows::Renderer r;
  r.set_scene(s);
  shadows::ShadowSettings st;
  st.map.resolution_texels = 256;
  for (const bool queries : {false, true}) {
    gl::PassTimer timer(queries);
    for (int i = 0; i < 3; ++i) r.render(st, 64, 36, &timer);
    timer.poll(true);
    const auto stats = timer.stats();
    ASSERT_FALSE(stats.empty());
    for (const auto& p : stats) {
      EXPECT_EQ(p.method, queries ? gl::TimingMethod::gpu_timer : gl::TimingMethod::wall_finish) << p.pass;
      EXPECT_EQ(p.samples, 3) << p.pass;
    }
  }
}

// Issue 47: the work a GPU pays for, counted by the driver per pass. A map 4 times finer rasterizes
// about 16 times the texels (the casters' area in texels) from the same primitives; the shading
// shades the same pixels; counting off leaves the list empty.
TEST(WorkCounts, AFourTimesFinerMapRasterizesAboutSixteenTimesTheTexels) {
  shadows::Renderer r;
  r.set_scene(scene::make_builtin_scene("demo"));
  shadows::ShadowSettings s;
  s.technique = shadows::Technique::pcf;
  const int w = 160, h = 90;
  EXPECT_TRUE(r.render(s, w, h).work.empty());
  r.set_count_work(true);
  const auto pass = [](const shadows::FrameInfo& f, const std::string& name) {
    for (const shadows::PassWork& p : f.work)
      if (p.pass == name) return p;
    ADD_FAILURE() << "no pass " << name;
    return shadows::PassWork{};
  };
  s.map.resolution_texels = 512;
  const shadows::FrameInfo coarse = r.render(s, w, h);
  s.map.resolution_texels = 2048;
  const shadows::FrameInfo fine = r.render(s, w, h);
  ASSERT_EQ(coarse.work.size(), coarse.passes.size());
  const shadows::PassWork cm = pass(coarse, "shadow_map"), fm = pass(fine, "shadow_map");
  EXPECT_EQ(cm.primitives, fm.primitives) << "the same casters";
  EXPECT_EQ(cm.primitives, coarse.map_triangles.at(0)) << "what the CPU counted as drawn";
  EXPECT_GT(cm.fragments, 1000u);
  const double ratio = static_cast<double>(fm.fragments) / static_cast<double>(cm.fragments);
  EXPECT_GT(ratio, 12.0);
  EXPECT_LT(ratio, 20.0);
  const shadows::PassWork cs = pass(coarse, "shading"), fs = pass(fine, "shading");
  EXPECT_EQ(cs.fragments, fs.fragments) << "the same pixels shaded";
  EXPECT_GE(cs.fragments, static_cast<std::uint64_t>(w) * h / 2);
  EXPECT_EQ(cm.compute_invocations, 0u);
}

// Issue 47: what the shading's shadow lookups read, counted by the shader itself at each pixel
// shown. Each count is known from the kernel: hard shadows one nearest comparison; the grid box of
// radius 1.5 texels spans 3 or 4 texels a side, two 2 × 2 gathers a side wherever the pixel lies;
// the Poisson disk one hardware 2 × 2 comparison per tap; VSM one bilinear fetch of its moments.
// Every technique counts the same pixels, each once.
TEST(ShadowReads, EachKernelReadsWhatItsShapeSays) {
  shadows::Renderer r;
  r.set_scene(scene::make_builtin_scene("demo"));
  const int w = 160, h = 90;
  EXPECT_THROW(r.count_shading_reads(), std::logic_error) << "no frame yet";
  struct Case {
    const char* name;
    shadows::ShadowSettings settings;
    double instructions, texels, bytes;  // per pixel
  };
  ShadowSettings hard;
  hard.technique = Technique::hard;
  ShadowSettings grid;
  grid.technique = Technique::pcf;
  grid.pcf.kernel = Kernel::grid;
  grid.pcf.radius = 1.5f;
  ShadowSettings poisson = grid;
  poisson.pcf.kernel = Kernel::poisson;
  poisson.pcf.poisson_taps = 25;
  ShadowSettings vsm;
  vsm.technique = Technique::vsm;
  const std::optional<shadows::MomentsLayout> moments = shadows::technique_entry(Technique::vsm).moments(vsm);
  ASSERT_TRUE(moments.has_value());
  const double moment_bytes = shadows::bytes_per_texel(moments->format);
  const Case cases[] = {
      {"hard", hard, 1, 1, 4},
      {"pcf grid r 1.5", grid, 4, 16, 64},
      {"pcf poisson 25 taps", poisson, 25, 100, 400},
      {"vsm", vsm, 1, 4, 4 * moment_bytes},
  };
  std::uint64_t pixels = 0;
  for (const Case& c : cases) {
    r.render(c.settings, w, h);
    const io::ImageF image = r.read_visibility();
    const shadows::ShadowReads reads = r.count_shading_reads();
    EXPECT_EQ(r.read_visibility().pixels, image.pixels) << c.name << ": the counting draw writes no image";
    EXPECT_GE(reads.pixels, static_cast<std::uint64_t>(w * h / 2)) << c.name << ": the ground fills most of the view";
    EXPECT_LE(reads.pixels, static_cast<std::uint64_t>(w * h)) << c.name << ": each pixel once";
    if (pixels) {
      EXPECT_EQ(reads.pixels, pixels) << c.name;
    }
    pixels = reads.pixels;
    EXPECT_DOUBLE_EQ(reads.per_pixel(reads.instructions), c.instructions) << c.name;
    EXPECT_DOUBLE_EQ(reads.per_pixel(reads.texels), c.texels) << c.name;
    EXPECT_DOUBLE_EQ(reads.per_pixel(reads.bytes), c.bytes) << c.name;
  }
}

// Counting a frame's reads leaves the frames after it as they were: the adaptive PCSS controller
// (which reads the previous frame's requirement) and the virtual map's cache see the same frames.
TEST(ShadowReads, CountingChangesNoLaterFrame) {
  const scene::Scene demo = scene::make_builtin_scene("demo");
  ShadowSettings pcss;
  pcss.technique = Technique::pcss;
  pcss.adaptive.enabled = true;
  pcss.adaptive.pcss = shadows::PcssRequirement::per_pixel;
  ShadowSettings paged;
  paged.technique = Technique::pcf;
  paged.pcf.kernel = Kernel::grid;
  paged.pcf.radius = 0.12f;
  paged.pcf.radius_unit = shadows::RadiusUnit::world;
  paged.map.virtual_pages = shadows::VirtualPages::rule;
  paged.map.virtual_cache = true;
  for (const ShadowSettings& s : {pcss, paged}) {
    shadows::Renderer counted, plain;
    counted.set_scene(demo);
    plain.set_scene(demo);
    for (int frame = 0; frame < 3; ++frame) {
      for (shadows::Renderer* r : {&counted, &plain}) r->scene().camera.position += glm::vec3(0.3f, 0, 0.2f);
      const shadows::FrameInfo a = counted.render(s, 160, 90);
      const shadows::ShadowReads reads = counted.count_shading_reads();
      EXPECT_GT(reads.instructions, reads.pixels) << shadows::technique_entry(s.technique).name;
      const shadows::FrameInfo b = plain.render(s, 160, 90);
      EXPECT_EQ(a.resolution_texels, b.resolution_texels) << "frame " << frame;
      if (a.virtual_map) {
        EXPECT_EQ(a.virtual_map->pages.drawn, b.virtual_map->pages.drawn) << "frame " << frame;
      }
      EXPECT_EQ(counted.read_visibility().pixels, plain.read_visibility().pixels) << "frame " << frame;
    }
  }
}

}  // namespace
}  // namespace penumbra
