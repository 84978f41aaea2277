// Light-frustum fitting (label `unit`: CPU only).
#include <gtest/gtest.h>

#include <random>

#include <glm/gtc/matrix_transform.hpp>

#include "shadows/fitting.h"

namespace penumbra::shadows {
namespace {

TEST(ConvexClip, BoxCutByAPlaneKeepsTheRightHalfAndCloses) {
  scene::Aabb b;
  b.extend(glm::vec3(-1));
  b.extend(glm::vec3(1));
  const Polyhedron half = clip(box_polyhedron(b), {1, 0, 0, 0});  // keep x >= 0
  const auto v = vertices(half);
  EXPECT_EQ(v.size(), 8u);
  for (const auto& p : v) EXPECT_GE(p.x, -1e-12);
  EXPECT_EQ(half.size(), 6u);  // five clipped faces and the cap
  EXPECT_TRUE(clip(box_polyhedron(b), {1, 0, 0, -2}).empty());  // x >= 2: nothing left
}

// Random points on the scene's triangles that the camera sees (inside its frustum).
std::vector<glm::vec3> visible_surface_points(const scene::Scene& s, float aspect, int total_samples) {
  std::size_t triangles = 0;
  for (const auto& o : s.objects) triangles += o.mesh->indices.size() / 3;
  const int per_triangle = std::max(20, total_samples / static_cast<int>(std::max<std::size_t>(triangles, 1)));
  const glm::mat4 vp = s.camera.projection_matrix(aspect) * s.camera.view();
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(0, 1);
  std::vector<glm::vec3> out;
  for (const auto& o : s.objects) {
    const auto& m = *o.mesh;
    for (std::size_t t = 0; t + 2 < m.indices.size(); t += 3) {
      for (int k = 0; k < per_triangle; ++k) {
        float a = u(rng), b = u(rng);
        if (a + b > 1) a = 1 - a, b = 1 - b;
        const glm::vec3 p = m.vertices[m.indices[t]].position * (1 - a - b) + m.vertices[m.indices[t + 1]].position * a +
                            m.vertices[m.indices[t + 2]].position * b;
        const glm::vec4 w = o.model * glm::vec4(p, 1);
        const glm::vec4 c = vp * w;
        if (c.w > 0 && std::abs(c.x) <= c.w && std::abs(c.y) <= c.w && std::abs(c.z) <= c.w) out.emplace_back(w);
      }
    }
  }
  return out;
}

void expect_contains_visible_receivers(const scene::Scene& s) {
  const float aspect = 16.0f / 9.0f;
  FitRequest req{true, aspect, 1024, 0, 0};
  const LightFrame fitted = compute_light_frame(s, req);
  req.fit = false;
  const LightFrame unfitted = compute_light_frame(s, req);
  ASSERT_TRUE(fitted.fitted);
  const auto points = visible_surface_points(s, aspect, 200000);
  ASSERT_GT(points.size(), 1000u);
  const glm::mat4 vp = fitted.view_projection();
  for (const auto& p : points) {
    const glm::vec4 c = vp * glm::vec4(p, 1);
    ASSERT_GT(c.w, 0);
    const glm::vec3 ndc = glm::vec3(c) / c.w;
    ASSERT_LE(std::abs(ndc.x), 1.0f + 1e-5f) << s.name;
    ASSERT_LE(std::abs(ndc.y), 1.0f + 1e-5f) << s.name;
    ASSERT_LE(ndc.z, 1.0f + 1e-5f) << s.name << ": a receiver behind the far plane";
  }
  // Light-space area: the fit magnifies uv by s_xy on each axis.
  EXPECT_GT(fitted.s_xy, 1.2f) << s.name;
  EXPECT_FLOAT_EQ(unfitted.s_xy, 1.0f);
  if (!fitted.perspective) {
    EXPECT_LT(fitted.extent_ws * fitted.extent_ws, unfitted.extent_ws * unfitted.extent_ws);
  }
}

TEST(Fitting, DirectionalFitContainsEveryVisibleReceiverAndCoversLess) {
  scene::Scene s = scene::make_builtin_scene("demo");
  expect_contains_visible_receivers(s);
}

TEST(Fitting, SpotFitContainsEveryVisibleReceiverAndCoversLess) {
  scene::Scene s = scene::make_two_planes_scene(3, 10, 1);
  s.camera.projection = scene::Camera::Projection::perspective;
  s.camera.position = {2, 3, 4};
  s.camera.target = {2, 0, 1};
  expect_contains_visible_receivers(s);
}

TEST(Fitting, PaddingGrowsTheFitByTheFilterRadius) {
  const scene::Scene s = scene::make_builtin_scene("demo");
  const LightFrame tight = compute_light_frame(s, {true, 1.5f, 1000, 0, 0});
  const LightFrame padded = compute_light_frame(s, {true, 1.5f, 1000, 100, 0});
  EXPECT_NEAR(padded.extent_ws, tight.extent_ws * 1000.0f / 800.0f, 1e-3f * tight.extent_ws);
  // Padding is capped at a quarter of the map per side: a 1000-texel radius at most doubles it.
  const LightFrame capped = compute_light_frame(s, {true, 1.5f, 1000, 1000, 0});
  EXPECT_NEAR(capped.extent_ws, 2 * tight.extent_ws, 1e-3f * tight.extent_ws);
}

TEST(Fitting, NothingVisibleFallsBackToTheUnfittedFrustum) {
  scene::Scene s = scene::make_builtin_scene("box");
  s.camera.target = s.camera.position + glm::vec3(0, 1, 0.01f);  // the sky
  const LightFrame f = compute_light_frame(s, {true, 1.5f, 512, 0, 0});
  EXPECT_FALSE(f.receivers_visible);
  EXPECT_FALSE(f.fitted);
  EXPECT_FLOAT_EQ(f.s_xy, 1.0f);
  const LightFrame empty = compute_light_frame(scene::make_builtin_scene("empty"), {true, 1.5f, 512, 0, 0});
  EXPECT_TRUE(std::isfinite(empty.extent_ws));
  EXPECT_GT(empty.far_ws, empty.near_ws);
}

// Issue 27: one sphere at x = 1e20 (or any object far outside what the camera sees) made the fit
// overflow (near = far = 3.4e38, s_xy NaN) and removed every shadow. The fit holds only what can
// cast onto the visible receivers: the far object changes nothing, and every number is finite.
void expect_far_object_changes_nothing(scene::Scene s, const glm::vec3& where) {
  const float aspect = 16.0f / 9.0f;
  for (const bool fit : {true, false}) {
    const LightFrame before = compute_light_frame(s, {fit, aspect, 1024, 2, 0});
    scene::Scene far = s;
    scene::Object o = s.objects.back();
    o.name = "far-away";
    o.model = glm::translate(glm::mat4(1), where) * o.model;
    far.objects.push_back(o);
    const LightFrame after = compute_light_frame(far, {fit, aspect, 1024, 2, 0});
    EXPECT_EQ(after.fitted, fit) << s.name;
    EXPECT_NEAR(after.extent_ws, before.extent_ws, 1e-4f * before.extent_ws) << s.name << " fit " << fit;
    EXPECT_NEAR(after.s_xy, before.s_xy, 1e-4f * before.s_xy) << s.name << " fit " << fit;
    EXPECT_NEAR(after.far_ws - after.near_ws, before.far_ws - before.near_ws, 1e-3f * (before.far_ws - before.near_ws)) << s.name;
    // The same receivers land on the same texels.
    const glm::mat4 a = before.view_projection(), b = after.view_projection();
    for (const glm::vec3 p : {glm::vec3(0, 0, 0), glm::vec3(1, 0.5f, -1), glm::vec3(-2, 1, 2)}) {
      const glm::vec4 pa = a * glm::vec4(p, 1), pb = b * glm::vec4(p, 1);
      EXPECT_NEAR(pa.x / pa.w, pb.x / pb.w, 1e-4f) << s.name;
      EXPECT_NEAR(pa.y / pa.w, pb.y / pb.w, 1e-4f) << s.name;
    }
    if (s.light.type == scene::Light::Type::spot) continue;
    const Cascades cascades = compute_cascades(far, {4, 0.75f, true, aspect, {1024}, 2, 0, true});
    for (const LightFrame& f : cascades.frames) {
      EXPECT_TRUE(std::isfinite(f.extent_ws) && std::isfinite(f.s_xy) && std::isfinite(f.near_ws) && std::isfinite(f.far_ws));
      EXPECT_LT(f.extent_ws, 2 * before.extent_ws / before.s_xy) << s.name;
    }
  }
}

TEST(Fitting, AFarAwayObjectStaysOutOfTheDirectionalFit) {
  expect_far_object_changes_nothing(scene::make_builtin_scene("demo"), {1e20f, 0, 0});
  expect_far_object_changes_nothing(scene::make_builtin_scene("demo"), {3e37f, -3e37f, 3e37f});
}

TEST(Fitting, AFarAwayObjectStaysOutOfTheSpotFit) {
  scene::Scene s = scene::make_two_planes_scene(3, 10, 1);
  s.camera.projection = scene::Camera::Projection::perspective;
  s.camera.position = {2, 3, 4};
  s.camera.target = {2, 0, 1};
  expect_far_object_changes_nothing(s, {1e20f, 0, 0});
  expect_far_object_changes_nothing(s, {0, -1e20f, 0});  // behind the receivers, along the light
}

// An object of size 1e30 that the camera sees into: the frame holds the receivers and the casters
// within 1000 receiver sizes of them (farther ones are clamped onto the near plane), finite.
TEST(Fitting, AnEnormousObjectIsClippedToTheReceiversReach) {
  scene::Scene s = scene::make_builtin_scene("demo");
  scene::Object o = s.objects.back();
  o.name = "enormous";
  o.model = glm::translate(glm::mat4(1), glm::vec3(0, 0, -1e29f)) * glm::scale(glm::mat4(1), glm::vec3(1e28f));
  s.objects.push_back(o);
  for (const bool fit : {true, false}) {
    const LightFrame f = compute_light_frame(s, {fit, 16.0f / 9.0f, 1024, 2, 0});
    EXPECT_TRUE(std::isfinite(f.near_ws) && std::isfinite(f.far_ws) && std::isfinite(f.s_xy)) << fit;
    EXPECT_LT(f.extent_ws, 1e6f) << fit;
    EXPECT_LT(f.far_ws - f.near_ws, 1e6f) << fit;
  }
  EXPECT_LT(shadow_region_diagonal_ws(s, 16.0f / 9.0f), 1e6f);
}

}  // namespace
}  // namespace penumbra::shadows
