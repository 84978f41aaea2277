// The shadow-map-side alternatives (RBSM, RPCF, MSM, EVSM, ESM) against their defining properties
// (label `gl`: needs an OpenGL 4.5 context; Mesa llvmpipe through EGL is enough).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <iterator>
#include <cmath>
#include <string>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "gl_test_env.h"
#include "gl/shader_library.h"
#include "shadows/moments_blur.h"
#include "shadows/techniques/esm.h"
#include "shadows/techniques/evsm.h"
#include "shadows/renderer.h"

namespace penumbra {
namespace {

using shadows::Kernel;
using shadows::ShadowSettings;
using shadows::Technique;
using test::look_down;
using test::pixel_to_world;
using test::render_visibility;
using test::settings;

// ---- RBSM: the staircase of a rotated square's edge ----------------------------------------------

// The square scene with the occluder turned by `angle_deg` about the vertical: its shadow under
// the straight-down light is the same square turned, so every edge is analytic.
scene::Scene rotated_square(float angle_deg) {
  scene::Scene s = scene::make_square_scene(2, 1);
  s.objects[1].model = glm::rotate(glm::translate(glm::mat4(1), glm::vec3(0, 1, 0)), glm::radians(angle_deg), glm::vec3(0, 1, 0));
  return s;
}

// Signed distance (world units, > 0 outside) from (x, z) to the boundary of the square of half
// side 1 turned by angle_deg, valid near the middle of its edges.
float square_distance(float x, float z, float angle_deg) {
  const float a = glm::radians(angle_deg);
  const float lx = x * std::cos(a) - z * std::sin(a);
  const float lz = x * std::sin(a) + z * std::cos(a);
  return std::max(std::abs(lx), std::abs(lz)) - 1.0f;
}

struct EdgeError {
  double xor_texels = 0;       // misclassified area per unit edge length, in texels
  double max_distance_texels = 0;  // farthest misclassified pixel from the true edge
};

// Hard-shadow footprint error along the middle of the edge local x = +1 of the turned square,
// in a window of half side `half` around it: pixels with visibility < 0.5 count as shadowed.
EdgeError edge_error(const ShadowSettings& st, float angle_deg, int n, float half) {
  const scene::Scene base = rotated_square(angle_deg);
  const float a = glm::radians(angle_deg);
  const glm::vec2 centre(std::cos(a), -std::sin(a));  // local (1, 0) in world x, z
  scene::Scene s = base;
  look_down(s, centre, half);
  shadows::Renderer r;
  r.set_scene(s);
  const auto info = r.render(st, n, n);
  const io::ImageF vis = r.read_visibility();
  const double texel = info.light.texel_ws(0, st.map.resolution_texels);
  const double px = 2.0 * half / n;
  int wrong = 0;
  double max_d = 0;
  for (int y = 0; y < n; ++y) {
    for (int x = 0; x < n; ++x) {
      const float wx = pixel_to_world(x, n, centre.x, half), wz = pixel_to_world(y, n, centre.y, half);
      const float d = square_distance(wx, wz, angle_deg);
      const bool shadowed = vis.at(x, y) < 0.5f;
      if (shadowed != (d < 0)) {
        ++wrong;
        max_d = std::max(max_d, static_cast<double>(std::abs(d)));
      }
    }
  }
  const double edge_length = 2.0 * half / std::max(std::abs(std::sin(a)), std::abs(std::cos(a)));
  return {wrong * px * px / edge_length / texel, max_d / texel};
}

class RbsmStaircase : public ::testing::TestWithParam<float> {};

TEST_P(RbsmStaircase, ReducesTheFootprintErrorOfShadowMappingAt512) {
  const float angle = GetParam();
  const int n = 400, res = 512;
  const float half = 0.4f;  // about 20 texels either side of the edge's middle, 10 pixels per texel
  const EdgeError hard = edge_error(settings(Technique::hard, res, false), angle, n, half);
  const EdgeError rbsm = edge_error(settings(Technique::rbsm, res, false), angle, n, half);
  RecordProperty("hard_xor_texels", std::to_string(hard.xor_texels));
  RecordProperty("rbsm_xor_texels", std::to_string(rbsm.xor_texels));
  RecordProperty("hard_max_texels", std::to_string(hard.max_distance_texels));
  RecordProperty("rbsm_max_texels", std::to_string(rbsm.max_distance_texels));
  std::printf("angle %5.1f: XOR area per edge length %.3f -> %.3f texels, farthest error %.3f -> %.3f texels\n", angle,
              hard.xor_texels, rbsm.xor_texels, hard.max_distance_texels, rbsm.max_distance_texels);
  // A staircase of centre samples misplaces the edge by a quarter texel on average.
  EXPECT_GT(hard.xor_texels, 0.1);
  // Revectorized: the line through the risers' midpoints, within half the slope of the truth
  // (the staircase leaves the edge's phase that uncertain), plus a pixel of rasterization.
  EXPECT_LT(rbsm.xor_texels, 0.5 * hard.xor_texels);
  EXPECT_LT(rbsm.max_distance_texels, 0.5 * hard.max_distance_texels);
  EXPECT_LT(rbsm.max_distance_texels, 0.3);
}

INSTANTIATE_TEST_SUITE_P(Angles, RbsmStaircase, ::testing::Values(9.0f, 18.43f, 33.0f, 45.0f, 71.57f),
                         [](const auto& p) { return "deg" + std::to_string(static_cast<int>(p.param * 100)); });

TEST(Rbsm, AxisAlignedEdgesStayWhereShadowMappingPutsThem) {
  // A long straight step ends in the square's corners (risers longer than one texel): the
  // revectorized line is the texel border itself, so RBSM equals the hard test away from corners.
  for (int res : {250, 256}) {  // edge on a texel border, and inside a texel
    scene::Scene s = scene::make_square_scene(2, 1);
    look_down(s, {1, 0}, 0.5f);
    const int n = 200;
    const io::ImageF hard = render_visibility(s, settings(Technique::hard, res, false), n);
    const io::ImageF rbsm = render_visibility(s, settings(Technique::rbsm, res, false), n);
    int differ = 0;
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) differ += hard.at(x, y) != rbsm.at(x, y);
    EXPECT_EQ(differ, 0) << "resolution " << res;
  }
}

TEST(Rbsm, VisibilityIsHardAndTheFarFieldIsUntouched) {
  scene::Scene s = rotated_square(30);
  look_down(s, {0, 0}, 2);
  const int n = 256;
  const io::ImageF vis = render_visibility(s, settings(Technique::rbsm, 128, true), n);
  int shadowed = 0;
  for (int y = 0; y < n; ++y) {
    for (int x = 0; x < n; ++x) {
      const float v = vis.at(x, y);
      ASSERT_TRUE(v == 0.0f || v == 1.0f) << v;
      const float d = square_distance(pixel_to_world(x, n, 0, 2), pixel_to_world(y, n, 0, 2), 30);
      if (std::abs(d) > 0.1f) {
        EXPECT_EQ(v, d < 0 ? 0.0f : 1.0f);  // 0.1 ws is more than three texels here
      }
      shadowed += v == 0.0f;
    }
  }
  EXPECT_GT(shadowed, n * n / 8);
}

// ---- RPCF ---------------------------------------------------------------------------------------

TEST(Rpcf, TexelAlignedEdgeGivesTheBoxPcfRamp) {
  // Nothing to revectorize on a straight texel-aligned edge: RPCF is the exact box PCF.
  scene::Scene s = scene::make_square_scene(2, 1);
  look_down(s, {1, 0}, 0.5f);
  const int n = 200, res = 250;
  ShadowSettings rpcf = settings(Technique::rpcf, res, false);
  rpcf.rpcf.radius = 2.5f;
  ShadowSettings pcf = settings(Technique::pcf, res, false);
  pcf.pcf.kernel = Kernel::grid;
  pcf.pcf.radius = 2.5f;
  const io::ImageF a = render_visibility(s, rpcf, n), b = render_visibility(s, pcf, n);
  ASSERT_TRUE(test::all_finite_in(a, 0, 1));
  for (int x = 0; x < n; ++x) EXPECT_NEAR(a.at(x, n / 2), b.at(x, n / 2), 1e-4) << "column " << x;
}

// Waviness of the visibility-0.5 contour of the turned square's edge local x = +1: the largest
// distance (texels) of the contour from its own best straight line (one interpolated crossing per
// row, least squares). A staircase makes the contour wave with the step period; a uniform shift
// of the whole edge does not count.
double contour_waviness(const ShadowSettings& st, float angle_deg, int n, float half) {
  scene::Scene s = rotated_square(angle_deg);
  const float a = glm::radians(angle_deg);
  const glm::vec2 centre(std::cos(a), -std::sin(a));
  look_down(s, centre, half);
  shadows::Renderer r;
  r.set_scene(s);
  const auto info = r.render(st, n, n);
  const io::ImageF vis = r.read_visibility();
  const double texel = info.light.texel_ws(0, st.map.resolution_texels);
  std::vector<double> ys, xs;
  for (int y = n / 8; y < 7 * n / 8; ++y) {
    for (int x = 1; x < n; ++x) {
      const float v0 = vis.at(x - 1, y), v1 = vis.at(x, y);
      if ((v0 < 0.5f) == (v1 < 0.5f)) continue;
      xs.push_back(pixel_to_world(x - 1, n, centre.x, half) + (0.5f - v0) / (v1 - v0) * 2 * half / n);
      ys.push_back(pixel_to_world(y, n, centre.y, half));
      break;
    }
  }
  EXPECT_GT(ys.size(), static_cast<std::size_t>(n / 2));
  double my = 0, mx = 0;
  for (std::size_t i = 0; i < ys.size(); ++i) my += ys[i], mx += xs[i];
  my /= static_cast<double>(ys.size());
  mx /= static_cast<double>(ys.size());
  double syy = 0, sxy = 0;
  for (std::size_t i = 0; i < ys.size(); ++i) syy += (ys[i] - my) * (ys[i] - my), sxy += (ys[i] - my) * (xs[i] - mx);
  const double slope = sxy / syy;
  double worst = 0;
  for (std::size_t i = 0; i < ys.size(); ++i)
    worst = std::max(worst, std::abs(xs[i] - mx - slope * (ys[i] - my)) / std::sqrt(1 + slope * slope));
  return worst / texel;
}

TEST(Rpcf, HalfContourIsStraighterThanPcfOfTheSameBox) {
  // Regular staircases (slope 1/3, 1) revectorize into straight lines; irregular ones (33 deg:
  // steps of one and two texels) into a polyline through the risers' midpoints, which still waves.
  const int n = 400, res = 512;
  double ratio_sum = 0;
  const float angles[] = {9.0f, 18.43f, 33.0f, 45.0f};
  for (float angle : angles) {
    ShadowSettings rpcf = settings(Technique::rpcf, res, false);
    rpcf.rpcf.radius = 1;
    ShadowSettings pcf = settings(Technique::pcf, res, false);
    pcf.pcf.kernel = Kernel::grid;
    pcf.pcf.radius = 1;
    const double w_rpcf = contour_waviness(rpcf, angle, n, 0.4f), w_pcf = contour_waviness(pcf, angle, n, 0.4f);
    std::printf("angle %5.1f: 0.5-contour waviness %.3f texels (PCF grid r 1) vs %.3f (RPCF r 1)\n", angle, w_pcf, w_rpcf);
    EXPECT_LT(w_rpcf, 0.8 * w_pcf) << "angle " << angle;
    ratio_sum += w_rpcf / w_pcf;
  }
  EXPECT_LT(ratio_sum / std::size(angles), 0.5);
}

// ---- MSM and EVSM -------------------------------------------------------------------------------

std::vector<ShadowSettings> filtered_variants(int res, bool fit, float radius) {
  std::vector<ShadowSettings> out;
  ShadowSettings msm = settings(Technique::msm, res, fit);
  msm.msm.radius = radius;
  out.push_back(msm);
  ShadowSettings evsm = settings(Technique::evsm, res, fit);
  evsm.evsm.radius = radius;
  out.push_back(evsm);
  evsm.evsm.format = shadows::MomentFormat::rgba16f;
  evsm.evsm.positive_exponent = 42;  // clamped to 5.54 by the format
  evsm.evsm.negative_exponent = 42;
  out.push_back(evsm);
  return out;
}

std::string name_of(const ShadowSettings& st) { return shadows::describe(st); }

TEST(Moments, ZeroWellInsideAndOneWellOutsideAPlanarOccludersShadow) {
  scene::Scene s = scene::make_square_scene(2, 1);
  look_down(s, {0, 0}, 2);
  const int n = 256, res = 256;
  const float radius = 3;
  for (const auto& st : filtered_variants(res, false, radius)) {
    SCOPED_TRACE(name_of(st));
    const io::ImageF vis = render_visibility(s, st, n);
    ASSERT_TRUE(test::all_finite_in(vis, 0, 1));
    const float texel = 10.0f / res;
    float worst_inside = 0, worst_outside = 1;
    for (int y = 0; y < n; ++y) {
      for (int x = 0; x < n; ++x) {
        const float d = square_distance(pixel_to_world(x, n, 0, 2), pixel_to_world(y, n, 0, 2), 0);
        if (std::abs(d) < (radius + 1.5f) * texel) continue;
        if (d < 0) worst_inside = std::max(worst_inside, vis.at(x, y));
        else worst_outside = std::min(worst_outside, vis.at(x, y));
      }
    }
    EXPECT_LE(worst_inside, 1e-3f);
    EXPECT_GE(worst_outside, 1.0f - 1e-3f);
  }
}

TEST(Moments, LessLightBleedingThanVsmWithThreeDepths) {
  // A high half-plane (y = 4, x < 0) over a low plate (y = 0.6) over the ground: under the plate
  // the ground is in umbra, but where the filter straddles the high edge the moments mix two
  // blocker depths and VSM's bound lets light through.
  scene::Scene s = scene::make_square_scene(2, 1);
  s.objects.resize(1);  // the ground
  auto box = [](glm::vec3 size, glm::vec3 at) {
    return scene::Object{"plate", std::make_shared<const scene::MeshData>(scene::make_box(size)),
                         glm::translate(glm::mat4(1), at), {0.5f, 0.5f, 0.5f}};
  };
  s.objects.push_back(box({4, 0.01f, 4}, {0, 0.6f, 0}));  // above y = 0.5: the camera sees only the ground
  s.objects.push_back(box({4, 0.01f, 4}, {-2, 4, 0}));
  look_down(s, {0, 0}, 0.5f);
  const int n = 200, res = 256;
  const float radius = 3;
  auto worst_bleed = [&](const ShadowSettings& st) {
    const io::ImageF vis = render_visibility(s, st, n);
    EXPECT_TRUE(test::all_finite_in(vis, 0, 1));
    float worst = 0;
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) worst = std::max(worst, vis.at(x, y));  // all of it is umbra
    return worst;
  };
  ShadowSettings vsm = settings(Technique::vsm, res, false);
  vsm.vsm.radius = radius;
  vsm.vsm.bleed_reduction = 0;
  const float vsm_bleed = worst_bleed(vsm);
  std::printf("worst light bleeding in umbra: VSM %.4f", vsm_bleed);
  EXPECT_GT(vsm_bleed, 0.2f) << "the configuration must make VSM bleed";
  for (const auto& st : filtered_variants(res, false, radius)) {
    const float bleed = worst_bleed(st);
    std::printf(", %s %.4f", name_of(st).c_str(), bleed);
    EXPECT_LT(bleed, 0.5f * vsm_bleed) << name_of(st);
  }
  std::printf("\n");
}

TEST(Moments, FilteredResultApproximatesBoxPcfOnTwoPlanes) {
  // Two depths under the filter (blocker, receiver): the exact answer is the box PCF of the
  // same radius. MSM's bias and EVSM's warps move it by at most the bound below.
  scene::Scene s = scene::make_two_planes_scene(3, 10, 1);
  look_down(s, {0, 0}, 0.5f);
  // 12 texels on 512: EVSM's window (24 texels) adds whole chunks of the line (vsm_blur.comp).
  for (const float radius : {4.0f, 12.0f}) {
    const int n = 200, res = 512;
    ShadowSettings pcf = settings(Technique::pcf, res, true);
    pcf.pcf.kernel = Kernel::grid;
    pcf.pcf.radius = radius;
    pcf.pcf.max_grid_taps = 64;
    const io::ImageF reference = render_visibility(s, pcf, n);
    for (const auto& st : filtered_variants(res, true, radius)) {
      const io::ImageF vis = render_visibility(s, st, n);
      float worst = 0;
      for (int x = 0; x < n; ++x) worst = std::max(worst, std::abs(vis.at(x, n / 2) - reference.at(x, n / 2)));
      std::printf("%s, r = %g texels: largest |visibility - box PCF| across the edge %.4f\n", name_of(st).c_str(), radius, worst);
      EXPECT_LT(worst, 0.05f) << name_of(st) << " r = " << radius;
    }
  }
}

TEST(Moments, WideBlurOnALargeMapCoversTheWholeMap) {
  // 2048 texels per line and a 24-texel radius: a blur that walked a whole line of windows in one
  // invocation ran 2048 * 49 loop iterations, past llvmpipe's 65535 per invocation, and left the
  // end of every line unwritten (a dark block in the lit half). Lit wherever box PCF is lit.
  scene::Scene s = scene::make_two_planes_scene(3, 10, 1);
  const int res = 2048, n = 160;
  const float radius = 24;
  ShadowSettings pcf = settings(Technique::pcf, res, true);
  pcf.pcf.kernel = Kernel::grid;
  pcf.pcf.radius = radius;
  pcf.pcf.max_grid_taps = 64;
  shadows::Renderer r;
  r.set_scene(s);
  r.render(pcf, n, n * 9 / 16);
  const io::ImageF reference = r.read_visibility();
  for (const auto& st : filtered_variants(res, true, radius)) {
    r.render(st, n, n * 9 / 16);
    const io::ImageF vis = r.read_visibility();
    int dark = 0, checked = 0;
    for (int y = 0; y < vis.height; ++y)
      for (int x = 0; x < vis.width; ++x) {
        if (reference.at(x, y) < 1.0f) continue;
        ++checked;
        dark += vis.at(x, y) < 0.98f;
      }
    EXPECT_GT(checked, vis.width * vis.height / 4) << name_of(st);
    EXPECT_EQ(dark, 0) << name_of(st);
  }
}

TEST(Moments, NeverDarkerThanBoxPcfOfTheSameRadius) {
  // Chebyshev (VSM, EVSM) and the Hamburger bound (MSM) bound the lit fraction from above, so
  // where the box PCF of the same radius is fully lit they must be lit too: no streaks, no acne.
  // The fence scene puts the sky (far-plane moments, e^84 for EVSM at c = 42) beside receivers.
  scene::Scene s = scene::make_builtin_scene("fence");
  const int res = 1024;
  const float radius = 2;
  ShadowSettings pcf = settings(Technique::pcf, res, true);
  pcf.pcf.kernel = Kernel::grid;
  pcf.pcf.radius = radius;
  shadows::Renderer r;
  r.set_scene(s);
  r.render(pcf, 320, 180);
  const io::ImageF reference = r.read_visibility();
  std::vector<ShadowSettings> variants = filtered_variants(res, true, radius);
  variants[1].evsm.positive_exponent = 42;
  for (const auto& st : variants) {
    r.render(st, 320, 180);
    const io::ImageF vis = r.read_visibility();
    int dark = 0, checked = 0;
    for (int y = 2; y < vis.height - 2; ++y) {
      for (int x = 2; x < vis.width - 2; ++x) {
        bool lit = true;  // the whole 5x5 neighbourhood: away from contacts and screen-space edges
        for (int dy = -2; dy <= 2; ++dy)
          for (int dx = -2; dx <= 2; ++dx) lit = lit && reference.at(x + dx, y + dy) == 1.0f;
        if (!lit) continue;
        ++checked;
        dark += vis.at(x, y) < 0.98f;
      }
    }
    EXPECT_GT(checked, vis.width * vis.height / 3);
    EXPECT_EQ(dark, 0) << name_of(st);
  }
}

TEST(Evsm, ExponentsAreClampedToTheFormat) {
  shadows::EvsmParams p;
  p.positive_exponent = 42;
  p.negative_exponent = 30;
  EXPECT_EQ(shadows::evsm_exponents(p), glm::vec2(42, 30));
  p.format = shadows::MomentFormat::rgba16f;
  EXPECT_EQ(shadows::evsm_exponents(p), glm::vec2(5.54f, 5.54f));
  // The largest second moment fits the format: e^(2 * 5.54) below half's 65504, e^84 below 3.4e38.
  EXPECT_LT(std::exp(2.0 * shadows::evsm_exponent_limit(shadows::MomentFormat::rgba16f)), 65504.0);
  EXPECT_LT(std::exp(2.0 * shadows::evsm_exponent_limit(shadows::MomentFormat::rgba32f)), 3.4e38);
  const auto far = shadows::evsm_layout(p).far_moments;
  EXPECT_FLOAT_EQ(far[0], std::exp(5.54f));
  EXPECT_FLOAT_EQ(far[3], std::exp(-2 * 5.54f));
}

// ---- ESM ------------------------------------------------------------------------------------------

ShadowSettings esm_settings(int res, bool fit, float radius, float exponent) {
  ShadowSettings st = settings(Technique::esm, res, fit);
  st.esm.radius = radius;
  st.esm.exponent = exponent;
  return st;
}

TEST(Esm, ExponentIsClampedToTheFloatRange) {
  shadows::EsmParams p;
  EXPECT_EQ(shadows::esm_exponent(p), shadows::kEsmMaxExponent) << "the default is the largest kept";
  p.exponent = 1000;
  EXPECT_EQ(shadows::esm_exponent(p), shadows::kEsmMaxExponent);
  p.exponent = -5;
  EXPECT_EQ(shadows::esm_exponent(p), 0.0f);
  // The far plane's exp(c), summed over a blur window as wide as the largest texture, stays finite.
  EXPECT_LT(std::exp(static_cast<double>(shadows::kEsmMaxExponent)) * 65536.0, 3.4e38);
  ShadowSettings st;
  st.esm.exponent = 1000;
  const auto layout = shadows::technique_entry(Technique::esm).moments(st);
  ASSERT_TRUE(layout.has_value());
  EXPECT_EQ(layout->format, shadows::MomentsFormat::r32f);
  EXPECT_FLOAT_EQ(layout->far_moments[0], std::exp(shadows::kEsmMaxExponent));
  EXPECT_TRUE(layout->direct_sums);
}

TEST(Esm, UmbraLeaksAsExpMinusCTimesTheDepthGap) {
  // The square plate one unit above the ground: in its umbra the receiver is Δt behind the
  // occluder, and ESM reads exp(-c Δt) there (Annen et al.: the approximation's light leak).
  // A larger c leaks less; outside the shadow every pixel is lit; nothing leaves [0, 1].
  scene::Scene s = scene::make_square_scene(2, 1);
  look_down(s, {0, 0}, 2);
  const int n = 128, res = 256;
  // Small exponents make the leak large enough to measure; the default leaves none to see.
  float umbra[3] = {0, 0, 0};
  const float exponents[3] = {2, 5, shadows::kEsmMaxExponent};
  for (int i = 0; i < 3; ++i) {
    const ShadowSettings st = esm_settings(res, false, 2, exponents[i]);
    shadows::Renderer r;
    r.set_scene(s);
    const shadows::FrameInfo info = r.render(st, n, n);
    const io::ImageF vis = r.read_visibility();
    ASSERT_TRUE(test::all_finite_in(vis, 0, 1));
    // Normalized depth gap between plate and ground along the (straight-down) light.
    const double gap = 1.0 / (info.light.far_ws - info.light.near_ws);
    const float texel = 10.0f / res;
    double sum = 0, lit_min = 1;
    int count = 0;
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        const float d = square_distance(pixel_to_world(x, n, 0, 2), pixel_to_world(y, n, 0, 2), 0);
        if (d < -4 * texel) sum += vis.at(x, y), ++count;
        if (d > 4 * texel) lit_min = std::min(lit_min, static_cast<double>(vis.at(x, y)));
      }
    ASSERT_GT(count, n * n / 8);
    umbra[i] = static_cast<float>(sum / count);
    const double expected = std::exp(-exponents[i] * gap);
    std::printf("ESM c = %.0f: umbra visibility %.6f, exp(-c gap) %.6f (gap %.4f)\n", exponents[i], umbra[i], expected, gap);
    EXPECT_NEAR(umbra[i], expected, 0.1 * expected + 1e-6) << "c = " << exponents[i];
    EXPECT_GT(gap, 0.1) << "the plate must sit well apart from the ground in normalized depth";
    EXPECT_GE(lit_min, 1.0 - 1e-4) << "c = " << exponents[i];
  }
  EXPECT_LT(umbra[1], 0.2 * umbra[0]);
  EXPECT_LT(umbra[2], 1e-6f);
}

TEST(Esm, CloseToBoxPcfAcrossALargeGapAndDarkerOnlyBySelfShadowing) {
  // exp(-c (d - z)) >= [d <= z] for every occluder sample, so the clamped mean is never below the
  // box PCF of the same radius, but for the receiver's own depth: ESM has no depth bias, and where
  // the receiver's depth d exceeds the map's rasterized depth of the same surface by e, it reads
  // exp(-c e) instead of 1 (measured: 0.0057 at most here, c = 77). With a large depth gap (two
  // planes) ESM and box PCF agree.
  scene::Scene s = scene::make_two_planes_scene(3, 10, 1);
  look_down(s, {0, 0}, 0.5f);
  const int n = 200, res = 512;
  const float radius = 4;
  ShadowSettings pcf = settings(Technique::pcf, res, true);
  pcf.pcf.kernel = Kernel::grid;
  pcf.pcf.radius = radius;
  const io::ImageF reference = render_visibility(s, pcf, n);
  const io::ImageF vis = render_visibility(s, esm_settings(res, true, radius, 77), n);
  ASSERT_TRUE(test::all_finite_in(vis, 0, 1));
  float worst = 0, darker = 0;
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      worst = std::max(worst, std::abs(vis.at(x, y) - reference.at(x, y)));
      darker = std::max(darker, reference.at(x, y) - vis.at(x, y));
    }
  std::printf("ESM: largest |visibility - box PCF| %.4f, largest amount darker %.5f\n", worst, darker);
  EXPECT_LT(worst, 0.05f);
  EXPECT_LT(darker, 0.01f);
}

// ---- the moments blur's work: bounded by the map, whatever the radius ----------------------------

// Texels the blur fetches for a size² map at a filter of `radius_texels` (the radius the frame
// would give, cut to the map by moments_blur_radius_texels), counted by the shader itself.
unsigned blur_fetches(const shadows::MomentsLayout& layout, int size, float radius_texels) {
  static const gl::ShaderLibrary library;
  const gl::Program blur = library.program({{GL_COMPUTE_SHADER, "vsm_blur.comp"}}, shadows::moments_blur_defines(layout, true));
  const GLenum format = shadows::moments_gl_format(layout.format);
  const gl::Texture moments({format, size, size, 1}, "blur work: moments"), scratch({format, size, size, 1}, "blur work: scratch");
  const float zero[4] = {0, 0, 0, 0};
  glClearTexImage(moments.id(), 0, GL_RGBA, GL_FLOAT, zero);
  const unsigned start = 0;
  const gl::Buffer counter(sizeof(unsigned), &start, GL_DYNAMIC_STORAGE_BIT);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, shadows::kBlurFetchCounterBinding, counter.id());
  shadows::blur_moments_region(blur, layout, moments, scratch, {0, 0}, size, shadows::moments_blur_radius_texels(radius_texels, size));
  glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
  unsigned fetches = 0;
  glGetNamedBufferSubData(counter.id(), 0, sizeof(unsigned), &fetches);
  return fetches;
}

// Issue 27: ESM and EVSM at r = 1e6 texels took 30 s and 23 s (VSM 1 s) when each texel summed its
// window anew. The work is asserted, not the seconds: at any radius the blur fetches at most a few
// map widths per line (sliding sums: the first window, cut to the map, then four texels a step;
// direct sums: each work group sums its line once in chunks, and a window adds the partial chunks
// at its ends and four edge texels).
TEST(MomentsBlur, AWindowWiderThanTheMapFetchesNoMoreThanTheMapBounds) {
  const int size = 512;
  const double texels = 2.0 * size * size;  // both axes
  const int chunk = (size + 255) / 256;     // CHUNKS in vsm_blur.comp
  struct Case {
    const char* name;
    shadows::MomentsLayout layout;
    double bound_per_texel;
  };
  const Case cases[] = {
      {"vsm (sliding sums)", {shadows::MomentsFormat::rg32f, {}, false}, (2.0 * size + 1 + 4.0 * size) / size},
      {"esm (direct sums)", {shadows::MomentsFormat::r32f, {}, true}, size / 64.0 + 2.0 * chunk + 4},
      {"evsm (direct sums)", {shadows::MomentsFormat::rgba32f, {}, true}, size / 64.0 + 2.0 * chunk + 4},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    const unsigned narrow = blur_fetches(c.layout, size, 4);
    const unsigned wide = blur_fetches(c.layout, size, 1e6f);
    std::printf("%s: texel fetches per texel and axis at r = 4: %.2f, at r = 1e6: %.2f (bound %.2f)\n", c.name, narrow / texels,
                wide / texels, c.bound_per_texel);
    EXPECT_GT(narrow, 0u) << "the counter counts";
    EXPECT_LE(wide / texels, c.bound_per_texel);
  }
}

}  // namespace
}  // namespace penumbra
