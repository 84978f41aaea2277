// The screen-space techniques against their defining formulas (label `gl`):
//  - EDTSM: I = 1/2 at the silhouette sites, 1/2 -+ D/P inside the penumbra, exactly 0 or 1 from
//    D = P/2 on (mean filter off), and a filter that keeps the edge where it was;
//  - EDTSM's penumbra is world-sized: the same from two camera distances;
//  - the pipeline stays finite on 1x1, line-shaped and odd-sized images;
//  - EDTSSM and erosion: on two parallel planes under a spot light of width W the penumbra is
//    W (z_R - z_B) / z_B wide, so it grows with the blocker's height and vanishes at contact.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <ostream>
#include <string>
#include <vector>

#include "gl_test_env.h"
#include "shadows/renderer.h"

namespace penumbra {
namespace {

using shadows::ShadowSettings;
using shadows::Technique;
using test::column_means;
using test::crossing;
using test::look_down;
using test::render_visibility;

// ---- EDTSM ---------------------------------------------------------------------------------------

class Edtsm : public ::testing::Test {
 protected:
  // The square occluder's edge x = 1 seen from above, 1 px = 1/400 world unit; P = 40 px.
  static constexpr int kPixels = 400;
  static constexpr float kWsPerPx = 1.0f / kPixels;
  static constexpr int kHalfPenumbraPx = 20;

  io::ImageF render(float filter_ws, io::ImageF* input = nullptr, bool edge_between_pixels = false) {
    scene::Scene s = scene::make_square_scene(2, 1);
    look_down(s, {1, 0}, 0.5f);
    ShadowSettings st;
    st.technique = Technique::edtsm;
    st.map.resolution_texels = 1024;
    st.edtsm.penumbra_ws = 2 * kHalfPenumbraPx * kWsPerPx;
    st.edtsm.filter_ws = filter_ws;
    st.edtsm.edge_between_pixels = edge_between_pixels;
    shadows::Renderer r;
    r.set_scene(s);
    const shadows::FrameInfo info = r.render(st, kPixels, kPixels);
    const std::vector<std::string> passes = {"shadow_map", "gbuffer", "sites", "edt", "edt_penumbra", "mean_filter", "shading"};
    EXPECT_EQ(info.passes, passes);
    if (input) *input = r.read_screen_space_input();
    return r.read_visibility();
  }
};

TEST_F(Edtsm, IntensityIsHalfAtTheSitesLinearInWorldDistanceAndExactlyZeroOrOneAtHalfP) {
  io::ImageF hard;
  const io::ImageF vis = render(0, &hard);
  ASSERT_TRUE(test::all_finite_in(vis, 0, 1));
  const double half_p_ws = kHalfPenumbraPx * kWsPerPx;
  int rows_checked = 0;
  for (int y = 50; y < kPixels - 50; y += 7) {
    // The hard edge on this row: last shadowed pixel s0, first lit pixel s1 = s0 + 1; both are sites.
    int s0 = -1;
    for (int x = 0; x + 1 < kPixels; ++x)
      if (hard.at(x, y) == 0.0f && hard.at(x + 1, y) == 1.0f) s0 = x;
    ASSERT_GT(s0, kHalfPenumbraPx + 2) << "row " << y;
    ASSERT_LT(s0 + 1, kPixels - kHalfPenumbraPx - 2) << "row " << y;
    // The edge is straight (parallel to the map's grid and the image's columns): D = k px exactly.
    EXPECT_FLOAT_EQ(vis.at(s0, y), 0.5f) << "row " << y;
    EXPECT_FLOAT_EQ(vis.at(s0 + 1, y), 0.5f) << "row " << y;
    for (int k = 1; k <= kHalfPenumbraPx + 5; ++k) {
      const double d = k * kWsPerPx;
      const double in_shadow = d < half_p_ws ? 0.5 - d / (2 * half_p_ws) : 0.0;
      const double lit = d < half_p_ws ? 0.5 + d / (2 * half_p_ws) : 1.0;
      EXPECT_NEAR(vis.at(s0 - k, y), in_shadow, 1e-4) << "row " << y << ", " << k << " px into the shadow";
      EXPECT_NEAR(vis.at(s0 + 1 + k, y), lit, 1e-4) << "row " << y << ", " << k << " px into the light";
    }
    // At D = P/2: 0 and 1 up to the float rounding of D; beyond it the hard value, exactly.
    EXPECT_NEAR(vis.at(s0 - kHalfPenumbraPx, y), 0.0f, 1e-6);
    EXPECT_NEAR(vis.at(s0 + 1 + kHalfPenumbraPx, y), 1.0f, 1e-6);
    for (int k = kHalfPenumbraPx + 1; k <= kHalfPenumbraPx + 5; ++k) {
      EXPECT_EQ(vis.at(s0 - k, y), 0.0f);
      EXPECT_EQ(vis.at(s0 + 1 + k, y), 1.0f);
    }
    ++rows_checked;
  }
  EXPECT_GT(rows_checked, 30);
}

TEST_F(Edtsm, EdgeBetweenPixelsPutsOneHalfOnTheSilhouetteItself) {
  // D measured from the silhouette between the site pixels: each site is half a pixel from it.
  io::ImageF hard;
  const io::ImageF vis = render(0, &hard, true);
  for (int y = 50; y < kPixels - 50; y += 7) {
    int s0 = -1;
    for (int x = 0; x + 1 < kPixels; ++x)
      if (hard.at(x, y) == 0.0f && hard.at(x + 1, y) == 1.0f) s0 = x;
    ASSERT_GT(s0, kHalfPenumbraPx + 2) << "row " << y;
    EXPECT_NEAR(vis.at(s0, y) + vis.at(s0 + 1, y), 1.0, 1e-5) << "1/2 halfway between the sites, row " << y;
    for (int k = 0; k < kHalfPenumbraPx; ++k) {
      const double d_px = k + 0.5;
      EXPECT_NEAR(vis.at(s0 - k, y), 0.5 - d_px / (2 * kHalfPenumbraPx), 1e-4) << "row " << y << ", k " << k;
      EXPECT_NEAR(vis.at(s0 + 1 + k, y), 0.5 + d_px / (2 * kHalfPenumbraPx), 1e-4) << "row " << y << ", k " << k;
    }
    EXPECT_EQ(vis.at(s0 - kHalfPenumbraPx, y), 0.0f);
    EXPECT_EQ(vis.at(s0 + 1 + kHalfPenumbraPx, y), 1.0f);
  }
}

TEST_F(Edtsm, MeanFilterKeepsTheEdgeAndTheRampMonotone) {
  const io::ImageF vis = render(0.03f);  // a 12-px box
  ASSERT_TRUE(test::all_finite_in(vis, 0, 1));
  const auto profile = column_means(vis, 100, 300);
  for (std::size_t i = 1; i < profile.size(); ++i) EXPECT_GE(profile[i] + 1e-6, profile[i - 1]) << "column " << i;
  // Half visibility stays on the occluder's edge (x = 1) within a shadow-map texel and a pixel.
  EXPECT_NEAR(crossing(profile, 0.5, 0.5, kWsPerPx), 1.0, 2 * kWsPerPx + 4.0 / 1024);
  // The box widens the ramp by its own width at most: fully dark/lit beyond P/2 + 6 px.
  EXPECT_EQ(profile.front(), 0.0);
  EXPECT_EQ(profile.back(), 1.0);
}

TEST_F(Edtsm, PenumbraIsViewpointInvariantInWorldUnits) {
  // A perspective camera straight above the edge at two heights: the fake penumbra and the mean
  // filter are world-sized, so the ramp measured in world units is the same from both.
  const int n = 400;
  const float fov_deg = 40;
  double widths[2];
  int i = 0;
  for (float height : {3.0f, 6.0f}) {
    scene::Scene s = scene::make_square_scene(2, 1);
    s.camera.projection = scene::Camera::Projection::perspective;
    s.camera.position = {1, height, 0};
    s.camera.target = {1, 0, 0};
    s.camera.up = {0, 0, -1};
    s.camera.fov_y_deg = fov_deg;
    s.camera.near_ws = height - 0.5f;  // the receiver only
    s.camera.far_ws = height + 1;
    ShadowSettings st;
    st.technique = Technique::edtsm;
    st.map.resolution_texels = 2048;
    st.edtsm.penumbra_ws = 0.2f;
    st.edtsm.filter_ws = 0.1f;
    const io::ImageF vis = render_visibility(s, st, n);
    ASSERT_TRUE(test::all_finite_in(vis, 0, 1));
    const auto profile = column_means(vis, n / 2 - 20, n / 2 + 20);
    const double ws_per_px = 2 * height * std::tan(glm::radians(fov_deg) / 2) / n;  // on the receiver
    // Only the edge x = 1 (the view's centre column); the square's far edge x = -1 is in view too.
    const int reach = static_cast<int>(0.5 / ws_per_px);
    int first = -1, last = -1;
    for (int x = n / 2 - reach; x < n / 2 + reach; ++x) {
      if (first < 0 && profile[static_cast<std::size_t>(x)] > 0.01) first = x;
      if (profile[static_cast<std::size_t>(x)] < 0.99) last = x;
    }
    widths[i++] = (last - first + 1) * ws_per_px;
    RecordProperty("width_ws_from_" + std::to_string(static_cast<int>(height)), std::to_string(widths[i - 1]));
  }
  // P = 0.2 plus at most the box's 0.1: about 0.25 world units from either height.
  EXPECT_NEAR(widths[0], widths[1], 2 * 2 * 6.0 * std::tan(glm::radians(fov_deg) / 2) / n);
  EXPECT_GT(widths[0], 0.2);
  EXPECT_LT(widths[0], 0.32);
}

TEST(ScreenSpaceImages, OddTinyAndLineShapedImagesStayFinite) {
  const scene::Scene s = scene::make_builtin_scene("demo");
  for (Technique t : {Technique::edtsm, Technique::edtssm, Technique::erosion}) {
    shadows::Renderer r;
    r.set_scene(s);
    ShadowSettings st;
    st.technique = t;
    st.map.resolution_texels = 512;
    for (const auto& [w, h] : std::vector<std::pair<int, int>>{{1, 1}, {1, 64}, {64, 1}, {37, 91}, {91, 37}, {3, 2}}) {
      r.render(st, w, h);
      EXPECT_TRUE(test::all_finite_in(r.read_visibility(), 0, 1)) << shadows::to_string(t) << " " << w << "x" << h;
    }
  }
}

// ---- EDTSSM and erosion: the parallel-planes penumbra --------------------------------------------

struct PlanesCase {
  Technique technique;
  double tolerance;  // relative, on the measured full width
};

void PrintTo(const PlanesCase& c, std::ostream* os) { *os << shadows::to_string(c.technique); }

class ParallelPlanes : public ::testing::TestWithParam<PlanesCase> {};

// Full width (world units) of the 1 %-99 % transition of the column-mean profile across the
// blocker's edge, for a blocker at `blocker_height`.
double measured_width(Technique t, float blocker_height, double* centre) {
  const float light_height = 10, light_width = 1;
  scene::Scene s = scene::make_two_planes_scene(blocker_height, light_height, light_width);
  const float half = 1.0f;
  look_down(s, {0, 0}, half, std::min(0.5f, blocker_height / 2));
  const int n = 800;
  const double ws_per_px = 2.0 * half / n;
  ShadowSettings st;
  st.technique = t;
  st.map.resolution_texels = 2048;
  st.edtssm.filter_ws = 0;  // the formula, before the skeleton filter
  const io::ImageF vis = render_visibility(s, st, n);
  EXPECT_TRUE(test::all_finite_in(vis, 0, 1));
  const auto profile = column_means(vis, n / 2 - 100, n / 2 + 100);
  int first = -1, last = -1;
  for (int i = 0; i < n; ++i) {
    if (first < 0 && profile[static_cast<std::size_t>(i)] > 0.01) first = i;
    if (profile[static_cast<std::size_t>(i)] < 0.99) last = i;
  }
  *centre = crossing(profile, 0.5, -half, ws_per_px);
  return (last - first + 1) * ws_per_px;
}

TEST_P(ParallelPlanes, PenumbraWidthFollowsTheParallelPlanesFormula) {
  const PlanesCase c = GetParam();
  double previous = 0;
  for (float blocker_height : {1.0f, 2.0f, 4.0f}) {
    double centre = 0;
    const double measured = measured_width(c.technique, blocker_height, &centre);
    const double z_r = 10, z_b = 10 - blocker_height;
    const double expected = 1.0 * (z_r - z_b) / z_b;
    EXPECT_NEAR(measured, expected, c.tolerance * expected + 0.01) << "blocker at " << blocker_height;
    EXPECT_GT(measured, previous) << "the penumbra must widen as the blocker rises";
    EXPECT_NEAR(centre, 0.0, 0.1 * expected + 0.005) << "centred on the blocker's edge";
    previous = measured;
    RecordProperty(std::string(shadows::to_string(c.technique)) + "_width_h" + std::to_string(blocker_height),
                   std::to_string(measured) + " vs " + std::to_string(expected));
  }
}

TEST_P(ParallelPlanes, ContactHardens) {
  double centre = 0;
  // Blocker 0.05 above the receiver: the penumbra is 0.005 wide (2 pixels of 0.0025; 44 pixels
  // with the blocker at 1). Allowed: the two site pixels and one pixel of edge placement per side.
  EXPECT_LE(measured_width(GetParam().technique, 0.05f, &centre), 4 * 0.0025 + 1e-9);
}

INSTANTIATE_TEST_SUITE_P(ScreenSpace, ParallelPlanes,
                         ::testing::Values(PlanesCase{Technique::edtssm, 0.1}, PlanesCase{Technique::erosion, 0.15}),
                         [](const auto& param_info) { return std::string(shadows::to_string(param_info.param.technique)); });

}  // namespace
}  // namespace penumbra
