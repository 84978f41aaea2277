// The flicker measure (metrics/temporal.h) and the surface probe it reprojects with: zero for a
// camera that does not move, zero for stabilized cascades under a sub-texel camera move that
// lands on pixel centres, positive for the same move with unstabilized cascades; the probe sees
// what the renderer draws.
#include <gtest/gtest.h>

#include <cmath>

#include "gl_test_env.h"
#include "metrics/surface_probe.h"
#include "metrics/temporal.h"

namespace penumbra {
namespace {

using shadows::ShadowSettings;
using shadows::Technique;

struct Frame {
  io::ImageF visibility, surface;
  glm::mat4 view_projection;
  shadows::FrameInfo info;
  metrics::FrameSample sample() const { return {&visibility, &surface, view_projection}; }
};

Frame render(shadows::Renderer& r, metrics::SurfaceProbe& probe, const ShadowSettings& st, int n) {
  Frame f;
  f.info = r.render(st, n, n);
  f.visibility = r.read_visibility();
  f.surface = probe.render(r.scene().camera, n, n);
  f.view_projection = metrics::camera_view_projection(r.scene().camera, n, n);
  return f;
}

// Two cascades of 128² over the fence scene's ground, seen straight down; the fence's shadow is
// in view.
ShadowSettings cascaded(Technique t, bool stabilize) {
  ShadowSettings st = test::settings(t, 128, true);
  st.map.cascades = 2;
  st.map.cascade_stabilize = stabilize;
  st.pcf.kernel = shadows::Kernel::grid;
  st.pcf.radius = 0.05f;
  st.pcf.radius_unit = shadows::RadiusUnit::world;
  return st;
}

constexpr int kPixels = 256;
constexpr float kHalf = 2;  // 4 m across: 1.5625 cm per pixel

TEST(SurfaceProbe, SeesWhatTheRendererDraws) {
  scene::Scene s = scene::make_builtin_scene("demo");
  shadows::Renderer r;
  r.set_scene(s);
  metrics::SurfaceProbe probe(s);
  r.render(test::settings(Technique::hard, 512, true), 96, 64);
  const io::Image8 color = r.read_color();
  const io::ImageF surf = probe.render(s.camera, 96, 64);
  ASSERT_EQ(surf.channels, 4);
  int sky = 0, surfaces = 0;
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 96; ++x) {
      const bool drawn = surf.at(x, y, 3) > 0;
      // The renderer clears to the sky colour (0.45, 0.55, 0.7): pixels the probe finds empty show it.
      const bool sky_colour = color.at(x, y, 2) > color.at(x, y, 0) + 20;
      sky += !drawn, surfaces += drawn;
      if (!drawn) {
        EXPECT_TRUE(sky_colour) << x << "," << y;
      }
      const float id = surf.at(x, y, 3);
      EXPECT_EQ(id, std::round(id));
      EXPECT_LE(id, static_cast<float>(s.objects.size()));
    }
  EXPECT_GT(sky, 0);
  EXPECT_GT(surfaces, 96 * 64 / 2);
  const glm::vec3 near_point(surf.at(48, 63, 0), surf.at(48, 63, 1), surf.at(48, 63, 2));
  EXPECT_NEAR(near_point.y, 0.0f, 1e-3f);  // the bottom centre shows the ground, at y = 0
}

TEST(Flicker, ZeroForAStaticCamera) {
  scene::Scene s = scene::make_builtin_scene("demo");
  shadows::Renderer r;
  r.set_scene(s);
  metrics::SurfaceProbe probe(s);
  for (bool stabilize : {true, false}) {
    SCOPED_TRACE(stabilize);
    const ShadowSettings st = cascaded(Technique::pcf, stabilize);
    const Frame a = render(r, probe, st, 160);
    const Frame b = render(r, probe, st, 160);
    const metrics::Flicker f = metrics::flicker(a.sample(), b.sample());
    EXPECT_GT(f.matched_pixels, f.surface_pixels * 8 / 10);
    EXPECT_EQ(f.mean_abs, 0.0);
    EXPECT_EQ(f.share_changed, 0.0);
  }
}

// The camera moves by exactly one pixel (1.56 cm) across an orthographic view of the ground
// (measured: stabilized 0 for hard shadows, 1e-7 for PCF; unstabilized 0.065 and 0.035):
// every pixel of the new frame lands on a pixel centre of the old one. Stabilized cascades keep
// their texel grid in the world (a shadow fixed in the world does not change); unstabilized ones
// slide with the camera by a fraction of a texel, and the fence's shadow edges change.
TEST(Flicker, PositiveForUnstabilizedCascadesUnderASubTexelMove) {
  scene::Scene s = scene::make_builtin_scene("fence");
  shadows::Renderer r;
  r.set_scene(s);
  metrics::SurfaceProbe probe(s);
  const glm::vec2 centre(-0.5f, -0.8f);
  const float pixel_ws = 2 * kHalf / kPixels;
  for (Technique t : {Technique::hard, Technique::pcf}) {
    double mean[2] = {0, 0};
    for (bool stabilize : {true, false}) {
      SCOPED_TRACE(std::string(shadows::to_string(t)) + (stabilize ? " stabilized" : " unstabilized"));
      const ShadowSettings st = cascaded(t, stabilize);
      test::look_down(r.scene(), centre, kHalf);
      const Frame a = render(r, probe, st, kPixels);
      test::look_down(r.scene(), centre + glm::vec2(pixel_ws, 0), kHalf);
      const Frame b = render(r, probe, st, kPixels);
      for (const auto& c : b.info.cascades)
        ASSERT_LT(pixel_ws, 0.7f * c.light.extent_ws / static_cast<float>(c.resolution_texels)) << "the move must be sub-texel";
      const metrics::Flicker f = metrics::flicker(a.sample(), b.sample());
      EXPECT_GT(f.matched_pixels, f.surface_pixels * 9 / 10);
      mean[stabilize ? 0 : 1] = f.mean_abs;
      if (stabilize) {
        EXPECT_LT(f.mean_abs, 1e-5);
      } else {
        EXPECT_GT(f.mean_abs, 1e-3);
        EXPECT_GT(f.share_changed, 0.01);
      }
    }
    EXPECT_GT(mean[1], 100 * mean[0]);
  }
}

TEST(Flicker, RefusesMismatchedFrames) {
  const io::ImageF vis{4, 4, 1, std::vector<float>(16, 1.0f)};
  const io::ImageF surf{4, 4, 4, std::vector<float>(64, 0.0f)};
  const io::ImageF small{2, 2, 1, std::vector<float>(4, 1.0f)};
  const metrics::FrameSample good{&vis, &surf, glm::mat4(1)};
  EXPECT_NO_THROW(metrics::flicker(good, good));
  EXPECT_THROW(metrics::flicker(good, {&small, &surf, glm::mat4(1)}), std::invalid_argument);
  EXPECT_THROW(metrics::flicker(good, {&vis, nullptr, glm::mat4(1)}), std::invalid_argument);
  EXPECT_THROW(metrics::flicker({&surf, &surf, glm::mat4(1)}, good), std::invalid_argument);
}

}  // namespace
}  // namespace penumbra
