// The reference filter size: the OpenCV comparison, the staircase's mean line, and the search's
// contract (identical within the tolerance at the result, different just below it).
#include <gtest/gtest.h>

#include <cmath>

#include "gl_test_env.h"
#include "stimuli/reference.h"
#include "stimuli/stimulus.h"

namespace {

using namespace penumbra;

TEST(Reference, CompareCountsPixelsAndLevels) {
  io::Image8 a{4, 3, 1, std::vector<std::uint8_t>(12, 100)};
  io::Image8 b = a;
  EXPECT_EQ(stimuli::compare(a, b).differing_pixels, 0);
  b.at(2, 1) = 103;
  b.at(0, 0) = 99;
  const stimuli::ImageDifference d = stimuli::compare(a, b);
  EXPECT_EQ(d.differing_pixels, 2);
  EXPECT_EQ(d.max_abs_levels, 3);
  io::Image8 c{3, 3, 1, std::vector<std::uint8_t>(9, 0)};
  EXPECT_THROW(stimuli::compare(a, c), std::invalid_argument);
}

// The mean line classifies every texel centre as the original line does (same staircase), and
// lies half a texel's worth of area-balance inside each column: the staircase top minus the line
// integrates to zero over every column.
TEST(Reference, StairMeanLineKeepsTheStaircaseAndBalancesIt) {
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    stimuli::StimulusSpec spec;
    spec.artifact_px = 7;
    spec.filter_radius_px = 20;
    spec.seed = seed;
    const stimuli::Geometry g = stimuli::make_geometry(spec);
    const double a = spec.artifact_px;
    const double b_mean = stimuli::stair_mean_line_b(g, a);
    EXPECT_LE(std::abs(b_mean - g.line_b), 0.5 * a + 1e-9) << seed;
    for (int i = 0; i < g.map_texels; ++i) {
      const double x = g.map_origin_px.x + (i + 0.5) * a;
      int top = -1;  // highest occluded row of column i
      for (int j = 0; j < g.map_texels; ++j) {
        const double y = g.map_origin_px.y + (j + 0.5) * a;
        ASSERT_EQ(y < x + g.line_b, y < x + b_mean) << "seed " << seed << " texel " << i << "," << j;
        if (y < x + g.line_b) top = j;
      }
      if (top < 0 || top + 1 >= g.map_texels) continue;  // column fully lit or fully occluded in the map
      const double staircase_top = g.map_origin_px.y + (top + 1) * a;
      EXPECT_NEAR(staircase_top, x + b_mean, 1e-9) << "seed " << seed << " column " << i;
    }
  }
}

TEST(Reference, ResultIsIdenticalThereAndDiffersJustBelow) {
  stimuli::StimulusRenderer renderer;
  stimuli::StimulusSpec spec;
  spec.pattern = stimuli::Pattern::stair;
  spec.artifact_px = 2;
  spec.lit_linear = 0.5;
  spec.size_px = 64;
  stimuli::ReferenceSearch search;
  search.partner = stimuli::Partner::mean_line;
  search.tolerance_levels = 1;
  search.resolution_px = 0.25;
  search.seeds = {3};
  const stimuli::Reference ref = stimuli::find_reference(renderer, spec, search);
  ASSERT_EQ(ref.seeds.size(), 1u);
  ASSERT_TRUE(ref.reference_px.has_value()) << "a 2 px stair at half contrast hides within r <= 32 px (1 level)";
  const double r = *ref.reference_px;
  EXPECT_GT(r, 10.0);  // well above the perceptual r = 3.47 a ~ 7 px
  EXPECT_LE(r, 32.0);
  auto max_levels = [&](double radius) {
    stimuli::StimulusSpec s = spec;
    s.seed = 3;
    s.filter_radius_px = radius;
    stimuli::Geometry g = stimuli::make_geometry(s);
    g.line_b = stimuli::stair_mean_line_b(g, s.artifact_px);
    const stimuli::StimulusPair pair = renderer.render(s, g);
    return stimuli::compare(pair.artifact, pair.line).max_abs_levels;
  };
  EXPECT_LE(max_levels(r), 1);
  EXPECT_GT(max_levels(ref.seeds[0].bracket_below_px), 1);
  EXPECT_LE(r - ref.seeds[0].bracket_below_px, 0.25 + 1e-12);
}

// The thesis's partner (sec. 4.4): the edge drawn at 1 px (through the stair's mean) and filtered
// the same way, on linear 8-bit intensities and after the sRGB transfer. By the definition
// (identical images) no showable radius hides a 2 px stair at half contrast: the published "far
// above the perceptual threshold" holds in the extreme. Forgiving single-level flips (the 1 px
// line is a staircase too) it is hidden at r = 7.26 px linear and 11.20 px sRGB: above the
// perceptual 3.47 a = 6.94 px, but not far above.
TEST(Reference, BresenhamPartnerIsAboveThePerceptualRadius) {
  stimuli::StimulusRenderer renderer;
  stimuli::StimulusSpec spec;
  spec.pattern = stimuli::Pattern::stair;
  spec.artifact_px = 2;
  spec.lit_linear = 0.5;
  spec.size_px = 64;
  stimuli::ReferenceSearch search;
  search.partner = stimuli::Partner::bresenham;
  search.resolution_px = 0.25;
  search.seeds = {3};
  for (const stimuli::Transfer& transfer : {stimuli::Transfer::linear, stimuli::Transfer::srgb}) {
    SCOPED_TRACE(stimuli::to_string(transfer));
    spec.transfer = transfer;
    search.tolerance_levels = 0;
    const stimuli::Reference exact = stimuli::find_reference(renderer, spec, search);
    EXPECT_FALSE(exact.reference_px.has_value());
    EXPECT_GT(exact.seeds.at(0).at_r_max.max_abs_levels, 0);
    search.tolerance_levels = 1;
    const stimuli::Reference forgiving = stimuli::find_reference(renderer, spec, search);
    ASSERT_TRUE(forgiving.reference_px.has_value());
    EXPECT_GT(*forgiving.reference_px, 3.47 * spec.artifact_px);
    EXPECT_EQ(stimuli::to_json(forgiving)["partner"], "bresenham");
    std::printf("bresenham reference, a = 2 px stair, half contrast, %s, 1 level forgiven: r = %.2f px\n",
                stimuli::to_string(transfer).c_str(), *forgiving.reference_px);
  }
}

TEST(Reference, RejectsBadSearches) {
  stimuli::StimulusRenderer renderer;
  stimuli::StimulusSpec spec;
  spec.pattern = stimuli::Pattern::step;
  stimuli::ReferenceSearch search;
  search.partner = stimuli::Partner::mean_line;
  EXPECT_THROW(stimuli::find_reference(renderer, spec, search), std::invalid_argument);
  spec.pattern = stimuli::Pattern::stair;
  search.r_max_px = 1000;  // beyond size / 2
  EXPECT_THROW(stimuli::find_reference(renderer, spec, search), std::invalid_argument);
  EXPECT_THROW(stimuli::parse_partner("straight"), std::invalid_argument);
}

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ::testing::AddGlobalTestEnvironment(new penumbra::test::GlEnvironment);
  return RUN_ALL_TESTS();
}
