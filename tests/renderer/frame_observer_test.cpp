// The frame observer (renderer/metrics/frame_observer.h): the guess rate on equal frames, near
// certainty on strong artifacts, the viewing distance, what its Weber law says about contrast, the
// tiling of the frame into patches and the refusals.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <stdexcept>
#include <vector>

#include "metrics/frame_observer.h"

using namespace penumbra;
using metrics::Encoding;

namespace {

// A one-channel linear image whose pixel value is the mean of `lit(x, y)` (linear light) over
// 4 × 4 samples of the pixel: edges are drawn with their coverage, as a renderer's would be.
image::ImageF draw(int width, int height, const std::function<double(double, double)>& lit) {
  image::ImageF img{width, height, 1, std::vector<float>(static_cast<std::size_t>(width) * height)};
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      double sum = 0;
      for (int sy = 0; sy < 4; ++sy)
        for (int sx = 0; sx < 4; ++sx) sum += lit(x + (sx + 0.5) / 4, y + (sy + 0.5) / 4);
      img.at(x, y) = static_cast<float>(sum / 16);
    }
  return img;
}

// A vertical shadow edge at x = edge_px with a linear penumbra `width_px` wide, from `dark` to `lit`.
image::ImageF soft_edge(int size, double edge_px, double width_px, double dark = 0.0, double lit = 1.0) {
  return draw(size, size, [=](double x, double) { return dark + (lit - dark) * std::clamp((x - edge_px) / width_px + 0.5, 0.0, 1.0); });
}

// The edge y = 0.5 x + b (lit below it), straight or as the staircase of a shadow map whose texels
// are `texel_px` wide: a texel is lit when its centre is.
image::ImageF slanted_edge(int size, double texel_px, bool staircase, double lit = 1.0) {
  return draw(size, size, [=](double x, double y) {
    if (staircase) {
      x = (std::floor(x / texel_px) + 0.5) * texel_px;
      y = (std::floor(y / texel_px) + 0.5) * texel_px;
    }
    return y > 0.5 * x + 0.3 * size ? lit : 0.0;
  });
}

}  // namespace

TEST(FrameObserver, AFrameEqualToItsReferenceIsSeenAtTheGuessRate) {
  const image::ImageF ref = slanted_edge(160, 6, true);
  const metrics::FrameDetection d = metrics::detect_difference(ref, Encoding::linear, ref, Encoding::linear);
  ASSERT_FALSE(d.patches.empty());
  for (const metrics::PatchDetection& p : d.patches) {
    EXPECT_EQ(p.deviation, 0.0);
    EXPECT_DOUBLE_EQ(p.p_correct, 0.5);
    EXPECT_EQ(p.p_detect, 0.0);
  }
  EXPECT_EQ(d.p_detect_max, 0.0);
  EXPECT_EQ(d.patches_visible, 0);
  EXPECT_FALSE(d.visible);
}

// A lit floor (1.0), an occluder's face (0.3) on [50, 70) and its shadow (0.05) from `shadow_from`
// to `shadow_to`, the shadow's far edge a penumbra `width_px` wide: vertical structures only.
image::ImageF occluder_and_shadow(int size, double shadow_from, double shadow_to, double width_px) {
  return draw(size, size, [=](double x, double) {
    if (x >= 50 && x < 70) return 0.3;
    if (x < shadow_from) return 1.0;
    return 0.05 + 0.95 * std::clamp((x - shadow_to) / width_px + 0.5, 0.0, 1.0);
  });
}

TEST(FrameObserver, AShadowThatLeavesItsOccluderIsSeenAlmostSurely) {
  // Peter-panning: the shadow starts 4 px away from the occluder's foot instead of at it.
  const image::ImageF ref = occluder_and_shadow(240, 70, 110, 3), test = occluder_and_shadow(240, 74, 114, 3);
  const metrics::FrameDetection d = metrics::detect_difference(ref, Encoding::linear, test, Encoding::linear);
  EXPECT_GT(d.p_detect_max, 0.99);
  EXPECT_TRUE(d.visible);
  // Only the patches that hold the change see it (2° at 38.2 px/deg: 76 px; the change lies in
  // x 70 to 116 and the windows reach up to 1° further); the rest are flat and equal.
  int seen = 0;
  for (const metrics::PatchDetection& p : d.patches) {
    if (p.p_detect > 0.99) ++seen;
    if (p.x_px >= 228) {  // beyond the largest window's reach
      EXPECT_LT(p.p_detect, 1e-3) << "patch at x " << p.x_px;  // the box filter's running sums leave ~1e-9
    }
  }
  EXPECT_GT(seen, 0);
}

// Positions are compared within a window, not across the two images: a soft shadow edge that moves
// by a pixel on its own is a shift the observer does not see, the same move against the occluder's
// edge beside it changes the shape it sees.
TEST(FrameObserver, AShadowMovedAsAWholeIsSeenLessThanOneMovedAgainstItsOccluder) {
  const metrics::FrameDetection alone = metrics::detect_difference(soft_edge(160, 80, 12), Encoding::linear, soft_edge(160, 81, 12),
                                                                   Encoding::linear);
  const metrics::FrameDetection anchored = metrics::detect_difference(occluder_and_shadow(160, 70, 82, 12), Encoding::linear,
                                                                      occluder_and_shadow(160, 70, 83, 12), Encoding::linear);
  EXPECT_LT(alone.p_detect_max, 0.2);
  EXPECT_GT(anchored.deviation_max, 3 * alone.deviation_max);
}

// The floor's meaning: a uniform change of 1 % of the surround's luminance over a degree of a flat
// field is at about the criterion (82 % correct), a third of it well below.
TEST(FrameObserver, AOnePercentChangeOfAFlatFieldIsAtTheCriterion) {
  auto field = [](double inside) {
    return draw(160, 160, [=](double x, double y) { return x >= 60 && x < 98 && y >= 60 && y < 98 ? inside : 0.5; });
  };
  const image::ImageF ref = field(0.5);
  const metrics::FrameDetection one = metrics::detect_difference(ref, Encoding::linear, field(0.505), Encoding::linear);
  const metrics::FrameDetection third = metrics::detect_difference(ref, Encoding::linear, field(0.5 + 0.005 / 3), Encoding::linear);
  double best = 0;
  for (const metrics::PatchDetection& p : one.patches) best = std::max(best, p.p_correct);
  EXPECT_GT(best, 0.76);
  EXPECT_LT(best, 0.88);
  EXPECT_LT(third.p_detect_max, 0.4);
}

TEST(FrameObserver, AStaircasedEdgeIsSeenAlmostSurelyAndTheSrgbFileTheSame) {
  const image::ImageF ref = slanted_edge(160, 8, false), test = slanted_edge(160, 8, true);
  const metrics::FrameDetection linear = metrics::detect_difference(ref, Encoding::linear, test, Encoding::linear);
  EXPECT_GT(linear.p_detect_max, 0.99);
  // Black and white are the same in sRGB and linear light: the encoding decodes to the same luminance.
  const metrics::FrameDetection srgb = metrics::detect_difference(ref, Encoding::srgb, test, Encoding::srgb);
  EXPECT_GT(srgb.p_detect_max, 0.99);
}

TEST(FrameObserver, AFartherViewerSeesAFineStaircaseLess) {
  const image::ImageF ref = slanted_edge(240, 2, false), test = slanted_edge(240, 2, true);
  metrics::FrameObserverParams near, far;
  near.pixels_per_degree = 38.2;
  far.pixels_per_degree = 4 * 38.2;  // four times as far: the eye's blur covers four times the pixels
  const metrics::FrameDetection dn = metrics::detect_difference(ref, Encoding::linear, test, Encoding::linear, near);
  const metrics::FrameDetection df = metrics::detect_difference(ref, Encoding::linear, test, Encoding::linear, far);
  EXPECT_GT(dn.deviation_max, 0.0);
  EXPECT_LT(df.deviation_max, 0.5 * dn.deviation_max);
  EXPECT_LT(df.p_detect_max, dn.p_detect_max);
}

// The Weber law for position divides a change by the edge's own contrast: a staircase and its
// straight edge both dimmed to 10 % (the study's lower lit levels, dark stays dark) give nearly the
// same deviation (the display's black level alone differs), while the same staircase as a 10 % edge
// on a bright surround is judged against the surround's luminance (the floor) and is seen less.
TEST(FrameObserver, ContrastMattersOnlyThroughTheSurroundNotThroughTheEdgesOwnScale) {
  auto deviation = [](double dark, double lit) {
    auto stair = [=](bool staircase) {
      image::ImageF img = slanted_edge(160, 6, staircase);
      for (float& v : img.pixels) v = static_cast<float>(dark + (lit - dark) * v);
      return img;
    };
    return metrics::detect_difference(stair(false), Encoding::linear, stair(true), Encoding::linear).deviation_max;
  };
  const double full = deviation(0.0, 1.0), dim = deviation(0.0, 0.1), on_white = deviation(0.9, 1.0);
  ASSERT_GT(full, 0.0);
  EXPECT_NEAR(dim / full, 1.0, 0.05);
  EXPECT_LT(on_white, 0.6 * full);
}

TEST(FrameObserver, PatchesTileTheFrameEdgesIncluded) {
  metrics::FrameObserverParams params;
  params.pixels_per_degree = 15;  // patches of 30 px
  const int width = 100, height = 70;
  const image::ImageF ref = draw(width, height, [](double, double) { return 0.5; });
  image::ImageF test = ref;
  test.at(width - 1, height - 1) = 1.0f;  // one pixel in the last corner
  const metrics::FrameDetection d = metrics::detect_difference(ref, Encoding::linear, test, Encoding::linear, params);
  EXPECT_EQ(d.patch_px, 30);
  EXPECT_EQ(d.patches_x, 4);
  EXPECT_EQ(d.patches_y, 3);
  ASSERT_EQ(d.patches.size(), 12u);
  std::vector<int> covered(static_cast<std::size_t>(width) * height, 0);
  for (const metrics::PatchDetection& p : d.patches)
    for (int y = p.y_px; y < p.y_px + p.height_px; ++y)
      for (int x = p.x_px; x < p.x_px + p.width_px; ++x) ++covered[static_cast<std::size_t>(y) * width + x];
  EXPECT_TRUE(std::all_of(covered.begin(), covered.end(), [](int c) { return c == 1; }));
  EXPECT_EQ(d.patches.back().width_px, 10);
  EXPECT_EQ(d.patches.back().height_px, 10);
  EXPECT_GT(d.patches.back().deviation, 0.0);
  EXPECT_EQ(d.patches.front().deviation, 0.0);
}

// A reference prepared once judges every frame as a fresh pair would, to the bit, whatever it
// judged before; and it refuses what the pairwise call refuses.
TEST(FrameObserver, APreparedReferenceGivesEachPairsVerdictWhateverCameBefore) {
  const image::ImageF reference = slanted_edge(96, 4, false);
  const std::vector<image::ImageF> tests = {slanted_edge(96, 4, true), soft_edge(96, 48, 6), reference, slanted_edge(96, 2, true)};
  const metrics::ObserverReference prepared(reference, Encoding::linear);
  for (int round = 0; round < 2; ++round)
    for (std::size_t i = 0; i < tests.size(); ++i) {
      const metrics::FrameDetection pair = metrics::detect_difference(reference, Encoding::linear, tests[i], Encoding::linear);
      const metrics::FrameDetection reused = prepared.judge(tests[i], Encoding::linear);
      ASSERT_EQ(reused.patches.size(), pair.patches.size());
      for (std::size_t k = 0; k < pair.patches.size(); ++k)
        ASSERT_EQ(reused.patches[k].deviation, pair.patches[k].deviation) << "test " << i << ", patch " << k << ", round " << round;
      EXPECT_EQ(reused.visible, pair.visible);
    }
  EXPECT_EQ(prepared.judge(reference, Encoding::linear).deviation_max, 0.0);
  EXPECT_TRUE(prepared.judge(tests[0], Encoding::linear).visible);
  EXPECT_THROW(prepared.judge(soft_edge(95, 48, 6), Encoding::linear), std::invalid_argument);
  metrics::FrameObserverParams bad;
  bad.weber = 0;
  EXPECT_THROW(metrics::ObserverReference(reference, Encoding::linear, bad), std::invalid_argument);
}

TEST(FrameObserver, RefusesMismatchedSizesAndBadParameters) {
  const image::ImageF a = soft_edge(64, 32, 4), b = soft_edge(65, 32, 4);
  EXPECT_THROW(metrics::detect_difference(a, Encoding::linear, b, Encoding::linear), std::invalid_argument);
  metrics::FrameObserverParams params;
  params.pixels_per_degree = 0;
  EXPECT_THROW(metrics::detect_difference(a, Encoding::linear, a, Encoding::linear, params), std::invalid_argument);
  params = {};
  params.criterion_f = 1;
  EXPECT_THROW(metrics::detect_difference(a, Encoding::linear, a, Encoding::linear, params), std::invalid_argument);
  image::ImageF nan = a;
  nan.at(3, 4) = NAN;
  try {
    metrics::detect_difference(a, Encoding::linear, nan, Encoding::linear);
    FAIL() << "a NaN was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("test image has a non-finite value at pixel (3, 4)"), std::string::npos) << e.what();
  }
}
