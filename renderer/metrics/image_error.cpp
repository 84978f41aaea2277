#include "metrics/image_error.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/quality/qualityssim.hpp>

#include "metrics/image_checks.h"

namespace penumbra::metrics {
namespace {

template <class T>
void check_shape(const io::Image<T>& img, const char* role) {
  if (img.width <= 0 || img.height <= 0 || img.channels <= 0)
    throw std::invalid_argument(std::string("compare: the ") + role + " image is empty (" + std::to_string(img.width) + "×" +
                                std::to_string(img.height) + "×" + std::to_string(img.channels) + ")");
  const std::size_t expected = static_cast<std::size_t>(img.width) * static_cast<std::size_t>(img.height) * static_cast<std::size_t>(img.channels);
  if (img.pixels.size() != expected)
    throw std::invalid_argument(std::string("compare: the ") + role + " image holds " + std::to_string(img.pixels.size()) +
                                " values, expected width × height × channels = " + std::to_string(expected));
}

template <class T>
void check_pair(const io::Image<T>& reference, const io::Image<T>& test, const CompareOptions& options) {
  check_shape(reference, "reference");
  check_shape(test, "test");
  check_same_size("compare", reference.width, reference.height, test.width, test.height);
  if (reference.channels != test.channels)
    throw std::invalid_argument("compare: channel counts differ (reference " + std::to_string(reference.channels) + ", test " +
                                std::to_string(test.channels) + ")");
  if (!(options.threshold >= 0) || !std::isfinite(options.threshold))
    throw std::invalid_argument("compare: threshold must be finite and >= 0, got " + std::to_string(options.threshold));
  if (const io::Image8* m = options.mask) {
    if (m->channels != 1 || m->width != reference.width || m->height != reference.height ||
        m->pixels.size() != static_cast<std::size_t>(m->width) * static_cast<std::size_t>(m->height))
      throw std::invalid_argument("compare: the mask must be one channel of " + std::to_string(reference.width) + "×" +
                                  std::to_string(reference.height) + ", got " + std::to_string(m->width) + "×" +
                                  std::to_string(m->height) + "×" + std::to_string(m->channels));
  }
}

bool selected(const CompareOptions& options, std::size_t pixel) { return !options.mask || options.mask->pixels[pixel] != 0; }

// Differences over the compared channels [0, channels) of each pixel, values scaled by `scale`.
template <class T>
ImageError difference_stats(const io::Image<T>& reference, const io::Image<T>& test, int channels, double scale,
                            const CompareOptions& options) {
  ImageError e;
  e.channels = channels;
  e.threshold = options.threshold;
  double sum = 0, sum_sq = 0;
  std::int64_t above = 0;
  const std::size_t n = static_cast<std::size_t>(reference.width) * static_cast<std::size_t>(reference.height);
  const auto stride = static_cast<std::size_t>(reference.channels);
  for (std::size_t p = 0; p < n; ++p) {
    if (!selected(options, p)) continue;
    ++e.pixels;
    double pixel_max = 0;
    for (int c = 0; c < channels; ++c) {
      // Sums in the stored unit (exact integers for 8-bit images), scaled once at the end.
      const double d = std::abs(static_cast<double>(test.pixels[p * stride + static_cast<std::size_t>(c)]) -
                                static_cast<double>(reference.pixels[p * stride + static_cast<std::size_t>(c)]));
      sum += d;
      sum_sq += d * d;
      pixel_max = std::max(pixel_max, d);
    }
    e.max_abs = std::max(e.max_abs, pixel_max * scale);
    if (pixel_max * scale > options.threshold) ++above;
  }
  if (e.pixels == 0) throw std::invalid_argument("compare: the mask selects no pixel");
  const double values = static_cast<double>(e.pixels) * channels;
  e.mean_abs = sum / values * scale;
  const double mse = sum_sq / values * scale * scale;
  e.rmse = std::sqrt(mse);
  e.psnr_db = mse > 0 ? 10 * std::log10(1 / mse) : std::numeric_limits<double>::infinity();
  e.share_above_threshold = static_cast<double>(above) / static_cast<double>(e.pixels);
  return e;
}

// Mean of the SSIM map of two one-channel CV_32F images on a 0..255 scale, over the mask.
double ssim(const cv::Mat& reference, const cv::Mat& test, const CompareOptions& options) {
  cv::Mat quality_map;
  const cv::Scalar whole = cv::quality::QualitySSIM::compute(reference, test, quality_map);
  if (!options.mask) return whole[0];
  const cv::Mat mask(options.mask->height, options.mask->width, CV_8UC1, const_cast<std::uint8_t*>(options.mask->pixels.data()));
  return cv::mean(quality_map, mask)[0];
}

cv::Mat luma(const io::Image8& img) {
  cv::Mat y(img.height, img.width, CV_32FC1);
  const auto stride = static_cast<std::size_t>(img.channels);
  for (int row = 0; row < img.height; ++row) {
    float* out = y.ptr<float>(row);
    for (int x = 0; x < img.width; ++x) {
      const std::size_t p = (static_cast<std::size_t>(row) * static_cast<std::size_t>(img.width) + static_cast<std::size_t>(x)) * stride;
      out[x] = img.channels == 1 ? static_cast<float>(img.pixels[p])
                                 : 0.299f * img.pixels[p] + 0.587f * img.pixels[p + 1] + 0.114f * img.pixels[p + 2];
    }
  }
  return y;
}

cv::Mat channel_times_255(const io::ImageF& img, int c) {
  cv::Mat m(img.height, img.width, CV_32FC1);
  const auto stride = static_cast<std::size_t>(img.channels);
  for (int row = 0; row < img.height; ++row) {
    float* out = m.ptr<float>(row);
    for (int x = 0; x < img.width; ++x)
      out[x] = 255.0f * img.pixels[(static_cast<std::size_t>(row) * static_cast<std::size_t>(img.width) + static_cast<std::size_t>(x)) * stride +
                                   static_cast<std::size_t>(c)];
  }
  return m;
}

void check_finite(const io::ImageF& img, const char* role) {
  for (std::size_t i = 0; i < img.pixels.size(); ++i) {
    if (std::isfinite(img.pixels[i])) continue;
    const std::size_t pixel = i / static_cast<std::size_t>(img.channels);
    throw std::invalid_argument(std::string("compare: the ") + role + " image has a non-finite value at pixel (" +
                                std::to_string(pixel % static_cast<std::size_t>(img.width)) + ", " +
                                std::to_string(pixel / static_cast<std::size_t>(img.width)) + ") channel " +
                                std::to_string(i % static_cast<std::size_t>(img.channels)));
  }
}

}  // namespace

ImageError compare(const io::Image8& reference, const io::Image8& test, const CompareOptions& options) {
  check_pair(reference, test, options);
  if (reference.channels != 1 && reference.channels != 3 && reference.channels != 4)
    throw std::invalid_argument("compare: 8-bit images need 1, 3 or 4 channels, got " + std::to_string(reference.channels));
  const int channels = reference.channels == 1 ? 1 : 3;
  ImageError e = difference_stats(reference, test, channels, 1.0 / 255.0, options);
  e.ssim = ssim(luma(reference), luma(test), options);
  return e;
}

ImageError compare(const io::ImageF& reference, const io::ImageF& test, const CompareOptions& options) {
  check_pair(reference, test, options);
  check_finite(reference, "reference");
  check_finite(test, "test");
  ImageError e = difference_stats(reference, test, reference.channels, 1.0, options);
  double sum = 0;
  for (int c = 0; c < reference.channels; ++c) sum += ssim(channel_times_255(reference, c), channel_times_255(test, c), options);
  e.ssim = sum / reference.channels;
  return e;
}

// Hand-written: psnr_db is infinite for identical images, and JSON has no infinity (null).
nlohmann::json to_json(const ImageError& e) {
  return {{"pixels", e.pixels},
          {"channels", e.channels},
          {"max_abs", e.max_abs},
          {"mean_abs", e.mean_abs},
          {"rmse", e.rmse},
          {"psnr_db", std::isfinite(e.psnr_db) ? nlohmann::json(e.psnr_db) : nlohmann::json(nullptr)},
          {"ssim", e.ssim},
          {"threshold", e.threshold},
          {"share_above_threshold", e.share_above_threshold}};
}

}  // namespace penumbra::metrics
