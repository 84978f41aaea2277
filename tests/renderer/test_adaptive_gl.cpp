// Adaptive resolution, storage, cascades and the per-pixel PCSS requirement in the renderer
// (label `gl`: needs an OpenGL 4.5 context; Mesa llvmpipe through EGL is enough).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "adaptive/resolution_rule.h"
#include "gl_test_env.h"
#include "shadows/fitting.h"
#include "shadows/renderer.h"

namespace penumbra {
namespace {

using shadows::Kernel;
using shadows::RadiusUnit;
using shadows::ShadowSettings;
using shadows::Storage;
using shadows::Technique;

constexpr int kW = 320, kH = 180;

ShadowSettings pcf_world(float radius_ws, bool adaptive) {
  ShadowSettings s;
  s.technique = Technique::pcf;
  s.pcf.kernel = Kernel::grid;
  s.pcf.radius = radius_ws;
  s.pcf.radius_unit = RadiusUnit::world;
  s.adaptive.enabled = adaptive;
  return s;
}

struct Diff {
  double max = 0, mean = 0;
};
Diff difference(const io::ImageF& a, const io::ImageF& b) {
  Diff d;
  EXPECT_EQ(a.pixels.size(), b.pixels.size());
  for (std::size_t i = 0; i < a.pixels.size(); ++i) {
    const double e = std::abs(static_cast<double>(a.pixels[i]) - b.pixels[i]);
    d.max = std::max(d.max, e);
    d.mean += e;
  }
  d.mean /= static_cast<double>(std::max<std::size_t>(a.pixels.size(), 1));
  return d;
}

struct Frame {
  shadows::FrameInfo info;
  io::ImageF visibility;
  io::Image8 color;
};

// Per-pixel difference of what the user sees (sRGB 8-bit, mean of R, G, B), in 8-bit steps;
// `share` = fraction of pixels off by more than 4 steps.
Diff color_difference(const io::Image8& a, const io::Image8& b, double* share = nullptr) {
  Diff d;
  double above = 0;
  EXPECT_EQ(a.pixels.size(), b.pixels.size());
  const std::size_t n = a.pixels.size() / 4;
  for (std::size_t i = 0; i < n; ++i) {
    double e = 0;
    for (int c = 0; c < 3; ++c) e += std::abs(static_cast<double>(a.pixels[4 * i + c]) - b.pixels[4 * i + c]) / 3;
    d.max = std::max(d.max, e);
    d.mean += e;
    above += e > 4 ? 1 : 0;
  }
  d.mean /= static_cast<double>(std::max<std::size_t>(n, 1));
  if (share) *share = above / static_cast<double>(std::max<std::size_t>(n, 1));
  return d;
}
Frame render(const scene::Scene& scene, const ShadowSettings& s, int frames = 1) {
  shadows::Renderer r;
  r.set_scene(scene);
  Frame f;
  for (int i = 0; i < frames; ++i) f.info = r.render(s, kW, kH);
  f.visibility = r.read_visibility();
  f.color = r.read_color();
  return f;
}

TEST(Adaptive, ResolutionFollowsTheRuleWithTheFittedExtent) {
  const scene::Scene scene = scene::make_builtin_scene("demo");
  for (float radius : {0.04f, 0.08f, 0.16f}) {
    const ShadowSettings s = pcf_world(radius, true);
    const Frame f = render(scene, s);
    ASSERT_EQ(f.info.cascades.size(), 1u);
    // res = c · L / r_ws with L the fitted extent (= r_uv = r_ws / L_unfitted · s_xy).
    const double expected = s.adaptive.c * f.info.light.extent_ws / radius;
    EXPECT_NEAR(f.info.cascades[0].required_texels, expected, 1e-3 * expected);
    EXPECT_EQ(f.info.resolution_texels,
              adaptive::clamp_resolution(expected, {s.adaptive.min_texels, s.adaptive.max_texels, s.adaptive.quantum_texels}));
    EXPECT_EQ(f.info.resolution_source, "rule");
    // The filter then spans at least c texels, and less than one quantum more.
    EXPECT_GE(f.info.filter_radius_texels, s.adaptive.c - 1e-3);
  }
}

TEST(Adaptive, ExtremeRadiiAreClampedAndRender) {
  const scene::Scene scene = scene::make_builtin_scene("demo");
  ShadowSettings s = pcf_world(1e-6f, true);
  s.adaptive.max_texels = 1024;
  Frame f = render(scene, s);
  EXPECT_EQ(f.info.resolution_texels, 1024);
  EXPECT_TRUE(test::all_finite_in(f.visibility, 0, 1));
  s.pcf.radius = 1e5f;
  f = render(scene, s);
  EXPECT_EQ(f.info.resolution_texels, s.adaptive.min_texels);
  EXPECT_TRUE(test::all_finite_in(f.visibility, 0, 1));
  s.technique = Technique::hard;  // no filter: the rule asks for the largest map
  f = render(scene, s);
  EXPECT_EQ(f.info.resolution_texels, 1024);
}

TEST(Adaptive, SubRectangleAndReallocationGiveTheSameImage) {
  const scene::Scene scene = scene::make_builtin_scene("demo");
  for (Technique t : {Technique::pcf, Technique::pcss, Technique::vsm}) {
    SCOPED_TRACE(std::string(shadows::to_string(t)));
    ShadowSettings s = pcf_world(0.08f, true);
    s.technique = t;
    s.vsm.radius = 0.08f;
    s.vsm.radius_unit = RadiusUnit::world;
    s.pcss.kernel = Kernel::grid;
    s.pcss.min_penumbra_ws = 0.05f;
    s.adaptive.pcss = shadows::PcssRequirement::min_penumbra;
    s.adaptive.storage = Storage::subrect;
    const Frame sub = render(scene, s);
    s.adaptive.storage = Storage::realloc;
    const Frame re = render(scene, s);
    EXPECT_EQ(sub.info.storage, "subrect");
    EXPECT_EQ(re.info.storage, "realloc");
    ASSERT_EQ(sub.info.resolution_texels, re.info.resolution_texels);
    EXPECT_EQ(sub.info.atlas_width, s.adaptive.max_texels + 4);  // the preallocated maximum, guard band included
    EXPECT_EQ(re.info.atlas_width, re.info.resolution_texels);
    const Diff d = difference(sub.visibility, re.visibility);
    // The region's uv differ from the whole texture's by float rounding (~1e-4 texel); VSM's
    // Chebyshev bound turns that into up to ~0.01 where the variance sits at its floor.
    EXPECT_LT(d.max, t == Technique::vsm ? 2e-2 : 2e-3);
    EXPECT_LT(d.mean, 1e-5);
  }
}

TEST(Adaptive, SubRectangleKeepsItsTextureReallocationDoesNot) {
  const scene::Scene scene = scene::make_builtin_scene("demo");
  for (Storage storage : {Storage::subrect, Storage::realloc}) {
    ShadowSettings s = pcf_world(0.08f, true);
    s.adaptive.storage = storage;
    s.adaptive.shrink_delay_frames = 0;
    shadows::Renderer r;
    r.set_scene(scene);
    int reallocations = 0;
    int last = 0, changes = 0;
    for (float radius : {0.08f, 0.04f, 0.16f, 0.08f}) {
      s.pcf.radius = radius;
      const auto info = r.render(s, kW, kH);
      reallocations += info.reallocated ? 1 : 0;
      changes += last != 0 && info.resolution_texels != last ? 1 : 0;
      last = info.resolution_texels;
    }
    EXPECT_EQ(changes, 3);
    EXPECT_EQ(reallocations, storage == Storage::subrect ? 1 : 4);
  }
}

TEST(Adaptive, ImageStaysCloseToTheFixedReference) {
  for (const char* name : {"demo", "fence", "tilted", "box", "sphere"}) {
    SCOPED_TRACE(name);
    const scene::Scene scene = scene::make_builtin_scene(name);
    ShadowSettings s = pcf_world(0.06f, false);
    s.map.resolution_texels = 2048;
    const Frame fixed = render(scene, s);
    s.adaptive.enabled = true;
    const Frame adaptive = render(scene, s);
    EXPECT_LT(adaptive.info.resolution_texels, 2048);
    // Compared as seen (lit sRGB colour): visibility on surfaces turned away from the light is
    // not shown and may differ freely. The filter hides the coarser map's texels: tiny mean error,
    // no pixel off by more than a few 8-bit steps.
    double share = 0;
    const Diff d = color_difference(fixed.color, adaptive.color, &share);
    EXPECT_LT(d.mean, 0.1);
    EXPECT_LT(share, 5e-3);
    EXPECT_LE(d.max, 20);
  }
}

// Camera view depth of a world point.
float view_depth(const scene::Camera& cam, const glm::vec3& p) { return -(cam.view() * glm::vec4(p, 1)).z; }

// Random points of the scene's bounds that the camera sees (inside its frustum).
std::vector<glm::vec3> visible_points(const scene::Scene& scene, float aspect, int n) {
  std::mt19937 rng(7);
  const scene::Aabb b = scene.bounds();
  std::uniform_real_distribution<float> ux(b.lo.x, b.hi.x), uy(b.lo.y, b.hi.y), uz(b.lo.z, b.hi.z);
  const glm::mat4 vp = scene.camera.projection_matrix(aspect) * scene.camera.view();
  std::vector<glm::vec3> pts;
  while (static_cast<int>(pts.size()) < n) {
    const glm::vec3 p(ux(rng), uy(rng), uz(rng));
    const glm::vec4 c = vp * glm::vec4(p, 1);
    if (c.w > 0 && std::abs(c.x) <= c.w && std::abs(c.y) <= c.w && std::abs(c.z) <= c.w) pts.push_back(p);
  }
  return pts;
}

bool inside_map(const shadows::LightFrame& f, const glm::vec3& p) {
  const glm::vec4 c = f.view_projection() * glm::vec4(p, 1);
  const glm::vec3 sc = glm::vec3(c) / c.w * 0.5f + 0.5f;
  return sc.x >= 0 && sc.x <= 1 && sc.y >= 0 && sc.y <= 1;
}

TEST(Cascades, EveryVisiblePointIsCoveredByItsCascadeAndTheBlendBand) {
  const scene::Scene scene = scene::make_builtin_scene("demo");
  const float aspect = 16.0f / 9.0f, blend = 0.1f;
  for (bool stabilize : {true, false}) {
    for (int count : {2, 3, 4}) {
      SCOPED_TRACE(std::to_string(count) + (stabilize ? " stabilized" : " tight"));
      shadows::CascadeRequest req{count, 0.75f, stabilize, aspect, {512}, 2, 0};
      const shadows::Cascades c = shadows::compute_cascades(scene, req);
      ASSERT_EQ(static_cast<int>(c.frames.size()), count);
      ASSERT_EQ(c.splits_ws.size(), static_cast<std::size_t>(count) + 1);
      int blended = 0;
      for (const glm::vec3& p : visible_points(scene, aspect, 4000)) {
        const float z = view_depth(scene.camera, p);
        int i = 0;  // as shading.frag picks it
        while (i < count - 1 && z > c.splits_ws[static_cast<std::size_t>(i) + 1]) ++i;
        ASSERT_TRUE(inside_map(c.frames[static_cast<std::size_t>(i)], p)) << "cascade " << i << " misses a point at depth " << z;
        const float lo = c.splits_ws[static_cast<std::size_t>(i)], hi = c.splits_ws[static_cast<std::size_t>(i) + 1];
        if (i < count - 1 && z > hi - blend * (hi - lo)) {
          ++blended;
          ASSERT_TRUE(inside_map(c.frames[static_cast<std::size_t>(i) + 1], p)) << "blend band of cascade " << i;
        }
      }
      EXPECT_GT(blended, 0);
    }
  }
}

TEST(Cascades, SubTexelCameraMovesKeepStabilizedMapsOnTheTexelGrid) {
  scene::Scene scene = scene::make_builtin_scene("demo");
  const float aspect = 16.0f / 9.0f;
  const int res = 512;
  auto windows = [&](bool stabilize) {
    shadows::CascadeRequest req{3, 0.75f, stabilize, aspect, {res}, 2, 0};
    return shadows::compute_cascades(scene, req);
  };
  const shadows::Cascades start = windows(true);
  const float texel0 = start.frames[0].extent_ws / res;
  int fractional_tight = 0;
  const shadows::Cascades tight0 = windows(false);
  for (int step = 1; step <= 10; ++step) {
    const glm::vec3 delta(0.13f * texel0 * step, 0, 0.07f * texel0 * step);  // well under a texel of any cascade
    scene::Scene moved = scene;
    scene.camera.position += delta;
    scene.camera.target += delta;
    const shadows::Cascades now = windows(true);
    const shadows::Cascades tight = windows(false);
    scene.camera.position -= delta;
    scene.camera.target -= delta;
    for (std::size_t i = 0; i < now.frames.size(); ++i) {
      // Same size, window moved by whole texels: the rasterized map is the same map, shifted, so
      // shadow edges on receivers do not move at all (< half a pixel, as required).
      EXPECT_FLOAT_EQ(now.frames[i].extent_ws, start.frames[i].extent_ws) << "cascade " << i;
      const float texel = now.frames[i].extent_ws / res;
      const float shift_x = (now.frames[i].projection[3][0] - start.frames[i].projection[3][0]) / now.frames[i].projection[0][0];
      const float shift_y = (now.frames[i].projection[3][1] - start.frames[i].projection[3][1]) / now.frames[i].projection[1][1];
      EXPECT_NEAR(shift_x / texel, std::round(shift_x / texel), 1e-2) << "cascade " << i;
      EXPECT_NEAR(shift_y / texel, std::round(shift_y / texel), 1e-2) << "cascade " << i;
      const float tight_shift = (tight.frames[i].projection[3][0] - tight0.frames[i].projection[3][0]) / tight.frames[i].projection[0][0];
      const float tight_texel = tight.frames[i].extent_ws / res;
      if (std::abs(tight_shift / tight_texel - std::round(tight_shift / tight_texel)) > 0.05f) ++fractional_tight;
    }
  }
  EXPECT_GT(fractional_tight, 0) << "unstabilized cascades should crawl (the property is not trivially true)";
}

TEST(Cascades, AutomaticCountIsOneWhenOneMapSufficesAndEachFitsOtherwise) {
  const scene::Scene scene = scene::make_builtin_scene("demo");
  ShadowSettings s = pcf_world(0.08f, true);
  s.map.cascades = 0;
  Frame f = render(scene, s);
  EXPECT_EQ(f.info.cascades.size(), 1u);
  s.adaptive.max_texels = 768;
  f = render(scene, s);
  EXPECT_GT(f.info.cascades.size(), 1u);
  for (const auto& c : f.info.cascades) EXPECT_LE(c.resolution_texels, 768);
  EXPECT_TRUE(test::all_finite_in(f.visibility, 0, 1));
  // A view that sees no receiver (camera looking up at the sky) has nothing to split: one map.
  scene::Scene sky = scene;
  sky.camera.target = sky.camera.position + glm::vec3(0, 10, 0.1f);
  s.map.cascades = 3;
  f = render(sky, s);
  EXPECT_EQ(f.info.cascades.size(), 1u);
  EXPECT_TRUE(test::all_finite_in(f.visibility, 0, 1));
  // A spot light is never cascaded.
  scene::Scene spot = scene::make_builtin_scene("two-planes");
  s.map.cascades = 3;
  EXPECT_EQ(render(spot, s).info.cascades.size(), 1u);
}

TEST(Cascades, CascadedImageMatchesTheSingleMapAwayFromTheBands) {
  const scene::Scene scene = scene::make_builtin_scene("demo");
  ShadowSettings s = pcf_world(0.08f, true);
  const Frame one = render(scene, s);
  s.map.cascades = 3;
  const Frame three = render(scene, s);
  ASSERT_EQ(three.info.cascades.size(), 3u);
  const Diff d = difference(one.visibility, three.visibility);
  EXPECT_LT(d.mean, 3e-3);
}

TEST(PcssRequirement, PerPixelMaximumMatchesTheTwoPlaneFormula) {
  // Spot light straight down at height H over a receiver plane, blocker plane at height h: every
  // penumbra pixel has the same filter radius, so the per-pixel maximum is the formula's value.
  const float H = 10, h = 3, W = 1;
  const scene::Scene scene = scene::make_two_planes_scene(h, H, W);
  ShadowSettings s;
  s.technique = Technique::pcss;
  s.pcss.kernel = Kernel::grid;
  s.pcss.min_penumbra_ws = 1e-4f;
  s.adaptive.enabled = true;
  s.adaptive.shrink_delay_frames = 0;
  shadows::Renderer r;
  r.set_scene(scene);
  const auto first = r.render(s, kW, kH);
  EXPECT_EQ(first.resolution_source, "pcss_min_penumbra");  // nothing measured yet
  const auto second = r.render(s, kW, kH);
  ASSERT_EQ(second.resolution_source, "pcss_per_pixel");
  ASSERT_TRUE(second.pcss_requirement.valid);
  const shadows::LightFrame& lf = second.light;
  const double z_r = H, z_b = H - h - 0.005;  // the blocker box is 0.01 thick
  const double filter_uv = W / 2.0 * lf.s_xy / (2 * std::tan(glm::radians(lf.fov_deg) / 2)) * (z_r - z_b) / (z_b * z_r);
  const double expected = s.adaptive.c / filter_uv;
  EXPECT_NEAR(second.pcss_requirement.required_texels[0], expected, 0.02 * expected);
  EXPECT_GT(second.pcss_requirement.evaluated_pixels, 500);
  EXPECT_EQ(second.pcss_requirement.clamped_fraction, 0);
  EXPECT_EQ(second.resolution_texels,
            adaptive::clamp_resolution(second.pcss_requirement.required_texels[0], {s.adaptive.min_texels, s.adaptive.max_texels, s.adaptive.quantum_texels}));

  // A minimum penumbra wider than every natural one clamps every pixel and sets the requirement.
  s.pcss.min_penumbra_ws = 2;
  r.reset_adaptive();
  r.render(s, kW, kH);
  const auto clamped = r.render(s, kW, kH);
  ASSERT_TRUE(clamped.pcss_requirement.valid);
  EXPECT_EQ(clamped.pcss_requirement.clamped_fraction, 1);
  const shadows::LightFrame& lf2 = clamped.light;  // the padding (one texel) moved with the resolution
  const double min_uv = 2.0 * lf2.s_xy / (2 * z_r * std::tan(glm::radians(lf2.fov_deg) / 2));
  EXPECT_NEAR(clamped.pcss_requirement.required_texels[0], s.adaptive.c / min_uv, 0.01 * s.adaptive.c / min_uv);
  EXPECT_EQ(clamped.pcss_requirement.above_max_fraction, 0);
}

TEST(PcssRequirement, ReductionMatchesTheImageItReduces) {
  // The GPU reduction (blocks of pixels per invocation, 64 x 64 per workgroup) against the same
  // reduction on the CPU of the requirement image it read, on an odd-sized image (partial blocks at
  // the right and bottom edges), with unclamped, clamped and above-maximum pixels.
  const scene::Scene scene = scene::make_builtin_scene("demo");
  ShadowSettings s;
  s.technique = Technique::pcss;
  s.pcss.kernel = Kernel::grid;
  s.pcss.min_penumbra_ws = 0.02f;
  s.adaptive.enabled = true;
  s.adaptive.max_texels = 1024;
  shadows::Renderer r;
  r.set_scene(scene);
  const int w = 333, h = 197;
  r.render(s, w, h);
  const io::ImageF req = r.read_pcss_requirement();
  const auto next = r.render(s, w, h);  // reports the previous frame's reduction
  ASSERT_TRUE(next.pcss_requirement.valid);
  ASSERT_EQ(req.width, w);
  ASSERT_EQ(req.channels, 2);
  double max_inverse_uv = 0, evaluated = 0, clamped = 0, above = 0;
  const double limit = s.adaptive.max_texels / s.adaptive.c;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const float inv = req.at(x, y, 0), tag = req.at(x, y, 1);
      if (inv <= 0) continue;
      ASSERT_LT(tag, 1.0f) << "one map: cascade 0";
      max_inverse_uv = std::max(max_inverse_uv, static_cast<double>(inv));
      ++evaluated;
      clamped += tag > 0.25f;
      above += inv > static_cast<float>(limit);
    }
  EXPECT_GT(evaluated, 1000);
  EXPECT_GT(clamped, 0);
  EXPECT_LT(clamped, evaluated);
  EXPECT_GT(above, 0);
  EXPECT_EQ(next.pcss_requirement.evaluated_pixels, evaluated);
  EXPECT_DOUBLE_EQ(next.pcss_requirement.clamped_fraction, clamped / evaluated);
  EXPECT_DOUBLE_EQ(next.pcss_requirement.above_max_fraction, above / evaluated);
  EXPECT_DOUBLE_EQ(next.pcss_requirement.required_texels[0], static_cast<double>(s.adaptive.c) * max_inverse_uv);
}

}  // namespace
}  // namespace penumbra
