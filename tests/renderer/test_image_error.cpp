// Image error metrics (renderer/metrics/image_error.h) against answers known in closed form.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "metrics/image_error.h"

namespace penumbra::metrics {
namespace {

using ::testing::HasSubstr;

io::ImageF float_image(int w, int h, int channels, float value) {
  return {w, h, channels, std::vector<float>(static_cast<std::size_t>(w) * h * channels, value)};
}
io::Image8 byte_image(int w, int h, int channels, std::uint8_t value) {
  return {w, h, channels, std::vector<std::uint8_t>(static_cast<std::size_t>(w) * h * channels, value)};
}
// A smooth ramp with some texture, values in [0.1, 0.9].
io::ImageF textured(int w, int h) {
  io::ImageF img = float_image(w, h, 1, 0);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) img.at(x, y) = 0.5f + 0.3f * std::sin(0.3f * x) * std::cos(0.2f * y) + 0.1f * (x % 3 == 0);
  return img;
}
// What SSIM gives for two constant images a and b on the 0..255 scale: the structure term is
// 1 (no variance), the luminance term (2ab + C1) / (a² + b² + C1).
double ssim_of_constants(double a, double b) {
  const double c1 = 0.01 * 255 * 0.01 * 255;
  return (2 * a * b + c1) / (a * a + b * b + c1);
}

template <class F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "(no exception)";
}

TEST(ImageError, IdenticalImagesHaveNoErrorAndSsimOne) {
  const io::ImageF a = textured(64, 48);
  const ImageError e = compare(a, a);
  EXPECT_EQ(e.pixels, 64 * 48);
  EXPECT_EQ(e.channels, 1);
  EXPECT_EQ(e.max_abs, 0);
  EXPECT_EQ(e.mean_abs, 0);
  EXPECT_EQ(e.rmse, 0);
  EXPECT_TRUE(std::isinf(e.psnr_db) && e.psnr_db > 0);
  EXPECT_DOUBLE_EQ(e.ssim, 1.0);
  EXPECT_EQ(e.share_above_threshold, 0);
  EXPECT_TRUE(to_json(e)["psnr_db"].is_null()) << "JSON has no infinity";

  io::Image8 rgba = byte_image(40, 30, 4, 0);
  for (std::size_t i = 0; i < rgba.pixels.size(); ++i) rgba.pixels[i] = static_cast<std::uint8_t>((i * 37) % 256);
  const ImageError e8 = compare(rgba, rgba);
  EXPECT_EQ(e8.channels, 3);
  EXPECT_EQ(e8.max_abs, 0);
  EXPECT_DOUBLE_EQ(e8.ssim, 1.0);
}

TEST(ImageError, ConstantOffset) {
  const io::ImageF a = float_image(32, 32, 1, 0.5f);
  const io::ImageF b = float_image(32, 32, 1, 0.6f);
  const ImageError e = compare(a, b);
  EXPECT_NEAR(e.max_abs, 0.1, 1e-6);
  EXPECT_NEAR(e.mean_abs, 0.1, 1e-6);
  EXPECT_NEAR(e.rmse, 0.1, 1e-6);
  EXPECT_NEAR(e.psnr_db, 20.0, 1e-4);
  EXPECT_EQ(e.share_above_threshold, 1.0);
  EXPECT_NEAR(e.ssim, ssim_of_constants(0.5 * 255, 0.6f * 255.0), 1e-6);

  // On a textured image the offset leaves structure intact: only the luminance term drops.
  io::ImageF t = textured(64, 64), u = t;
  for (auto& v : u.pixels) v += 0.05f;
  const ImageError et = compare(t, u);
  EXPECT_NEAR(et.mean_abs, 0.05, 1e-6);
  EXPECT_NEAR(et.max_abs, 0.05, 1e-6);
  EXPECT_GT(et.ssim, 0.97);
  EXPECT_LT(et.ssim, 1.0);

  // 8-bit: 10 codes everywhere, in every colour channel.
  const ImageError e8 = compare(byte_image(16, 8, 3, 100), byte_image(16, 8, 3, 110));
  EXPECT_DOUBLE_EQ(e8.max_abs, 10.0 / 255);
  EXPECT_DOUBLE_EQ(e8.mean_abs, 10.0 / 255);
  EXPECT_NEAR(e8.psnr_db, 20 * std::log10(25.5), 1e-9);
  EXPECT_NEAR(e8.ssim, ssim_of_constants(100, 110), 1e-5);  // luma of grey is the grey value
}

TEST(ImageError, SinglePixelChange) {
  io::Image8 a = byte_image(64, 64, 1, 100), b = a;
  b.at(20, 30) = 151;  // +51 codes = 0.2
  const ImageError e = compare(a, b);
  EXPECT_DOUBLE_EQ(e.max_abs, 0.2);
  EXPECT_DOUBLE_EQ(e.mean_abs, 0.2 / 4096);
  EXPECT_NEAR(e.rmse, std::sqrt(0.04 / 4096), 1e-12);
  EXPECT_DOUBLE_EQ(e.share_above_threshold, 1.0 / 4096);
  EXPECT_LT(e.ssim, 1.0);
  EXPECT_GT(e.ssim, 0.99);

  // One channel of one RGB pixel: the pixel counts once, the mean is over all 3 channels.
  io::Image8 c = byte_image(10, 10, 3, 50), d = c;
  d.at(3, 4, 1) = 0;
  const ImageError ec = compare(c, d);
  EXPECT_DOUBLE_EQ(ec.max_abs, 50.0 / 255);
  EXPECT_DOUBLE_EQ(ec.mean_abs, 50.0 / 255 / 300);
  EXPECT_DOUBLE_EQ(ec.share_above_threshold, 0.01);
}

TEST(ImageError, ThresholdIsStrict) {
  // One code everywhere: rounding noise, not above the default 1/255 threshold.
  const io::Image8 a = byte_image(8, 8, 4, 200), b = byte_image(8, 8, 4, 201);
  EXPECT_EQ(compare(a, b).share_above_threshold, 0.0);
  EXPECT_EQ(compare(a, b, {.threshold = 0}).share_above_threshold, 1.0);
  EXPECT_EQ(compare(a, byte_image(8, 8, 4, 202)).share_above_threshold, 1.0);
  // Float: the same threshold applies to the value itself.
  const io::ImageF f = float_image(4, 4, 1, 0.5f);
  EXPECT_EQ(compare(f, float_image(4, 4, 1, 0.5f + 0.5f / 255)).share_above_threshold, 0.0);
  EXPECT_EQ(compare(f, float_image(4, 4, 1, 0.5f + 1.5f / 255)).share_above_threshold, 1.0);
}

TEST(ImageError, AlphaIsIgnoredAndLumaWeightsTheChannels) {
  io::Image8 a = byte_image(16, 16, 4, 128), b = a;
  for (std::size_t i = 3; i < b.pixels.size(); i += 4) b.pixels[i] = 0;
  const ImageError alpha_only = compare(a, b);
  EXPECT_EQ(alpha_only.max_abs, 0);
  EXPECT_DOUBLE_EQ(alpha_only.ssim, 1.0);

  // The same change in blue moves the luma less than in green: higher SSIM.
  io::Image8 green = a, blue = a;
  for (int y = 4; y < 12; ++y)
    for (int x = 4; x < 12; ++x) green.at(x, y, 1) = 0, blue.at(x, y, 2) = 0;
  const ImageError eg = compare(a, green), eb = compare(a, blue);
  EXPECT_DOUBLE_EQ(eg.mean_abs, eb.mean_abs);
  EXPECT_GT(eb.ssim, eg.ssim);
}

TEST(ImageError, ExtremesBlackAgainstWhite) {
  const ImageError e = compare(byte_image(32, 32, 3, 0), byte_image(32, 32, 3, 255));
  EXPECT_EQ(e.max_abs, 1.0);
  EXPECT_EQ(e.mean_abs, 1.0);
  EXPECT_EQ(e.psnr_db, 0.0);
  EXPECT_NEAR(e.ssim, ssim_of_constants(0, 255), 1e-9);
  EXPECT_LT(e.ssim, 1e-3);
  EXPECT_EQ(e.share_above_threshold, 1.0);
}

TEST(ImageError, SsimIsSymmetricAndFallsWithNoise) {
  const io::ImageF a = textured(80, 60);
  double previous = 1.0;
  for (float amplitude : {0.01f, 0.05f, 0.2f}) {
    io::ImageF b = a;
    for (std::size_t i = 0; i < b.pixels.size(); ++i) b.pixels[i] += amplitude * ((i * 7919) % 13 < 6 ? 1.0f : -1.0f);
    const ImageError ab = compare(a, b), ba = compare(b, a);
    EXPECT_NEAR(ab.ssim, ba.ssim, 1e-12);
    EXPECT_EQ(ab.max_abs, ba.max_abs);
    EXPECT_LT(ab.ssim, previous) << "amplitude " << amplitude;
    previous = ab.ssim;
  }
}

TEST(ImageError, TinyImagesAreFinite) {
  for (auto [w, h] : {std::pair{1, 1}, std::pair{1, 7}, std::pair{7, 1}, std::pair{2, 2}}) {
    const ImageError same = compare(float_image(w, h, 1, 0.3f), float_image(w, h, 1, 0.3f));
    EXPECT_DOUBLE_EQ(same.ssim, 1.0) << w << "x" << h;
    const ImageError diff = compare(float_image(w, h, 1, 0.3f), float_image(w, h, 1, 0.7f));
    EXPECT_TRUE(std::isfinite(diff.ssim)) << w << "x" << h;
    EXPECT_NEAR(diff.ssim, ssim_of_constants(0.3 * 255, 0.7 * 255), 1e-5) << w << "x" << h;
    EXPECT_NEAR(diff.mean_abs, 0.4, 1e-6);
  }
}

TEST(ImageError, MaskRestrictsEveryMetric) {
  io::ImageF a = float_image(32, 32, 1, 0.5f), b = a;
  for (int x = 0; x < 16; ++x) b.at(x, 5) = 0;  // changes only in the left half
  io::Image8 right = byte_image(32, 32, 1, 0);
  for (int y = 0; y < 32; ++y)
    for (int x = 16; x < 32; ++x) right.at(x, y) = 255;
  const ImageError outside = compare(a, b, {.mask = &right});
  EXPECT_EQ(outside.pixels, 32 * 16);
  EXPECT_EQ(outside.max_abs, 0);
  EXPECT_EQ(outside.share_above_threshold, 0);
  EXPECT_LT(outside.ssim, 1.0) << "windows at the mask's edge see the change next to it";
  EXPECT_GT(outside.ssim, compare(a, b).ssim);

  io::Image8 row5 = byte_image(32, 32, 1, 0);
  for (int x = 0; x < 32; ++x) row5.at(x, 5) = 1;
  const ImageError inside = compare(a, b, {.mask = &row5});
  EXPECT_EQ(inside.pixels, 32);
  EXPECT_DOUBLE_EQ(inside.share_above_threshold, 0.5);
  EXPECT_NEAR(inside.mean_abs, 0.25, 1e-7);
}

TEST(ImageError, BadInputIsRefusedWithOneClearLine) {
  const io::ImageF a = float_image(8, 8, 1, 0);
  EXPECT_THAT(error_of([&] { compare(a, float_image(8, 9, 1, 0)); }), HasSubstr("sizes differ (reference 8×8, test 8×9)"));
  EXPECT_THAT(error_of([&] { compare(a, float_image(8, 8, 2, 0)); }), HasSubstr("channel counts differ"));
  EXPECT_THAT(error_of([&] { compare(io::ImageF{}, io::ImageF{}); }), HasSubstr("reference image is empty"));
  EXPECT_THAT(error_of([&] { compare(a, io::ImageF{}); }), HasSubstr("test image is empty"));
  EXPECT_THAT(error_of([&] { compare(io::Image8{}, io::Image8{}); }), HasSubstr("empty"));
  EXPECT_THAT(error_of([&] { compare(byte_image(4, 4, 2, 0), byte_image(4, 4, 2, 0)); }), HasSubstr("1, 3 or 4 channels"));
  io::ImageF short_buffer = a;
  short_buffer.pixels.pop_back();
  EXPECT_THAT(error_of([&] { compare(a, short_buffer); }), HasSubstr("holds 63 values, expected"));
  io::ImageF nan = a;
  nan.at(3, 2) = std::nanf("");
  EXPECT_THAT(error_of([&] { compare(a, nan); }), HasSubstr("non-finite value at pixel (3, 2)"));
  const io::Image8 bad_mask = byte_image(8, 8, 3, 1);
  EXPECT_THAT(error_of([&] { compare(a, a, {.mask = &bad_mask}); }), HasSubstr("mask must be one channel of 8×8"));
  const io::Image8 empty_mask = byte_image(8, 8, 1, 0);
  EXPECT_THAT(error_of([&] { compare(a, a, {.mask = &empty_mask}); }), HasSubstr("mask selects no pixel"));
  EXPECT_THAT(error_of([&] { compare(a, a, {.threshold = -1}); }), HasSubstr("threshold"));
}

}  // namespace
}  // namespace penumbra::metrics
