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
  MarkOptions rule;  // c = 3.47
  rule.min_texel_px = 1;  // one footprint
  EXPECT_NEAR(requested_texel_ws({{0, 0}, 0.001, 0.12}, rule), 0.12 / 3.47, 1e-12);
  EXPECT_NEAR(requested_texel_ws({{0, 0}, 0.1, 0.12}, rule), 0.1, 1e-12) << "the pixel floor wins far away";
  EXPECT_NEAR(requested_texel_ws({{0, 0}, 0.001, 0}, rule), 0.001, 1e-12) << "no filter: the footprint";
  MarkOptions footprint = rule;
  footprint.marking = Marking::footprint;
  EXPECT_NEAR(requested_texel_ws({{0, 0}, 0.001, 0.12}, footprint), 0.001, 1e-12);
  footprint.min_texel_px = 2;
  EXPECT_NEAR(requested_texel_ws({{0, 0}, 0.001, 0.12}, footprint), 0.002, 1e-12);
}

// The default floor, 2^-0.5 footprints: where it sets the level, the level's texel is 0.35 to 0.71
// of the pixel's footprint, never a whole one (a floor of 1 gave texels up to a pixel, which shift
// shadow edges and drop thin lit rims by a pixel: docs/results/virtual-maps.md).
TEST(VirtualPages, TheDefaultFloorGivesTexelsOfAThirdToSevenTenthsOfAPixel) {
  const VirtualMapLayout l = layout();  // texels 0.005 · 2^k, k = 0..5
  const MarkOptions options;
  EXPECT_NEAR(options.min_texel_px, std::sqrt(0.5), 1e-4);
  for (double s = 0.0071; s < 0.1; s *= 1.07) {  // footprints whose floor lies within the levels
    SCOPED_TRACE(s);
    const double texel = l.texel0_ws * std::ldexp(1.0, level_for_texel(requested_texel_ws({{0, 0}, s, 0.001}, options), l));
    EXPECT_GT(texel, 0.3535 * s);
    EXPECT_LE(texel, 0.7071 * s);
  }
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
  // 3 mm inside, the filter stays in its page; a shading that reads a texel (5 mm) past the
  // filter's square (its normal offset) reaches the four again, and only them.
  const std::vector<PixelRequest> inside = {{{-0.16 + 0.02 * 8 + 0.003, -0.16 + 0.02 * 8 + 0.003}, 0.001, 0.002}};
  EXPECT_EQ(mark_pages(inside, {0, 0}, l, footprint).pages.size(), 1u);
  MarkOptions reach = footprint;
  reach.reach_texels = 1;
  EXPECT_EQ(mark_pages(inside, {0, 0}, l, reach).pages.size(), 4u);
  EXPECT_EQ(mark_pages(inside, {0, 0}, l, reach).pixels_per_level[0], 1) << "the reach widens the square, not the level";
  // Outside level 0's 32 cm window: level 1 (64 cm) takes it; beyond the coarsest (10.24 m): unmarked.
  const MarkResult far = mark_pages({{{0.3, 0}, 0.001, 0}, {{100, 0}, 0.001, 0}}, {0, 0}, l, footprint);
  EXPECT_EQ(far.pixels_per_level[1], 1);
  EXPECT_EQ(far.unmarked, 1);
  VirtualMapLayout bad = l;
  bad.levels = 0;
  EXPECT_THROW(mark_pages({}, {0, 0}, bad, footprint), std::invalid_argument);
}

// Issue 47: marks read a frame late are the previous camera's window-relative pages; rebased to the
// new camera they are the pages the new camera's marking gives the same surface points.
TEST(VirtualPages, MarksRebasedToAMovedCameraAreThatCamerasMarks) {
  const VirtualMapLayout l = layout();
  const MarkOptions footprint{Marking::footprint, 3.47, 1};
  std::vector<PixelRequest> pixels;
  // Within 9 cm of both cameras (inside level 0's window, 16 cm each way, for both), none on a
  // page boundary (where the two windows' float arithmetic may round apart).
  for (int i = 0; i < 40; ++i)
    pixels.push_back({{0.0131 + 0.06 * std::sin(0.7 * i), -0.0087 + 0.06 * std::cos(1.3 * i)}, i % 2 ? 0.004 : 0.008, 0});
  const LightXY a{0, 0}, b{0.05, -0.03};
  const MarkResult at_a = mark_pages(pixels, a, l, footprint), at_b = mark_pages(pixels, b, l, footprint);
  ASSERT_GT(at_a.pages.size(), 10u);
  EXPECT_EQ(at_a.unmarked + at_b.unmarked, 0);
  EXPECT_EQ(rebase_pages(at_a.pages, a, b, l), at_b.pages);
  EXPECT_EQ(rebase_pages(at_a.pages, a, a, l), at_a.pages);
  // A camera a metre away: level 0's and 1's windows (32 and 64 cm) hold none of them any more; a
  // level-5 page (10.24 m window) keeps its place.
  const std::set<Page> far = rebase_pages({{0, 8, 8}, {1, 8, 8}, {5, 8, 8}}, a, {1.0, 0}, l);
  ASSERT_EQ(far.size(), 1u);
  EXPECT_EQ(far.begin()->level, 5);
  EXPECT_EQ(far.begin()->x, 8 - 1);  // level 5's window moved one of its 64 cm pages
}

TEST(VirtualPages, TheRegionFloorCoversTheRegionOnTheFinestLevelThatFits) {
  const VirtualMapLayout l = layout();
  const LightXY camera{0.01, -0.02}, lo{-0.2, -0.25}, hi{0.22, 0.18};
  for (int max_pages : {16, 64, 400}) {
    SCOPED_TRACE(max_pages);
    const std::set<Page> floor = region_floor_pages(lo, hi, camera, l, max_pages);
    ASSERT_FALSE(floor.empty());
    const int level = floor.begin()->level;
    EXPECT_EQ(floor.rbegin()->level, level) << "one level";
    EXPECT_LE(static_cast<int>(floor.size()), max_pages);
    // Every point of the region lies in a page of the floor.
    const double page_ws = l.page_texels * l.texel0_ws * std::ldexp(1.0, level);
    const LightXY o = level_origin(level, camera, l);
    for (double x = lo.x; x <= hi.x; x += 0.01)
      for (double y = lo.y; y <= hi.y; y += 0.01) {
        const Page p{level, static_cast<int>(std::floor((x - o.x) / page_ws)), static_cast<int>(std::floor((y - o.y) / page_ws))};
        EXPECT_TRUE(floor.count(p)) << x << ", " << y;
      }
    // The next finer level would not do: more pages than allowed, or its window misses some.
    if (level > 0) {
      const double finer = page_ws / 2;
      const LightXY of = level_origin(level - 1, camera, l);
      const double nx = std::floor((hi.x - of.x) / finer) - std::floor((lo.x - of.x) / finer) + 1;
      const double ny = std::floor((hi.y - of.y) / finer) - std::floor((lo.y - of.y) / finer) + 1;
      const bool fits = of.x <= lo.x && of.y <= lo.y && hi.x < of.x + l.pages_per_side * finer && hi.y < of.y + l.pages_per_side * finer;
      EXPECT_TRUE(!fits || nx * ny > max_pages) << "level " << level - 1 << " would hold it in " << nx * ny;
    }
  }
  EXPECT_GT(region_floor_pages(lo, hi, camera, l, 16).begin()->level, region_floor_pages(lo, hi, camera, l, 400).begin()->level);
  // A region larger than the coarsest window: that level's whole window.
  const std::set<Page> huge = region_floor_pages({-100, -100}, {100, 100}, camera, l, 4);
  EXPECT_EQ(huge.size(), 16u * 16u);
  EXPECT_EQ(huge.begin()->level, 5);
  EXPECT_TRUE(region_floor_pages(hi, lo, camera, l, 64).empty());  // lo above hi: nothing
  EXPECT_TRUE(region_floor_pages({std::nan(""), 0}, hi, camera, l, 64).empty());
}

// The tiles a pixel's square reaches, a texel wider, on each page it marks; the CPU reference
// records them as the GPU marking does (VirtualMap.MarkingOnTheGpuEqualsTheCpuReference).
TEST(VirtualPages, ASquareMarksTheTilesItReachesATexelWider) {
  VirtualMapLayout l;
  l.levels = 2;
  l.texel0_ws = 0.01;  // a page of 128 texels is 1.28 m, a tile 16 cm
  l.page_texels = 128;
  l.pages_per_side = 4;
  MarkOptions footprint;
  footprint.marking = Marking::footprint;
  const LightXY o = level_origin(0, {0, 0}, l);
  EXPECT_DOUBLE_EQ(o.x, -2.56);
  const auto bit = [](int tx, int ty) { return TileMask{1} << (ty * kTilesPerSide + tx); };
  // The middle of page (1, 2) with a 5 cm filter: tiles 3 and 4 on each axis (its square and a
  // texel reach 6 cm of the 16 cm tiles).
  const LightXY middle{o.x + 1.28 * 1.5, o.y + 1.28 * 2.5};
  const MarkResult m = mark_pages({{middle, 0.001, 0.05}}, {0, 0}, l, footprint);
  ASSERT_EQ(m.pages.size(), 1u);
  EXPECT_EQ(m.tiles.at({0, 1, 2}), bit(3, 3) | bit(4, 3) | bit(3, 4) | bit(4, 4));
  // A square whose edge lies half a texel inside tile 3: the texel wider reaches tile 2.
  const MarkResult edge = mark_pages({{{o.x + 1.28 * (1 + 0.375 + 0.5 / 128) + 0.05, middle.y}, 0.001, 0.05}}, {0, 0}, l, footprint);
  ASSERT_EQ(edge.pages.size(), 1u);
  EXPECT_EQ(edge.tiles.at({0, 1, 2}), bit(2, 3) | bit(3, 3) | bit(2, 4) | bit(3, 4));
  // 2 cm inside the page's lower left corner: the square crosses to three neighbours, each getting
  // the tiles along the shared edges.
  const MarkResult corner = mark_pages({{{o.x + 1.28 + 0.02, o.y + 1.28 + 0.02}, 0.001, 0.05}}, {0, 0}, l, footprint);
  ASSERT_EQ(corner.pages.size(), 4u);
  EXPECT_EQ(corner.tiles.at({0, 1, 1}), bit(0, 0));
  EXPECT_EQ(corner.tiles.at({0, 0, 0}), bit(7, 7));
  EXPECT_EQ(corner.tiles.at({0, 1, 0}), bit(0, 7));
  EXPECT_EQ(corner.tiles.at({0, 0, 1}), bit(7, 0));
  // Two pixels: their tiles join.
  const MarkResult two = mark_pages({{middle, 0.001, 0.05}, {{middle.x + 0.5, middle.y}, 0.001, 0.05}}, {0, 0}, l, footprint);
  ASSERT_EQ(two.pages.size(), 1u);
  EXPECT_EQ(two.tiles.at({0, 1, 2}), bit(3, 3) | bit(4, 3) | bit(3, 4) | bit(4, 4) | bit(6, 3) | bit(7, 3) | bit(6, 4) | bit(7, 4));
}

// A page drawn by its marked tiles draws their bounding rectangle, a margin wider, within the page.
TEST(VirtualPages, APageIsDrawnOverItsMarkedTilesRectangleAMarginWider) {
  const auto bit = [](int tx, int ty) { return TileMask{1} << (ty * kTilesPerSide + tx); };
  EXPECT_EQ(tiles_rect(kEveryTile, 128, 2), (TexelRect{0, 0, 128, 128}));
  EXPECT_EQ(tiles_rect(0, 128, 2), (TexelRect{0, 0, 128, 128})) << "no tile known: the whole page";
  EXPECT_EQ(tiles_rect(bit(3, 5), 128, 0), (TexelRect{48, 80, 64, 96}));
  EXPECT_EQ(tiles_rect(bit(3, 5), 128, 2), (TexelRect{46, 78, 66, 98}));
  // Two tiles at opposite corners: the rectangle between them; the margin stops at the page's edges.
  EXPECT_EQ(tiles_rect(bit(0, 7) | bit(6, 1), 128, 3), (TexelRect{0, 13, 115, 128}));
  EXPECT_EQ(tiles_rect(bit(7, 0), 128, 40), (TexelRect{72, 0, 128, 56}));
  EXPECT_EQ(tiles_rect(bit(1, 1), 16, 0), (TexelRect{2, 2, 4, 4})) << "any page side the tiles divide";
  // A tile outside the rectangle would be a read the page misses: every marked tile lies inside.
  const TileMask scattered = bit(2, 1) | bit(5, 3) | bit(4, 6);
  const TexelRect r = tiles_rect(scattered, 128, 1);
  for (int b = 0; b < kTilesPerSide * kTilesPerSide; ++b)
    if ((scattered >> b) & 1u) {
      const int x = (b % kTilesPerSide) * 16, y = (b / kTilesPerSide) * 16;
      EXPECT_TRUE(x >= r.x0 && x + 16 <= r.x1 && y >= r.y0 && y + 16 <= r.y1) << "tile " << b;
    }
  EXPECT_THROW(tiles_rect(bit(0, 0), 100, 1), std::invalid_argument) << "100 texels are not 8 tiles";
  EXPECT_THROW(tiles_rect(bit(0, 0), 0, 1), std::invalid_argument);
  EXPECT_THROW(tiles_rect(bit(0, 0), 128, -1), std::invalid_argument);
}

}  // namespace
}  // namespace penumbra::adaptive
