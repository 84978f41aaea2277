// The frame observer (renderer/metrics/frame_observer.h): the guess rate on equal frames, near
// certainty on strong artifacts, the viewing distance, what its Weber law says about contrast, the
// tiling of the frame into patches and the refusals.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <stdexcept>

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

TEST(FrameObserver, AShadowEdgeShiftedByFourPixelsIsSeenAlmostSurely) {
  const image::ImageF ref = soft_edge(160, 80, 3), test = soft_edge(160, 84, 3);
  const metrics::FrameDetection d = metrics::detect_difference(ref, Encoding::linear, test, Encoding::linear);
  EXPECT_GT(d.p_detect_max, 0.99);
  EXPECT_TRUE(d.visible);
  // Only the patches the edge crosses see it: the flat ones on either side do not.
  int seen = 0;
  for (const metrics::PatchDetection& p : d.patches) {
    const bool crossed = p.x_px <= 90 && p.x_px + p.width_px >= 74;
    if (crossed) {
      ++seen;
      EXPECT_GT(p.p_detect, 0.99) << "patch at x " << p.x_px;
    } else {
      EXPECT_LT(p.p_detect, 1e-3) << "patch at x " << p.x_px;  // the box filter's running sums leave ~1e-9
    }
  }
  EXPECT_GT(seen, 0);
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

// The Weber law for position divides a change by the edge's own contrast: a frame and its reference
// both dimmed to 10 % (the study's lower lit levels, dark stays dark) give nearly the same deviation
// (the display's black level alone differs), while the same displacement of a 10 % edge on a bright
// surround is judged against the surround's luminance (the floor) and is seen less.
TEST(FrameObserver, ContrastMattersOnlyThroughTheSurroundNotThroughTheEdgesOwnScale) {
  const metrics::FrameDetection full = metrics::detect_difference(soft_edge(160, 80, 12), Encoding::linear, soft_edge(160, 81, 12),
                                                                  Encoding::linear);
  const metrics::FrameDetection dim = metrics::detect_difference(soft_edge(160, 80, 12, 0.0, 0.1), Encoding::linear,
                                                                 soft_edge(160, 81, 12, 0.0, 0.1), Encoding::linear);
  const metrics::FrameDetection on_white = metrics::detect_difference(soft_edge(160, 80, 12, 0.9, 1.0), Encoding::linear,
                                                                      soft_edge(160, 81, 12, 0.9, 1.0), Encoding::linear);
  ASSERT_GT(full.deviation_max, 0.0);
  EXPECT_NEAR(dim.deviation_max / full.deviation_max, 1.0, 0.05);
  EXPECT_LT(on_white.deviation_max, 0.75 * full.deviation_max);
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
