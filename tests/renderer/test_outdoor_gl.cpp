// The outdoor scene through the renderer: every technique gives a finite image with shadows in it,
// under the sun (with cascades where a technique has them) and under the floodlight.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <memory>
#include <string>

#include <glm/gtc/matrix_transform.hpp>

#include "gl_test_env.h"
#include "scene/outdoor.h"

namespace penumbra {
namespace {

using shadows::ShadowSettings;
using shadows::Technique;

// Shares of pixels in shadow (< 0.1) and lit (> 0.9).
std::pair<double, double> shadow_and_lit(const io::ImageF& v) {
  double dark = 0, lit = 0;
  for (float p : v.pixels) dark += p < 0.1f, lit += p > 0.9f;
  return {dark / static_cast<double>(v.pixels.size()), lit / static_cast<double>(v.pixels.size())};
}

TEST(OutdoorGl, EveryTechniqueRendersFiniteShadows) {
  scene::Scene s = scene::make_builtin_scene("outdoor");
  s.camera = s.camera_path.at(s.camera, 120);  // the street, the site and the crane's shadow
  shadows::Renderer r;
  r.set_scene(s);
  for (auto name : shadows::technique_names()) {
    SCOPED_TRACE(std::string(name));
    ShadowSettings st;
    st.technique = shadows::technique_from_string(name);
    st.map.resolution_texels = 1024;
    st.map.cascades = 4;  // ignored by the screen-space techniques, which use one map
    r.render(st, 160, 90);
    const io::ImageF v = r.read_visibility();
    ASSERT_TRUE(test::all_finite_in(v, 0, 1));
    const auto [dark, lit] = shadow_and_lit(v);
    EXPECT_GT(dark, 0.02) << "no shadow in view";
    EXPECT_GT(lit, 0.1) << "nothing lit in view";
  }
}

TEST(OutdoorGl, FloodlightRendersFiniteShadows) {
  scene::Scene s = scene::make_builtin_scene("outdoor-spot");
  s.camera = s.camera_path.at(s.camera, 120);
  for (Technique t : {Technique::pcf, Technique::pcss}) {
    ShadowSettings st = test::settings(t, 1024, true);
    const io::ImageF v = test::render_visibility(s, st, 96);
    ASSERT_TRUE(test::all_finite_in(v, 0, 1));
    const auto [dark, lit] = shadow_and_lit(v);
    EXPECT_GT(dark, 0.02);
    EXPECT_GT(lit, 0.05);
  }
}

// Culling (map.culling) drops what cannot reach a pixel: the same image, pixel for pixel, with
// fewer triangles into every map and the camera.
struct Frame {
  io::Image8 color;
  io::ImageF visibility;
  shadows::FrameInfo info;
};
Frame render_frame(shadows::Renderer& r, ShadowSettings st, bool culling, int w, int h) {
  st.map.culling = culling;
  Frame f;
  f.info = r.render(st, w, h);
  f.color = r.read_color();
  f.visibility = r.read_visibility();
  return f;
}

void expect_culling_changes_no_pixel(const scene::Scene& s, const ShadowSettings& st, int w, int h) {
  shadows::Renderer r;
  r.set_scene(s);
  const Frame all = render_frame(r, st, false, w, h);
  const Frame culled = render_frame(r, st, true, w, h);
  EXPECT_EQ(culled.color.pixels, all.color.pixels) << "the lit image differs with culling";
  EXPECT_EQ(culled.visibility.pixels, all.visibility.pixels) << "the visibility differs with culling";
  ASSERT_EQ(culled.info.map_triangles.size(), all.info.map_triangles.size());
  for (std::size_t i = 0; i < all.info.map_triangles.size(); ++i) {
    EXPECT_EQ(all.info.map_triangles[i], all.info.scene_triangles) << "without culling every map draws the scene";
    EXPECT_LE(culled.info.map_triangles[i], all.info.map_triangles[i]) << "map " << i;
  }
  EXPECT_LE(culled.info.camera_triangles, all.info.camera_triangles);
}

TEST(OutdoorGl, CullingChangesNoPixelAndDrawsLess) {
  scene::Scene s = scene::make_builtin_scene("outdoor");
  s.camera = s.camera_path.at(s.camera, 120);
  for (Technique t : {Technique::pcf, Technique::pcss, Technique::vsm}) {
    SCOPED_TRACE(std::string(shadows::to_string(t)));
    ShadowSettings st = test::settings(t, 1024, true);
    st.map.cascades = 4;
    expect_culling_changes_no_pixel(s, st, 192, 108);
  }
  // The near cascade of the street holds a small part of the town.
  shadows::Renderer r;
  r.set_scene(s);
  ShadowSettings st = test::settings(Technique::pcf, 1024, true);
  st.map.cascades = 4;
  const Frame f = render_frame(r, st, true, 192, 108);
  EXPECT_LT(f.info.map_triangles.front(), f.info.scene_triangles / 4);
  // Two camera passes draw it: the depth prepass and the shading (map.depth_prepass).
  EXPECT_LT(f.info.camera_triangles, 2 * (f.info.scene_triangles / 2)) << "the street sees a part of the town";
}

// The maps and cascades cull casters by clusters (scene::cull_clusters against each cascade's four
// sides), as the virtual map's pages do: on the street every cascade holds the same depths, texel
// for texel, as when culled by whole units (a cluster dropped covers none of its texels), from
// fewer triangles, and the image is the same.
TEST(OutdoorGl, CascadesCullByClustersIntoTheSameDepthsAsByUnits) {
  scene::Scene s = scene::make_builtin_scene("outdoor");
  s.camera = s.camera_path.at(s.camera, 120);
  shadows::Renderer by_units, by_clusters;
  by_units.set_scene(s, 0);
  by_clusters.set_scene(s);
  for (Technique t : {Technique::pcf, Technique::vsm}) {
    SCOPED_TRACE(std::string(shadows::to_string(t)));
    ShadowSettings st = test::settings(t, 1024, true);
    st.map.cascades = 4;
    const Frame units = render_frame(by_units, st, true, 192, 108), clusters = render_frame(by_clusters, st, true, 192, 108);
    ASSERT_EQ(units.info.map_triangles.size(), 4u);
    ASSERT_EQ(clusters.info.map_triangles.size(), 4u);
    std::uint64_t by_unit = 0, by_cluster = 0;
    for (int k = 0; k < 4; ++k) {
      SCOPED_TRACE("cascade " + std::to_string(k));
      const io::ImageF a = by_units.read_shadow_depth(k), b = by_clusters.read_shadow_depth(k);
      ASSERT_EQ(a.pixels.size(), b.pixels.size());
      std::size_t differ = 0, covered = 0;
      for (std::size_t i = 0; i < a.pixels.size(); ++i) differ += a.pixels[i] != b.pixels[i], covered += a.pixels[i] < 1.0f;
      EXPECT_EQ(differ, 0u) << "of " << a.pixels.size() << " texels";
      EXPECT_GT(covered, a.pixels.size() / 2) << "the town is in the cascade";
      EXPECT_LT(clusters.info.map_triangles[k], units.info.map_triangles[k]);
      by_unit += units.info.map_triangles[k];
      by_cluster += clusters.info.map_triangles[k];
    }
    EXPECT_EQ(clusters.color.pixels, units.color.pixels);
    EXPECT_EQ(clusters.visibility.pixels, units.visibility.pixels);
    EXPECT_LT(by_cluster, by_unit * 19 / 20) << by_cluster << " against " << by_unit;
  }
}

TEST(OutdoorGl, CullingChangesNoPixelOnTheDemoSceneAndUnderTheFloodlight) {
  const scene::Scene demo = scene::make_builtin_scene("demo");
  expect_culling_changes_no_pixel(demo, test::settings(Technique::pcss, 1024, true), 128, 96);
  scene::Scene spot = scene::make_builtin_scene("outdoor-spot");
  spot.camera = spot.camera_path.at(spot.camera, 120);
  expect_culling_changes_no_pixel(spot, test::settings(Technique::pcf, 1024, true), 128, 72);
}

// The camera's depth prepass (map.depth_prepass): the shading pass then shades each pixel's visible
// surface once instead of every surface drawn over it first (llvmpipe's invocation count cannot
// show it: it counts the fragments rasterized before the depth test, the same with and without),
// and the image is the same but where two surfaces tie in depth (the last drawn shows instead of
// the first). Its triangles are the camera's again; the floor frame has it too.
TEST(OutdoorGl, TheDepthPrepassLeavesTheImageButDepthTiesAndTheFloorHasItToo) {
  scene::Scene s = scene::make_builtin_scene("outdoor");
  s.camera = s.camera_path.at(s.camera, 120);
  const int w = 192, h = 108;
  for (Technique t : {Technique::pcf, Technique::vsm}) {
    SCOPED_TRACE(std::string(shadows::to_string(t)));
    shadows::Renderer r;
    r.set_scene(s);
    ShadowSettings st = test::settings(t, 1024, true);
    st.map.cascades = 4;
    st.map.depth_prepass = false;
    const Frame drawn = render_frame(r, st, true, w, h);
    st.map.depth_prepass = true;
    const Frame prepared = render_frame(r, st, true, w, h);
    EXPECT_EQ(std::count(drawn.info.passes.begin(), drawn.info.passes.end(), "depth_prepass"), 0);
    ASSERT_EQ(std::count(prepared.info.passes.begin(), prepared.info.passes.end(), "depth_prepass"), 1);
    EXPECT_EQ(prepared.info.camera_triangles, 2 * drawn.info.camera_triangles) << "the prepass draws the camera's triangles again";
    const std::uint64_t pixels = static_cast<std::uint64_t>(w) * h;
    std::size_t differ = 0;
    const auto channels = static_cast<std::size_t>(drawn.color.channels);
    ASSERT_EQ(drawn.color.pixels.size(), pixels * channels);
    for (std::size_t i = 0; i < drawn.color.pixels.size(); i += channels)
      for (std::size_t c = 0; c < channels; ++c)
        if (drawn.color.pixels[i + c] != prepared.color.pixels[i + c]) {
          ++differ;
          break;
        }
    EXPECT_LT(differ, pixels / 200) << "more pixels differ than depth ties explain";
    const shadows::FrameInfo floor = r.render(shadows::unshadowed_floor(st), w, h);
    EXPECT_EQ(std::count(floor.passes.begin(), floor.passes.end(), "depth_prepass"), 1) << "the floor shades as its frame does";
  }
}

// Instances (the crane's and the fence's panels) share one mesh on the GPU: the town uploads 13
// meshes for its 111 objects, and draws the same image, pixel for pixel, as a copy of the scene in
// which every object has a mesh of its own.
TEST(OutdoorGl, InstancesShareOneUploadAndDrawAsTheirOwnCopies) {
  scene::Scene s = scene::make_builtin_scene("outdoor");
  s.camera = s.camera_path.at(s.camera, 150);  // the site: fence and crane in view
  scene::Scene own = s;
  for (auto& o : own.objects) o.mesh = std::make_shared<const scene::MeshData>(*o.mesh);
  shadows::Renderer shared_r, own_r;
  shared_r.set_scene(s);
  own_r.set_scene(own);
  EXPECT_EQ(shared_r.uploaded_meshes(), 13u);
  EXPECT_EQ(own_r.uploaded_meshes(), s.objects.size());
  ShadowSettings st = test::settings(Technique::pcf, 1024, true);
  st.map.cascades = 4;
  const Frame a = render_frame(shared_r, st, true, 192, 108), b = render_frame(own_r, st, true, 192, 108);
  EXPECT_EQ(a.color.pixels, b.color.pixels);
  EXPECT_EQ(a.visibility.pixels, b.visibility.pixels);
  EXPECT_EQ(a.info.map_triangles, b.info.map_triangles);
  EXPECT_EQ(a.info.scene_triangles, b.info.scene_triangles) << "every instance counts";
}

// A pillar outside the camera's view whose shadow falls into it: the camera drops it, its map
// draws it, and the shadow is there.
TEST(OutdoorGl, ACasterOutsideTheViewStillCasts) {
  scene::Scene s;
  s.objects.push_back({"ground", std::make_shared<const scene::MeshData>(scene::make_plane(40, 40)), glm::mat4(1), glm::vec3(0.8f)});
  s.objects.push_back({"pillar", std::make_shared<const scene::MeshData>(scene::make_box({2, 10, 2})),
                       glm::translate(glm::mat4(1), glm::vec3(0, 5, 0)), glm::vec3(0.8f)});
  s.light.direction = glm::normalize(glm::vec3(0.5f, -1, 0));  // the shadow falls toward +x, to x = 6
  s.light.size = 0;
  test::look_down(s, {7, 0}, 5);  // sees x in [2, 12], nothing above y = 0.5
  const ShadowSettings st = test::settings(Technique::pcf, 1024, true);
  expect_culling_changes_no_pixel(s, st, 64, 64);

  shadows::Renderer r;
  r.set_scene(s);
  const Frame f = render_frame(r, st, true, 64, 64);
  const std::uint64_t ground = s.objects[0].mesh->indices.size() / 3;
  EXPECT_EQ(f.info.camera_triangles, 2 * ground) << "the camera draws the ground only, in its depth prepass and its shading";
  EXPECT_EQ(f.info.map_triangles.front(), f.info.scene_triangles) << "the map draws the pillar";
  const auto [dark, lit] = shadow_and_lit(f.visibility);
  EXPECT_GT(dark, 0.05) << "the pillar's shadow is in view (x in [2, 6], z in [-1, 1]: 8 % of it)";
  EXPECT_GT(lit, 0.5);
}

}  // namespace
}  // namespace penumbra
