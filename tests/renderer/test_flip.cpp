// LDR-FLIP (metrics/flip.h): zero for identical images, the colour pipeline against the published
// formulas computed here for uniform pairs (where the feature term vanishes), edge shifts of
// different contrast, the direction of pixels per degree, FLIP's weighted pooling, the encodings,
// the magma map, and the refusals.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "metrics/flip.h"

namespace {

using penumbra::image::Image8;
using penumbra::image::ImageF;
using penumbra::metrics::Encoding;
using penumbra::metrics::FlipOptions;
using penumbra::metrics::ldr_flip;
using ::testing::HasSubstr;

ImageF uniform(int w, int h, double r, double g, double b) {
  ImageF img{w, h, 3, {}};
  for (int i = 0; i < w * h; ++i) img.pixels.insert(img.pixels.end(), {static_cast<float>(r), static_cast<float>(g), static_cast<float>(b)});
  return img;
}

// A vertical edge: `left` for x < edge_x, `right` from it on (grey, all three channels).
ImageF edge(int w, int h, int edge_x, double left, double right) {
  ImageF img{w, h, 3, std::vector<float>(static_cast<std::size_t>(w) * h * 3)};
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) img.at(x, y, c) = static_cast<float>(x < edge_x ? left : right);
  return img;
}

// --- the published colour pipeline, written out independently from the paper's formulas with the
// textbook constants (IEC 61966-2-1 sRGB, its XYZ matrix to 7 digits, the CIE D65 white) ---------

struct Lab {
  double l, a, b;
};

double srgb_decode(double v) { return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4); }

Lab hunt_lab_of_linear(double r, double g, double b) {
  const double x = 0.4124564 * r + 0.3575761 * g + 0.1804375 * b;
  const double y = 0.2126729 * r + 0.7151522 * g + 0.0721750 * b;
  const double z = 0.0193339 * r + 0.1191920 * g + 0.9503041 * b;
  auto f = [](double t) { return t > 216.0 / 24389.0 ? std::cbrt(t) : (24389.0 / 27.0 * t + 16.0) / 116.0; };
  const double fx = f(x / 0.95047), fy = f(y / 1.0), fz = f(z / 1.08883);
  const double l = 116.0 * fy - 16.0;
  return {l, l / 100.0 * 500.0 * (fx - fy), l / 100.0 * 200.0 * (fy - fz)};  // Hunt: a, b times L/100
}

double hyab(const Lab& p, const Lab& q) { return std::abs(p.l - q.l) + std::hypot(p.a - q.a, p.b - q.b); }

// ΔE_c of two uniform sRGB colours: HyAB^0.7 remapped with c_max (green against blue), p_c = 0.4,
// p_t = 0.95. With no edges or points ΔE_f = 0 and FLIP = ΔE_c.
double expected_uniform_flip(const double s[3], const double t[3]) {
  const double qc = 0.7, pc = 0.4, pt = 0.95;
  const double cmax = std::pow(hyab(hunt_lab_of_linear(0, 1, 0), hunt_lab_of_linear(0, 0, 1)), qc);
  const double e = std::pow(hyab(hunt_lab_of_linear(srgb_decode(s[0]), srgb_decode(s[1]), srgb_decode(s[2])),
                                 hunt_lab_of_linear(srgb_decode(t[0]), srgb_decode(t[1]), srgb_decode(t[2]))),
                            qc);
  return e < pc * cmax ? pt / (pc * cmax) * e : pt + (e - pc * cmax) / (cmax - pc * cmax) * (1 - pt);
}

TEST(Flip, IdenticalImagesGiveZeroEverywhere) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  ImageF img{48, 32, 3, std::vector<float>(48 * 32 * 3)};
  for (float& v : img.pixels) v = u(rng);
  const auto r = ldr_flip(img, Encoding::srgb, img, Encoding::srgb);
  ASSERT_EQ(r.map.width, 48);
  ASSERT_EQ(r.map.height, 32);
  ASSERT_EQ(r.map.channels, 1);
  for (float v : r.map.pixels) ASSERT_EQ(v, 0.0f);
  EXPECT_EQ(r.pooled.mean, 0.0);
  EXPECT_EQ(r.pooled.max, 0.0);
  EXPECT_EQ(r.pooled.weighted_median, 0.0);
  EXPECT_EQ(r.pooled.share_above, 0.0);
}

TEST(Flip, UniformPairsMatchThePublishedColourPipeline) {
  struct Pair {
    double ref[3], test[3];
  };
  // A small difference (below p_c·c_max), a larger one, black against white (above p_c·c_max).
  const Pair pairs[] = {{{0.8, 0.3, 0.2}, {0.7, 0.35, 0.25}}, {{0.2, 0.6, 0.9}, {0.9, 0.5, 0.1}}, {{0, 0, 0}, {1, 1, 1}}};
  for (const Pair& p : pairs) {
    const double expected = expected_uniform_flip(p.ref, p.test);
    ASSERT_GT(expected, 0.0);
    const auto r = ldr_flip(uniform(24, 20, p.ref[0], p.ref[1], p.ref[2]), Encoding::srgb, uniform(24, 20, p.test[0], p.test[1], p.test[2]),
                            Encoding::srgb);
    // Textbook constants against the implementation's exact ones: agreement to 0.05 %.
    for (float v : r.map.pixels) ASSERT_NEAR(v, expected, 5e-4 * expected) << "pair starting " << p.ref[0] << " vs " << p.test[0];
    EXPECT_NEAR(r.pooled.mean, expected, 5e-4 * expected);
  }
  // Black against white lands above p_t (the upper branch of the remap), the small pair below it.
  EXPECT_GT(expected_uniform_flip(pairs[2].ref, pairs[2].test), 0.95);
  EXPECT_LT(expected_uniform_flip(pairs[0].ref, pairs[0].test), 0.95);
}

TEST(Flip, ShiftedHighContrastEdgeDiffersMoreThanLowContrastEdge) {
  // One-pixel shift of a black/white edge against the same shift of a 10 % (Michelson) contrast
  // edge around 18 % grey, given in linear RGB.
  const double lo = 0.18 * 0.9, hi = 0.18 * 1.1;
  const auto bw = ldr_flip(edge(64, 32, 32, 0, 1), Encoding::linear, edge(64, 32, 33, 0, 1), Encoding::linear);
  const auto low = ldr_flip(edge(64, 32, 32, lo, hi), Encoding::linear, edge(64, 32, 33, lo, hi), Encoding::linear);
  EXPECT_GT(low.pooled.mean, 0.0);
  EXPECT_GT(bw.pooled.mean, 2.0 * low.pooled.mean);
  EXPECT_GT(bw.pooled.max, low.pooled.max);
  // The difference stays near the edge: beyond both filters' reach (11 px at 67 px/deg) it is 0.
  for (int y = 0; y < 32; ++y)
    for (int x : {0, 10, 20, 44, 63}) ASSERT_EQ(bw.map.at(x, y), 0.0f) << x << "," << y;
  EXPECT_GT(bw.map.at(32, 16), 0.5f);
}

TEST(Flip, MorePixelsPerDegreeHideFineDetail) {
  // One-pixel stripes against their mean (in linear light, so that nothing but the detail
  // differs): the finer the pixels are to the eye, the smaller the difference. Measured inside the
  // pattern, beyond the widest filter (17 px at 120 px/deg) from the borders, where the repeated
  // edge pixels make a coarse edge of their own.
  const int n = 128;
  ImageF stripes{n, n, 3, std::vector<float>(static_cast<std::size_t>(n) * n * 3)};
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x)
      for (int c = 0; c < 3; ++c) stripes.at(x, y, c) = x % 2 ? 0.25f : 0.15f;
  const ImageF mean_grey = uniform(n, n, 0.2, 0.2, 0.2);
  double previous = 2.0;
  for (double ppd : {15.0, 30.0, 67.0, 120.0}) {
    FlipOptions o;
    o.pixels_per_degree = ppd;
    const ImageF map = ldr_flip(mean_grey, Encoding::linear, stripes, Encoding::linear, o).map;
    double sum = 0;
    for (int y = 48; y < 80; ++y)
      for (int x = 48; x < 80; ++x) sum += map.at(x, y);
    const double centre = sum / (32.0 * 32.0);
    if (ppd == 15.0) {
      EXPECT_GT(centre, 0.25);  // plainly visible when the stripes are coarse to the eye
    }
    EXPECT_LT(centre, 0.8 * previous) << ppd << " px/deg";
    previous = centre;
  }
  EXPECT_LT(previous, 0.005);  // at 120 px/deg the stripes blur into their mean
}

TEST(Flip, LinearAndSrgbEncodingsOfOneImageAgree) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  ImageF a{32, 24, 3, std::vector<float>(32 * 24 * 3)}, b = a;
  for (float& v : a.pixels) v = u(rng);
  for (float& v : b.pixels) v = u(rng);
  auto encode = [](ImageF img) {
    for (float& v : img.pixels) v = static_cast<float>(v <= 0.0031308f ? 12.92 * v : 1.055 * std::pow(v, 1 / 2.4) - 0.055);
    return img;
  };
  const auto lin = ldr_flip(a, Encoding::linear, b, Encoding::linear);
  const auto srgb = ldr_flip(encode(a), Encoding::srgb, encode(b), Encoding::srgb);
  const auto mixed = ldr_flip(a, Encoding::linear, encode(b), Encoding::srgb);
  for (std::size_t i = 0; i < lin.map.pixels.size(); ++i) {
    ASSERT_NEAR(lin.map.pixels[i], srgb.map.pixels[i], 1e-4);
    ASSERT_NEAR(lin.map.pixels[i], mixed.map.pixels[i], 1e-4);
  }
  // Treating linear values as sRGB is a different image: the encoding matters.
  const auto wrong = ldr_flip(a, Encoding::srgb, b, Encoding::srgb);
  EXPECT_GT(std::abs(wrong.pooled.mean - lin.pooled.mean), 0.01);
  // Values above 1 (an EXR) are clamped: 2.0 reads as 1.0.
  ImageF bright = a;
  for (float& v : bright.pixels) v = v > 0.5f ? 2.0f : v;
  ImageF clamped = a;
  for (float& v : clamped.pixels) v = v > 0.5f ? 1.0f : v;
  const auto over = ldr_flip(bright, Encoding::linear, b, Encoding::linear);
  const auto one = ldr_flip(clamped, Encoding::linear, b, Encoding::linear);
  EXPECT_EQ(over.map.pixels, one.map.pixels);
}

TEST(Flip, GreyAndAlphaChannelsAreRead) {
  const ImageF rgb_a = uniform(16, 16, 0.3, 0.3, 0.3), rgb_b = uniform(16, 16, 0.6, 0.6, 0.6);
  ImageF grey_a{16, 16, 1, std::vector<float>(256, 0.3f)}, grey_b{16, 16, 2, {}};
  for (int i = 0; i < 256; ++i) grey_b.pixels.insert(grey_b.pixels.end(), {0.6f, 0.1f});  // grey, alpha (ignored)
  const double expected = ldr_flip(rgb_a, Encoding::srgb, rgb_b, Encoding::srgb).pooled.mean;
  EXPECT_GT(expected, 0.0);
  EXPECT_NEAR(ldr_flip(grey_a, Encoding::srgb, grey_b, Encoding::srgb).pooled.mean, expected, 1e-6);
}

TEST(Flip, PixelsPerDegreeFromViewingGeometry) {
  // FLIP's default viewer: 3840 px over 0.7 m seen from 0.7 m, about 67.02 px/deg.
  EXPECT_NEAR(penumbra::metrics::pixels_per_degree(3840, 0.7, 0.7), 67.02, 0.01);
  EXPECT_NEAR(penumbra::metrics::kFlipDefaultPixelsPerDegree, 67.0206, 1e-4);
  // The study's default display (data/studies/default.json): 1920 px over 527 mm from 600 mm.
  EXPECT_NEAR(penumbra::metrics::pixels_per_degree(1920, 0.527, 0.6), 38.15, 0.01);
  // Twice as far: twice the pixels per degree (to 0.01 %).
  EXPECT_NEAR(penumbra::metrics::pixels_per_degree(1920, 0.527, 1.2), 2 * 38.15, 0.02);
  EXPECT_THROW(penumbra::metrics::pixels_per_degree(1920, 0, 0.6), std::invalid_argument);
  EXPECT_THROW(penumbra::metrics::pixels_per_degree(1920, 0.5, NAN), std::invalid_argument);
  // A viewer so far that a pixel spans degrees: the filters shrink to their centre tap, the map
  // stays finite (the colour difference alone).
  FlipOptions o;
  o.pixels_per_degree = 0.01;
  const auto far = ldr_flip(edge(16, 8, 8, 0, 1), Encoding::srgb, edge(16, 8, 9, 0, 1), Encoding::srgb, o);
  for (float v : far.map.pixels) ASSERT_TRUE(std::isfinite(v));
  EXPECT_GT(far.pooled.max, 0.9);  // the one column that changed from black to white
}

TEST(Flip, PoolingIsFlipsValueWeightedConvention) {
  ImageF map{8, 1, 1, {0.25f, 0.01f, 0.35f, 0.03f, 0.1f, 0.02f, 0.2f, 0.04f}};
  const auto p = penumbra::metrics::pool_flip(map, static_cast<double>(0.1f));  // the stored value itself
  // Sorted 0.01 0.02 0.03 0.04 0.1 0.2 0.25 0.35 (total 1.0); running sums .01 .03 .06 .10 .20 .40
  // .65 1.0. Weighted by value, not by count (by count the median would be 0.04 or 0.1).
  EXPECT_FLOAT_EQ(p.weighted_q1, 0.2f);       // first running sum above 0.25
  EXPECT_FLOAT_EQ(p.weighted_median, 0.25f);  // first above 0.5
  EXPECT_FLOAT_EQ(p.weighted_q3, 0.35f);      // first above 0.75
  EXPECT_NEAR(p.mean, 0.125, 1e-7);
  EXPECT_FLOAT_EQ(p.min, 0.01f);
  EXPECT_FLOAT_EQ(p.max, 0.35f);
  // Strictly above: the value at the threshold (0.1) does not count.
  EXPECT_DOUBLE_EQ(p.share_above, 3.0 / 8.0);
  EXPECT_DOUBLE_EQ(penumbra::metrics::pool_flip(map, 0.0).share_above, 1.0);
  EXPECT_EQ(p.pixels, 8);
}

TEST(Flip, MatchesTheAuthorsImplementation) {
  // A grey square (code value 200 of 255, 32×24) on black in a 64×48 image, shifted right by one
  // pixel: the means that the authors' tool (NVlabs/flip v1.6, commit 1eb247c, built from its
  // source; docs/compare.md) prints for the same pair as PNGs, 6 decimals. They pin every part of
  // the pipeline at once (filters, their sizes from pixels per degree, the feature term's scale).
  auto square = [](int x0) {
    ImageF img{64, 48, 3, std::vector<float>(64 * 48 * 3, 0.0f)};
    for (int y = 12; y < 36; ++y)
      for (int x = x0; x < x0 + 32; ++x)
        for (int c = 0; c < 3; ++c) img.at(x, y, c) = 200.0f / 255.0f;
    return img;
  };
  const struct {
    double ppd, mean;
  } published[] = {{15, 0.018572}, {30, 0.032451}, {67, 0.045405}, {120, 0.058106}};
  for (const auto& p : published) {
    FlipOptions o;
    o.pixels_per_degree = p.ppd;
    EXPECT_NEAR(ldr_flip(square(16), Encoding::srgb, square(17), Encoding::srgb, o).pooled.mean, p.mean, 2e-6) << p.ppd << " px/deg";
  }
  // One-pixel stripes (code values 102, 153) against grey 127, 64×64: the pattern runs into the
  // borders, so these pin the border rule (edge pixels repeated) too.
  ImageF stripes{64, 64, 3, std::vector<float>(64 * 64 * 3)}, grey{64, 64, 3, std::vector<float>(64 * 64 * 3, 127.0f / 255.0f)};
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x)
      for (int c = 0; c < 3; ++c) stripes.at(x, y, c) = (x % 2 ? 153.0f : 102.0f) / 255.0f;
  const struct {
    double ppd, mean;
  } striped[] = {{15, 0.442832}, {30, 0.239187}, {67, 0.092054}, {120, 0.100721}};
  for (const auto& p : striped) {
    FlipOptions o;
    o.pixels_per_degree = p.ppd;
    EXPECT_NEAR(ldr_flip(grey, Encoding::srgb, stripes, Encoding::srgb, o).pooled.mean, p.mean, 2e-5) << p.ppd << " px/deg";
  }
  // Saturated colours, whose blur leaves the RGB cube (the clamp): a red/blue edge at x = 24 of
  // 48×32 shifted by one pixel, and a green/magenta one-pixel checkerboard against grey 128, 32×32.
  auto red_blue = [](int x0) {
    ImageF img{48, 32, 3, std::vector<float>(48 * 32 * 3, 0.0f)};
    for (int y = 0; y < 32; ++y)
      for (int x = 0; x < 48; ++x) img.at(x, y, x < x0 ? 0 : 2) = 1.0f;
    return img;
  };
  ImageF checker{32, 32, 3, std::vector<float>(32 * 32 * 3, 0.0f)};
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 32; ++x)
      for (int c = 0; c < 3; ++c) checker.at(x, y, c) = ((x + y) % 2 ? c == 1 : c != 1) ? 1.0f : 0.0f;
  const ImageF grey128{32, 32, 3, std::vector<float>(32 * 32 * 3, 128.0f / 255.0f)};
  for (const auto& [ppd, edge_mean, checker_mean] : {std::tuple{30.0, 0.058291, 0.849530}, std::tuple{67.0, 0.075685, 0.526710}}) {
    FlipOptions o;
    o.pixels_per_degree = ppd;
    EXPECT_NEAR(ldr_flip(red_blue(24), Encoding::srgb, red_blue(25), Encoding::srgb, o).pooled.mean, edge_mean, 2e-6) << ppd;
    EXPECT_NEAR(ldr_flip(grey128, Encoding::srgb, checker, Encoding::srgb, o).pooled.mean, checker_mean, 5e-6) << ppd;
  }
}

TEST(Flip, MagmaMapEndsAndSize) {
  ImageF map{3, 1, 1, {0.0f, 0.5f, 1.0f}};
  const Image8 m = penumbra::metrics::flip_magma(map);
  ASSERT_EQ(m.channels, 3);
  ASSERT_EQ(m.width, 3);
  EXPECT_EQ((std::vector<int>{m.at(0, 0, 0), m.at(0, 0, 1), m.at(0, 0, 2)}), (std::vector<int>{0, 0, 4}));        // near black
  EXPECT_EQ((std::vector<int>{m.at(2, 0, 0), m.at(2, 0, 1), m.at(2, 0, 2)}), (std::vector<int>{252, 253, 191}));  // pale yellow
  // Brighter with the value (magma is perceptually ordered).
  auto luma = [&](int x) { return 0.2126 * m.at(x, 0, 0) + 0.7152 * m.at(x, 0, 1) + 0.0722 * m.at(x, 0, 2); };
  EXPECT_LT(luma(0), luma(1));
  EXPECT_LT(luma(1), luma(2));
}

// A reference prepared once (the main job compares a dozen configurations against each) judges
// every test image as a fresh pair would, to the bit, whatever it judged before; and it refuses
// what the pairwise call refuses.
TEST(Flip, APreparedReferenceGivesEachPairsValueWhateverCameBefore) {
  const ImageF reference = edge(48, 24, 24, 0.1, 0.9);
  const std::vector<ImageF> tests = {edge(48, 24, 25, 0.1, 0.9), uniform(48, 24, 0.5, 0.2, 0.7), edge(48, 24, 20, 0.0, 1.0), reference};
  FlipOptions o;
  o.pixels_per_degree = 30;
  const penumbra::metrics::FlipReference prepared(reference, Encoding::srgb, o);
  for (int round = 0; round < 2; ++round)
    for (std::size_t i = 0; i < tests.size(); ++i) {
      const auto pair = ldr_flip(reference, Encoding::srgb, tests[i], Encoding::srgb, o);
      const auto reused = prepared.compare(tests[i], Encoding::srgb);
      ASSERT_EQ(reused.map.pixels, pair.map.pixels) << "test " << i << ", round " << round;
      EXPECT_EQ(reused.pooled.mean, pair.pooled.mean);
      EXPECT_EQ(reused.pixels_per_degree, 30.0);
    }
  EXPECT_EQ(prepared.compare(reference, Encoding::srgb).pooled.max, 0.0);
  EXPECT_GT(prepared.compare(tests[2], Encoding::srgb).pooled.mean, 0.01);
  EXPECT_THROW(prepared.compare(uniform(47, 24, 0.5, 0.5, 0.5), Encoding::srgb), std::invalid_argument);
  o.pixels_per_degree = -1;
  EXPECT_THROW(penumbra::metrics::FlipReference(reference, Encoding::srgb, o), std::invalid_argument);
}

TEST(Flip, RefusesWhatItCannotCompare) {
  const ImageF a = uniform(8, 8, 0.5, 0.5, 0.5);
  auto message = [](auto f) {
    try {
      f();
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no exception");
  };
  EXPECT_THAT(message([&] { ldr_flip(a, Encoding::srgb, uniform(8, 9, 0.5, 0.5, 0.5), Encoding::srgb); }), HasSubstr("sizes differ"));
  ImageF nan = a;
  nan.at(3, 5, 1) = NAN;
  EXPECT_THAT(message([&] { ldr_flip(a, Encoding::srgb, nan, Encoding::srgb); }), HasSubstr("non-finite value at pixel (3, 5)"));
  ImageF five{8, 8, 5, std::vector<float>(8 * 8 * 5)};
  EXPECT_THAT(message([&] { ldr_flip(five, Encoding::srgb, a, Encoding::srgb); }), HasSubstr("5 channels"));
  ImageF short_buffer = a;
  short_buffer.pixels.pop_back();
  EXPECT_THAT(message([&] { ldr_flip(a, Encoding::srgb, short_buffer, Encoding::srgb); }), HasSubstr("holds"));
  FlipOptions o;
  o.pixels_per_degree = 0;
  EXPECT_THAT(message([&] { ldr_flip(a, Encoding::srgb, a, Encoding::srgb, o); }), HasSubstr("pixels per degree"));
  o = {};
  o.threshold = 1.5;
  EXPECT_THAT(message([&] { ldr_flip(a, Encoding::srgb, a, Encoding::srgb, o); }), HasSubstr("threshold"));
}

}  // namespace
