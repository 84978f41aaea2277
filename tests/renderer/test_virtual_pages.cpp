// Page marking for a virtual shadow map (adaptive/virtual_pages.h): the level each pixel asks for
// is the rule's (or the footprint's) texel rounded to the clipmap's powers of two, computed here
// by hand for known footprints and radii; the filter's reach marks neighbouring pages; a pixel
// beyond a level's window goes coarser, beyond the coarsest it is counted, not marked.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <vector>

#include "adaptive/virtual_pages.h"

namespace penumbra::adaptive {
namespace {

VirtualMapLayout layout() {
  VirtualMapLayout l;
  l.levels = 6;
  l.texel0_ws = 0.005;
  l.page_texels = 4;      // a page is 2 cm at level 0
  l.pages_per_side = 16;  // 32 cm per level 0 window
  return l;
}

TEST(VirtualPages, RequestedTexelIsTheRuleAboveThePixelFloor) {
  MarkOptions rule;  // c = 3.47, one footprint
  EXPECT_NEAR(requested_texel_ws({{0, 0}, 0.001, 0.12}, rule), 0.12 / 3.47, 1e-12);
  EXPECT_NEAR(requested_texel_ws({{0, 0}, 0.1, 0.12}, rule), 0.1, 1e-12) << "the pixel floor wins far away";
  EXPECT_NEAR(requested_texel_ws({{0, 0}, 0.001, 0}, rule), 0.001, 1e-12) << "no filter: the footprint";
  MarkOptions footprint = rule;
  footprint.marking = Marking::footprint;
  EXPECT_NEAR(requested_texel_ws({{0, 0}, 0.001, 0.12}, footprint), 0.001, 1e-12);
  footprint.min_texel_px = 2;
  EXPECT_NEAR(requested_texel_ws({{0, 0}, 0.001, 0.12}, footprint), 0.002, 1e-12);
}

TEST(VirtualPages, LevelIsTheCoarsestTexelNotAboveTheRequest) {
  const VirtualMapLayout l = layout();  // texels 0.005, 0.01, 0.02, 0.04, 0.08, 0.16
  EXPECT_EQ(level_for_texel(0.12 / 3.47, l), 2);  // 0.0346: 0.02 <= it < 0.04
  EXPECT_EQ(level_for_texel(0.04, l), 3) << "exactly a level's texel is that level";
  EXPECT_EQ(level_for_texel(0.004, l), 0) << "finer than level 0: level 0";
  EXPECT_EQ(level_for_texel(0.0, l), 0);
  EXPECT_EQ(level_for_texel(std::nan(""), l), 0);
  EXPECT_EQ(level_for_texel(1e30, l), 5) << "the coarsest";
}

TEST(VirtualPages, RuleMarksCoarserPagesThanTheFootprint) {
  const VirtualMapLayout l = layout();
  // A 1 cm grid of pixels over 10 cm around the camera, 1 mm footprints, a 2 cm filter.
  std::vector<PixelRequest> pixels;
  for (int y = 0; y < 10; ++y)
    for (int x = 0; x < 10; ++x) pixels.push_back({{0.01 * x - 0.05, 0.01 * y - 0.05}, 0.001, 0.02});
  MarkOptions rule;
  rule.c_texels = 2;  // texel 1 cm: level 1
  const MarkResult by_rule = mark_pages(pixels, {0, 0}, l, rule);
  MarkOptions footprint = rule;
  footprint.marking = Marking::footprint;  // 1 mm: level 0
  const MarkResult by_footprint = mark_pages(pixels, {0, 0}, l, footprint);
  EXPECT_EQ(by_rule.pixels_per_level[1], 100);
  EXPECT_EQ(by_footprint.pixels_per_level[0], 100);
  for (const Page& p : by_rule.pages) EXPECT_EQ(p.level, 1);
  for (const Page& p : by_footprint.pages) EXPECT_EQ(p.level, 0);
  // Level 1 pages are 4 cm, level 0 pages 2 cm: the points and their 2 cm reach span x, y in
  // [-0.07, 0.06]: level 0 pages 4..11 (window from -0.16), level 1 pages 6..9 (from -0.32).
  EXPECT_EQ(by_footprint.pages.size(), 64u);
  EXPECT_EQ(by_rule.pages.size(), 16u);
  EXPECT_EQ(by_rule.pages_per_level()[1], static_cast<std::int64_t>(by_rule.pages.size()));
  EXPECT_EQ(by_rule.unmarked, 0);
}

TEST(VirtualPages, TheFilterReachMarksNeighboursAndFarPixelsGoCoarser) {
  const VirtualMapLayout l = layout();
  const LightXY origin = level_origin(0, {0, 0}, l);
  EXPECT_DOUBLE_EQ(origin.x, -0.16);  // half of 16 pages of 2 cm, page-snapped
  MarkOptions footprint;
  footprint.marking = Marking::footprint;
  // A point 1 mm inside a page corner at level 0 with a 2 mm filter reaches the four pages there.
  const MarkResult corner = mark_pages({{{-0.16 + 0.02 * 8 + 0.001, -0.16 + 0.02 * 8 + 0.001}, 0.001, 0.002}}, {0, 0}, l, footprint);
  ASSERT_EQ(corner.pages.size(), 4u);
  EXPECT_EQ(corner.pages.begin()->x, 7);
  EXPECT_EQ(corner.pages.rbegin()->x, 8);
  // Outside level 0's 32 cm window: level 1 (64 cm) takes it; beyond the coarsest (10.24 m): unmarked.
  const MarkResult far = mark_pages({{{0.3, 0}, 0.001, 0}, {{100, 0}, 0.001, 0}}, {0, 0}, l, footprint);
  EXPECT_EQ(far.pixels_per_level[1], 1);
  EXPECT_EQ(far.unmarked, 1);
  VirtualMapLayout bad = l;
  bad.levels = 0;
  EXPECT_THROW(mark_pages({}, {0, 0}, bad, footprint), std::invalid_argument);
}

}  // namespace
}  // namespace penumbra::adaptive
