// Stimulus pixels against an independent CPU computation: the shadow map from the texel-centre
// rule in double precision, and the disk/box integrals by Gauss–Legendre quadrature over the
// kernel's height (split at every texel row, where the integrand jumps), not by the closed forms
// the shader uses.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <numbers>

#include "gl_test_env.h"
#include "observers/image_observer.h"
#include "sampling/poisson_disk.h"
#include "shadows/renderer.h"
#include "stimuli/stimulus.h"

namespace {

using namespace penumbra;
using stimuli::Geometry;
using stimuli::StimulusSpec;

constexpr double kGaussX[8] = {-0.9602898564975363, -0.7966664774136267, -0.5255324099163290, -0.1834346424956498,
                               0.1834346424956498,  0.5255324099163290,  0.7966664774136267,  0.9602898564975363};
constexpr double kGaussW[8] = {0.1012285362903763, 0.2223810344533745, 0.3137066458778873, 0.3626837833783620,
                               0.3626837833783620, 0.3137066458778873, 0.2223810344533745, 0.1012285362903763};

// Integral of f over [lo, hi], split at the sorted breaks, each piece subdivided 8 times.
double integrate(const std::function<double(double)>& f, double lo, double hi, std::vector<double> breaks) {
  breaks.push_back(lo);
  breaks.push_back(hi);
  std::sort(breaks.begin(), breaks.end());
  double sum = 0;
  for (std::size_t k = 0; k + 1 < breaks.size(); ++k) {
    const double a = std::max(lo, breaks[k]), b = std::min(hi, breaks[k + 1]);
    if (!(b > a)) continue;
    constexpr int sub = 8;
    for (int s = 0; s < sub; ++s) {
      const double s0 = a + (b - a) * s / sub, s1 = a + (b - a) * (s + 1) / sub;
      for (int g = 0; g < 8; ++g) sum += 0.5 * (s1 - s0) * kGaussW[g] * f(0.5 * (s0 + s1) + 0.5 * (s1 - s0) * kGaussX[g]);
    }
  }
  return sum;
}

struct Reference {
  const StimulusSpec& spec;
  const Geometry& g;
  std::vector<glm::vec2> taps = sampling::poisson_disk(spec.poisson_taps);
  double a() const { return spec.artifact_px; }
  // When set, the rasterized map (canonical rows) stands in for the texel-centre rule.
  const std::vector<std::uint8_t>* rasterized = nullptr;
  // Texel-centre rule: a texel is occluded when its centre lies below the edge.
  bool texel_lit(long i, long j) const {
    if (i < 0 || j < 0 || i >= g.map_texels || j >= g.map_texels) return true;
    if (rasterized) return (*rasterized)[static_cast<std::size_t>(j) * g.map_texels + i] != 0;
    return centre_above_edge_texels(i, j) >= 0;
  }
  // Vertical distance of texel (i, j)'s centre above the edge, in texels.
  double centre_above_edge_texels(long i, long j) const {
    const double cx = g.map_origin_px.x + (i + 0.5) * a(), cy = g.map_origin_px.y + (j + 0.5) * a();
    return (cy - (g.line_m * cx + g.line_b)) / a();
  }
  // Lit length of the segment [x0, x1] (canonical) at height y, from the shadow map or the edge.
  double lit_length(double x0, double x1, double y, bool from_map) const {
    if (!(x1 > x0)) return 0;
    if (!from_map) {
      const double x_edge = (y - g.line_b) / g.line_m;  // lit for x <= x_edge (m > 0)
      return std::clamp(x_edge - x0, 0.0, x1 - x0);
    }
    const long j = static_cast<long>(std::floor((y - g.map_origin_px.y) / a()));
    const long i0 = static_cast<long>(std::floor((x0 - g.map_origin_px.x) / a()));
    const long i1 = static_cast<long>(std::floor((x1 - g.map_origin_px.x) / a()));
    double len = 0;
    for (long i = i0; i <= i1; ++i) {
      if (!texel_lit(i, j)) continue;
      const double t0 = g.map_origin_px.x + i * a(), t1 = t0 + a();
      len += std::max(0.0, std::min(x1, t1) - std::max(x0, t0));
    }
    return len;
  }
  double visibility(glm::dvec2 q, bool from_map) const {
    const double r = spec.filter_radius_px;
    if (spec.kernel == stimuli::Kernel::poisson) {
      double sum = 0;
      for (auto t : taps) {
        const double c = std::cos(g.poisson_rotation), s = std::sin(g.poisson_rotation);
        const glm::dvec2 p = q + r * glm::dvec2(c * t.x - s * t.y, s * t.x + c * t.y);
        sum += lit_length(p.x - 1e-9, p.x + 1e-9, p.y, from_map) > 0 ? 1 : 0;
      }
      return sum / static_cast<double>(taps.size());
    }
    std::vector<double> breaks;  // texel rows (the integrand jumps there)
    const double first = std::floor((q.y - r - g.map_origin_px.y) / a());
    for (double k = first; g.map_origin_px.y + k * a() <= q.y + r; k += 1) breaks.push_back(g.map_origin_px.y + k * a());
    if (spec.kernel == stimuli::Kernel::grid) {
      const double area = integrate([&](double y) { return lit_length(q.x - r, q.x + r, y, from_map); }, q.y - r,
                                    q.y + r, breaks);
      return area / (4 * r * r);
    }
    // Disk: y = q.y + r sin(theta), chord half-width r cos(theta).
    std::vector<double> theta_breaks;
    for (double y : breaks) {
      const double s = (y - q.y) / r;
      if (s > -1 && s < 1) theta_breaks.push_back(std::asin(s));
    }
    const double area = integrate(
        [&](double t) {
          const double half = r * std::cos(t);
          return lit_length(q.x - half, q.x + half, q.y + r * std::sin(t), from_map) * r * std::cos(t);
        },
        -std::numbers::pi / 2, std::numbers::pi / 2, theta_breaks);
    return area / (std::numbers::pi * r * r);
  }
};

// Stimuli drawn by the renderer's own PCF (renderer/shaders/shadow_pcf.glsl) through the stimulus
// scene, against the independent computation above. Disk and grid: the kernel's area integral
// over the map and over the edge. Poisson (the renderer's disk, unrotated): each tap is the hardware's
// 2x2 comparison, computed here as the bilinear weights of the four texel centres around it; the
// partner tests each tap against the edge.
struct TechniqueCase {
  stimuli::Pattern pattern;
  double artifact_px, radius_px, lit;
  std::string kernel;
  std::uint64_t seed;
  int size_px = 96;
};

void PrintTo(const TechniqueCase& c, std::ostream* os) { *os << c.kernel << " a=" << c.artifact_px << " r=" << c.radius_px; }

class RendererStimulusPixels : public ::testing::TestWithParam<TechniqueCase> {};

TEST_P(RendererStimulusPixels, MatchIndependentFilteredEdgeWithinOneLevel) {
  const TechniqueCase c = GetParam();
  StimulusSpec spec;
  spec.pattern = c.pattern;
  spec.artifact_px = c.artifact_px;
  spec.filter_radius_px = c.radius_px;
  spec.lit_linear = c.lit;
  spec.kernel = stimuli::parse_kernel(c.kernel);  // the reference's kernel (disk, grid)
  spec.size_px = c.size_px;
  spec.seed = c.seed;
  spec.technique = "pcf";
  spec.technique_settings = {{"pcf.kernel", c.kernel}, {"pcf.poisson_taps", "24"}};
  stimuli::StimulusRenderer renderer;
  const auto pair = renderer.render(spec);
  const Geometry& g = pair.geometry;
  Reference ref{spec, g, {}};

  // The rasterized map is the texel-centre rule, except where a centre lies closer to the edge
  // than the rasterizer's sub-pixel precision resolves (GL snaps vertices to 1/256 of a texel or
  // finer; the step's crossing texel can be that close). The filters are then checked on the
  // map as rasterized.
  const auto& map = renderer.last_shadow_map();
  int map_mismatch = 0;
  for (int j = 0; j < g.map_texels; ++j)
    for (int i = 0; i < g.map_texels; ++i)
      map_mismatch += map[j * g.map_texels + i] != (ref.texel_lit(i, j) ? 1 : 0) && std::abs(ref.centre_above_edge_texels(i, j)) > 1.0 / 256;
  EXPECT_EQ(map_mismatch, 0);
  ref.rasterized = &map;

  const bool poisson = c.kernel == "poisson";
  std::vector<glm::dvec2> taps;  // canonical offsets
  for (const glm::vec2 t : sampling::poisson_disk(24)) taps.push_back(g.to_canonical * (c.radius_px * glm::dvec2(t)));
  // Hardware PCF of one tap at canonical q: bilinear weights of the texel centres around it.
  const auto bilinear = [&](glm::dvec2 q) {
    const glm::dvec2 t = (q - g.map_origin_px) / spec.artifact_px - 0.5;
    const glm::dvec2 f = t - glm::floor(t);
    const long i = static_cast<long>(std::floor(t.x)), j = static_cast<long>(std::floor(t.y));
    return (1 - f.x) * (1 - f.y) * ref.texel_lit(i, j) + f.x * (1 - f.y) * ref.texel_lit(i + 1, j) +
           (1 - f.x) * f.y * ref.texel_lit(i, j + 1) + f.x * f.y * ref.texel_lit(i + 1, j + 1);
  };
  const int n = spec.size_px;
  int worst = 0, artifact_differs = 0;
  for (int y = 0; y < n; ++y) {
    for (int x = 0; x < n; ++x) {
      const glm::dvec2 q = g.to_canonical * glm::dvec2(x + 0.5 - 0.5 * n, (n - 1 - y) + 0.5 - 0.5 * n);
      for (int from_map = 0; from_map < 2; ++from_map) {
        double v = 0;
        if (!poisson) {
          v = ref.visibility(q, from_map == 1);
        } else {
          for (const glm::dvec2 t : taps)
            v += from_map ? bilinear(q + t) : ((q + t).y >= g.line_m * (q + t).x + g.line_b ? 1.0 : 0.0);
          v /= static_cast<double>(taps.size());
        }
        const int expected = stimuli::encode(c.lit * v, spec.transfer);
        const int got = from_map ? pair.artifact.at(x, y) : pair.line.at(x, y);
        const int diff = std::abs(expected - got);
        worst = std::max(worst, diff);
        if (diff > 1) ADD_FAILURE() << (from_map ? "artifact" : "line") << " pixel (" << x << ", " << y << "): got "
                                    << got << ", expected " << expected << " (visibility " << v << ")";
      }
      artifact_differs += pair.artifact.at(x, y) != pair.line.at(x, y);
    }
  }
  EXPECT_LE(worst, 1);
  EXPECT_GT(artifact_differs, 20);
  const auto [lo, hi] = std::minmax_element(pair.line.pixels.begin(), pair.line.pixels.end());
  EXPECT_EQ(*lo, 0);
  EXPECT_EQ(*hi, stimuli::encode(c.lit, spec.transfer));
}

INSTANTIATE_TEST_SUITE_P(
    Pcf, RendererStimulusPixels,
    ::testing::Values(TechniqueCase{stimuli::Pattern::stair, 10, 4, 1.0, "disk", 1},
                      TechniqueCase{stimuli::Pattern::stair, 10, 17, 1.0, "disk", 2},
                      TechniqueCase{stimuli::Pattern::step, 10, 4, 1.0, "disk", 3},
                      TechniqueCase{stimuli::Pattern::step, 20, 17, 0.5, "disk", 4},
                      TechniqueCase{stimuli::Pattern::stair, 5, 30, 1.0, "disk", 5, 128},
                      TechniqueCase{stimuli::Pattern::stair, 10, 4, 1.0, "grid", 11},
                      TechniqueCase{stimuli::Pattern::stair, 5, 6, 0.5, "grid", 12},
                      TechniqueCase{stimuli::Pattern::step, 10, 17, 1.0, "grid", 13},
                      TechniqueCase{stimuli::Pattern::step, 20, 7.5, 0.5, "grid", 14, 160},
                      TechniqueCase{stimuli::Pattern::stair, 10, 6, 1.0, "poisson", 15},
                      TechniqueCase{stimuli::Pattern::step, 10, 12, 0.5, "poisson", 16}),
    [](const ::testing::TestParamInfo<TechniqueCase>& p) { return std::to_string(p.index) + "_" + p.param.kernel; });

// What the study sets itself and what a config may set, by penumbra-render's keys.
// A spec without a technique (the earlier configs' stimulus.kernel) is drawn by the renderer's
// PCF with that kernel: the same bytes as the spec that names it.
TEST(StimulusSpec, WithoutATechniqueIsTheRenderersPcfWithItsKernel) {
  stimuli::StimulusRenderer renderer;
  for (const stimuli::Kernel kernel : {stimuli::Kernel::disk, stimuli::Kernel::grid, stimuli::Kernel::poisson}) {
    StimulusSpec legacy;
    legacy.pattern = stimuli::Pattern::stair;
    legacy.artifact_px = 8;
    legacy.filter_radius_px = 11;
    legacy.size_px = 64;
    legacy.seed = 21;
    legacy.kernel = kernel;
    legacy.poisson_taps = 20;
    StimulusSpec named = legacy;
    named.technique = "pcf";
    named.technique_settings = {{"pcf.kernel", stimuli::to_string(kernel)}};
    if (kernel == stimuli::Kernel::poisson) named.technique_settings.emplace_back("pcf.poisson_taps", "20");
    EXPECT_EQ(stimuli::as_renderer_pcf(legacy).technique_settings, named.technique_settings);
    const auto a = renderer.render(legacy), b = renderer.render(named);
    EXPECT_EQ(a.artifact.pixels, b.artifact.pixels) << stimuli::to_string(kernel);
    EXPECT_EQ(a.line.pixels, b.line.pixels) << stimuli::to_string(kernel);
    EXPECT_NE(a.artifact.pixels, a.line.pixels) << stimuli::to_string(kernel);
  }
}

TEST(StimulusSettings, TrialRadiusBecomesTexelsAndTheStudyOwnsTheMap) {
  StimulusSpec spec;
  spec.artifact_px = 8;
  spec.filter_radius_px = 20;
  spec.technique = "pcf";
  spec.technique_settings = {{"pcf.kernel", "poisson"}, {"pcf.poisson_taps", "40"}, {"map.depth_bias_texels", "0.25"}};
  const shadows::ShadowSettings s = stimuli::stimulus_settings(spec, 61);
  EXPECT_EQ(s.technique, shadows::Technique::pcf);
  EXPECT_FLOAT_EQ(s.pcf.radius, 2.5f);
  EXPECT_EQ(s.pcf.radius_unit, shadows::RadiusUnit::texels);
  EXPECT_EQ(s.pcf.kernel, shadows::Kernel::poisson);
  EXPECT_EQ(s.pcf.poisson_taps, 40);
  EXPECT_FALSE(s.pcf.rotate);
  EXPECT_FLOAT_EQ(s.map.depth_bias_texels, 0.25f);
  EXPECT_EQ(s.map.resolution_texels, 61);
  EXPECT_FALSE(s.map.fit);
  EXPECT_EQ(s.map.cascades, 1);
  EXPECT_FALSE(s.adaptive.enabled);
  EXPECT_EQ(stimuli::partner_unavailable(s), "");

  // Every filter-radius technique can be set up, and has a partner.
  spec.technique_settings.clear();
  for (const auto& [t, partner] : std::vector<std::pair<std::string, stimuli::PartnerMethod>>{
           {"rpcf", stimuli::PartnerMethod::box_integral}, {"vsm", stimuli::PartnerMethod::fine_map}, {"msm", stimuli::PartnerMethod::fine_map},
           {"evsm", stimuli::PartnerMethod::fine_map}, {"esm", stimuli::PartnerMethod::fine_map}}) {
    spec.technique = t;
    EXPECT_EQ(stimuli::partner_for(stimuli::stimulus_settings(spec, 61)), partner) << t;
  }
  spec.technique = "pcf";
  spec.technique_settings = {{"pcf.kernel", "grid"}};
  EXPECT_EQ(stimuli::partner_for(stimuli::stimulus_settings(spec, 61)), stimuli::PartnerMethod::box_integral);
  // The partner's finer map: a sixteenth of the artifact or of the radius, capped.
  stimuli::Geometry g;
  g.map_texels = 41;
  spec.artifact_px = 8;
  spec.filter_radius_px = 20;
  EXPECT_EQ(stimuli::fine_map_texels(spec, g), 41 * 64);
  spec.filter_radius_px = 6;
  EXPECT_EQ(stimuli::fine_map_texels(spec, g), 3499);  // ceil(328 px / (6 / 64) px)
  spec.filter_radius_px = 0.5;  // shown as 1 px
  EXPECT_EQ(stimuli::fine_map_texels(spec, g), stimuli::kMaxFineMapTexels);
  spec.artifact_px = 8;
  spec.filter_radius_px = 20;

  const auto refused = [&](const std::string& technique, std::vector<std::pair<std::string, std::string>> settings,
                           const std::string& expected) {
    spec.technique = technique;
    spec.technique_settings = std::move(settings);
    try {
      stimuli::stimulus_settings(spec, 61);
      ADD_FAILURE() << "accepted: " << expected;
    } catch (const std::invalid_argument& e) {
      EXPECT_EQ(std::string(e.what()).rfind(expected, 0), 0u) << e.what();
    }
  };
  refused("pfc", {}, "technique: ");
  refused("pcss", {}, "technique: 'pcss' has no fixed filter radius");
  refused("pcf", {{"pcf.radius", "3"}}, "pcf.radius: set by the study");
  refused("pcf", {{"map.resolution_texels", "512"}}, "map.resolution_texels: set by the study");
  refused("pcf", {{"adaptive.enabled", "true"}}, "adaptive.enabled: not a setting of technique 'pcf'");
  refused("pcf", {{"vsm.radius", "1"}}, "vsm.radius: not a setting of technique 'pcf'");
  refused("pcf", {{"pcf.kernal", "grid"}}, "pcf.kernal: no such setting");
  refused("pcf", {{"pcf.kernel", "cone"}}, "pcf.kernel: ");
  refused("pcf", {{"kernel", "grid"}}, "kernel: expected section.key");
  spec.technique = "pcf";
  spec.technique_settings = {{"pcf.kernel", "poisson"}, {"pcf.rotate", "true"}};
  EXPECT_EQ(stimuli::partner_unavailable(stimuli::stimulus_settings(spec, 61)).rfind("pcf.rotate: ", 0), 0u);
}

// The techniques whose partner is not checked pixel by pixel above. RPCF's partner is the box
// integral of the edge (revectorizing a straight edge gives it back): RPCF itself on a map 16
// times finer agrees with it within one level (for radii of at least ~0.8 trial texels: at
// a = 10, r = 4 px it departs by 1.4 levels at 16 times finer and 3.6 at 32: revectorizing the fine
// map's own one-texel steps is not the identity there), and on the trial's map its staircase stays. The
// filtered-moments techniques' partner is themselves on the fine map: a map twice as fine again
// changes no pixel by more than one level (the fine map's own staircase is below it), while the
// trial's map differs.
struct PartnerCase {
  std::string technique;
  stimuli::Pattern pattern;
  double artifact_px, radius_px;
};
void PrintTo(const PartnerCase& c, std::ostream* os) { *os << c.technique << " a=" << c.artifact_px << " r=" << c.radius_px; }

class RendererStimulusPartner : public ::testing::TestWithParam<PartnerCase> {};

TEST_P(RendererStimulusPartner, IsTheTechniqueOnAFinerMap) {
  const PartnerCase c = GetParam();
  StimulusSpec spec;
  spec.pattern = c.pattern;
  spec.artifact_px = c.artifact_px;
  spec.filter_radius_px = c.radius_px;
  spec.size_px = 96;
  spec.seed = 21;
  spec.technique = c.technique;
  stimuli::StimulusRenderer stimulus;
  const auto pair = stimulus.render(spec);
  const Geometry& g = pair.geometry;
  const double extent = spec.artifact_px * g.map_texels;
  const int finer = c.technique == "rpcf" ? g.map_texels * 16 : 2 * stimuli::fine_map_texels(spec, g);
  shadows::Renderer renderer;
  renderer.set_scene(stimuli::stimulus_scene(spec, g));
  renderer.render(stimuli::stimulus_settings(spec, finer, extent / finer), spec.size_px, spec.size_px);
  const io::ImageF check = renderer.read_visibility();
  // In linear light: one 8-bit level is 1/255 of visibility. (Display-encoded, near black, a
  // level is 13 times finer: the sRGB difference is reported, not bounded.)
  double worst = 0;
  int worst_encoded = 0, artifact_differs = 0;
  for (int y = 0; y < spec.size_px; ++y) {
    for (int x = 0; x < spec.size_px; ++x) {
      worst = std::max(worst, static_cast<double>(std::abs(check.at(x, y) - pair.line_visibility.at(x, y))));
      worst_encoded = std::max(worst_encoded, std::abs(stimuli::encode(check.at(x, y), spec.transfer) - pair.line.at(x, y)));
      artifact_differs += std::abs(pair.artifact_visibility.at(x, y) - pair.line_visibility.at(x, y)) > 1.0 / 255;
    }
  }
  EXPECT_LE(worst, 1.0 / 255) << "sRGB levels: " << worst_encoded;
  EXPECT_GT(artifact_differs, 20);
  RecordProperty("worst_linear_levels", std::to_string(worst * 255));
  RecordProperty("worst_srgb_levels", std::to_string(worst_encoded));
  std::printf("partner %s a=%g r=%g: map %d -> %d texels: worst %.3f linear levels, %d sRGB levels\n", c.technique.c_str(),
              c.artifact_px, c.radius_px, c.technique == "rpcf" ? g.map_texels : stimuli::fine_map_texels(spec, g), finer,
              worst * 255, worst_encoded);
}

INSTANTIATE_TEST_SUITE_P(
    Techniques, RendererStimulusPartner,
    ::testing::Values(PartnerCase{"rpcf", stimuli::Pattern::stair, 10, 8}, PartnerCase{"rpcf", stimuli::Pattern::step, 10, 12},
                      PartnerCase{"vsm", stimuli::Pattern::stair, 10, 6}, PartnerCase{"vsm", stimuli::Pattern::step, 20, 12},
                      PartnerCase{"msm", stimuli::Pattern::stair, 10, 12}, PartnerCase{"evsm", stimuli::Pattern::stair, 10, 12},
                      PartnerCase{"esm", stimuli::Pattern::step, 10, 12}),
    [](const ::testing::TestParamInfo<PartnerCase>& p) { return std::to_string(p.index) + "_" + p.param.technique; });

TEST(StimulusGeometry, StepCrossesExactlyOneTexelRowAndOrientationsVary) {
  std::set<int> orientations;
  for (std::uint64_t seed = 1; seed <= 40; ++seed) {
    StimulusSpec spec;
    spec.pattern = stimuli::Pattern::step;
    spec.seed = seed;
    const Geometry g = stimuli::make_geometry(spec);
    orientations.insert(g.orientation);
    // Texel-centre rows crossed by the edge inside the stimulus: exactly one.
    const double half = 0.5 * spec.size_px;
    const double y_left = g.line_m * -half + g.line_b, y_right = g.line_m * half + g.line_b;
    int crossed = 0;
    for (int j = 0; j < g.map_texels; ++j) {
      const double cy = g.map_origin_px.y + (j + 0.5) * spec.artifact_px;
      crossed += (cy - y_left) * (cy - y_right) < 0;
    }
    EXPECT_EQ(crossed, 1) << "seed " << seed;
  }
  EXPECT_EQ(orientations.size(), 8u);
}

TEST(StimulusDisplay, TransferFunctionsAndRadiusClamp) {
  EXPECT_EQ(stimuli::encode(0.5, stimuli::Transfer::srgb), 188);  // 50 % linear light is sRGB 188
  EXPECT_EQ(stimuli::encode(0.5, stimuli::Transfer::gamma22), 186);
  EXPECT_EQ(stimuli::encode(0.5, stimuli::Transfer::linear), 128);
  for (int v = 0; v < 256; ++v)
    for (auto t : {stimuli::Transfer::srgb, stimuli::Transfer::gamma22, stimuli::Transfer::linear})
      EXPECT_EQ(stimuli::encode(stimuli::decode(static_cast<std::uint8_t>(v), t), t), v);
  EXPECT_EQ(stimuli::clamp_filter_radius(0.3, 320).filter_radius_px, 1.0);
  EXPECT_TRUE(stimuli::clamp_filter_radius(0.3, 320).clamped);
  EXPECT_EQ(stimuli::clamp_filter_radius(500, 320).filter_radius_px, 160.0);
  EXPECT_FALSE(stimuli::clamp_filter_radius(20, 320).clamped);
}

TEST(ImageObserver, SeesTheStaircaseAtSmallRadiiAndNotAtLargeOnes) {
  stimuli::StimulusRenderer renderer;
  observers::ImageObserver eye({0.02, 0.0, 60.0}, 11);
  auto residual_gap = [&](double ratio) {
    StimulusSpec spec;
    spec.artifact_px = 10;
    spec.filter_radius_px = ratio * spec.artifact_px;
    spec.size_px = 160;
    spec.seed = 9;
    const auto pair = renderer.render(spec);
    return eye.straightness_residual(pair.artifact, spec, pair.geometry, false) -
           eye.straightness_residual(pair.line, spec, pair.geometry, false);
  };
  const double sharp = residual_gap(0.5), soft = residual_gap(6.0);
  EXPECT_GT(sharp, 10.0);        // luminance^2 summed over the edge band
  EXPECT_LT(soft, 0.01 * sharp);  // 6 texels of disk PCF hide almost all of it
  EXPECT_GE(soft, -1e-3);
  // With noise, at r = a/2 it picks the jagged one nearly always.
  StimulusSpec spec;
  spec.filter_radius_px = 5;
  spec.size_px = 160;
  const auto pair = renderer.render(spec);
  int right = 0;
  for (int i = 0; i < 20; ++i) right += eye.first_is_jagged(pair.artifact, pair.line, spec, pair.geometry);
  EXPECT_GE(right, 19);
}

// The local criterion: a step is seen by its bend while the filter is small, hidden once it is
// several texels wide (the global fit still sees the sub-texel shift there); the relative
// deviation depends on r / a only, so thresholds scale with a.
TEST(ImageObserver, LocalCriterionHidesTheStepAtLargeRadiiAndScalesWithTheArtifact) {
  stimuli::StimulusRenderer renderer;
  observers::ImageObserver eye({}, 3);
  auto deviation = [&](stimuli::Pattern pattern, double a, double ratio, bool jagged) {
    StimulusSpec spec;
    spec.pattern = pattern;
    spec.artifact_px = a;
    spec.filter_radius_px = ratio * a;
    spec.seed = 21;
    const auto pair = renderer.render(spec);
    return eye.local_deviation(jagged ? pair.artifact : pair.line, spec, pair.geometry, false);
  };
  const double weber = observers::ImageObserverParams{}.weber;
  for (double a : {5.0, 20.0}) {
    SCOPED_TRACE(a);
    EXPECT_GT(deviation(stimuli::Pattern::step, a, 1.5, true), 2 * weber);
    EXPECT_LT(deviation(stimuli::Pattern::step, a, 6.0, true), weber);
    EXPECT_GT(deviation(stimuli::Pattern::stair, a, 1.0, true), 2 * weber);
    EXPECT_LT(deviation(stimuli::Pattern::stair, a, 6.0, true), 0.2 * weber);
    EXPECT_LT(deviation(stimuli::Pattern::step, a, 1.5, false), 0.5 * weber);  // the straight partner: 8-bit steps only
  }
  // Scale invariance: a = 5 and a = 20 at the same r / a differ by little.
  const double d5 = deviation(stimuli::Pattern::step, 5, 3, true), d20 = deviation(stimuli::Pattern::step, 20, 3, true);
  EXPECT_NEAR(d5 / d20, 1.0, 0.2);
  // The global criterion still separates the step at r = 6 a (what people do not see).
  StimulusSpec spec;
  spec.pattern = stimuli::Pattern::step;
  spec.filter_radius_px = 60;
  const auto pair = renderer.render(spec);
  observers::ImageObserver global({0.0, 0.0, 60.0, observers::StraightnessCriterion::global}, 3);
  EXPECT_GT(global.straightness_residual(pair.artifact, spec, pair.geometry, false),
            20 * global.straightness_residual(pair.line, spec, pair.geometry, false) + 1e-3);
}

// yes/no: "jagged" for a visible staircase, the false-alarm rate for straight edges.
TEST(ImageObserver, YesNoAnswersFollowTheCriterion) {
  stimuli::StimulusRenderer renderer;
  StimulusSpec spec;
  spec.filter_radius_px = 5;  // a = 10: plainly jagged
  spec.size_px = 96;
  const auto sharp = renderer.render(spec);
  observers::ImageObserverParams params;
  params.false_alarm = 0.1;
  observers::ImageObserver eye(params, 5);
  int hits = 0, false_alarms = 0;
  constexpr int n = 300;
  for (int i = 0; i < n; ++i) {
    hits += eye.judges_jagged(sharp.artifact, spec, sharp.geometry);
    false_alarms += eye.judges_jagged(sharp.line, spec, sharp.geometry);
  }
  EXPECT_EQ(hits, n);
  EXPECT_NEAR(false_alarms / double(n), 0.1, 0.05);  // binomial sd 0.017
  observers::ImageObserver global({0.02, 0.0, 60.0, observers::StraightnessCriterion::global}, 5);
  EXPECT_THROW(global.judges_jagged(sharp.line, spec, sharp.geometry), std::invalid_argument);
}

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ::testing::AddGlobalTestEnvironment(new penumbra::test::GlEnvironment);
  return RUN_ALL_TESTS();
}
