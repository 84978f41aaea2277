// The outdoor scene through the renderer: every technique gives a finite image with shadows in it,
// under the sun (with cascades where a technique has them) and under the floodlight.
#include <gtest/gtest.h>

#include <string>

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

}  // namespace
}  // namespace penumbra
