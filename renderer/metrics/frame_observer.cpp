#include "metrics/frame_observer.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

namespace penumbra::metrics {
namespace {

double srgb_to_linear(double v) { return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4); }

void check_image(const image::ImageF& img, const char* role) {
  const std::string what = std::string("frame observer: the ") + role + " image ";
  if (img.width <= 0 || img.height <= 0)
    throw std::invalid_argument(what + "is empty (" + std::to_string(img.width) + "×" + std::to_string(img.height) + ")");
  if (img.channels < 1 || img.channels > 4)
    throw std::invalid_argument(what + "has " + std::to_string(img.channels) +
                                " channels; expected 1 (grey), 2 (grey, alpha), 3 (RGB) or 4 (RGBA)");
  const std::size_t expected = static_cast<std::size_t>(img.width) * static_cast<std::size_t>(img.height) * static_cast<std::size_t>(img.channels);
  if (img.pixels.size() != expected)
    throw std::invalid_argument(what + "holds " + std::to_string(img.pixels.size()) + " values, expected width × height × channels = " +
                                std::to_string(expected));
  for (std::size_t i = 0; i < img.pixels.size(); ++i)
    if (!std::isfinite(img.pixels[i])) {
      const std::size_t p = i / static_cast<std::size_t>(img.channels);
      throw std::invalid_argument(what + "has a non-finite value at pixel (" + std::to_string(p % static_cast<std::size_t>(img.width)) +
                                  ", " + std::to_string(p / static_cast<std::size_t>(img.width)) + ")");
    }
}

void check_param(double value, bool ok, const char* name, const char* range) {
  if (!ok || !std::isfinite(value))
    throw std::invalid_argument(std::string("frame observer: ") + name + " must be " + range + ", got " + std::to_string(value));
}

// Linear luminance (white = 1) of the displayed values, clamped to [0, 1] like LDR-FLIP's input.
cv::Mat luminance(const image::ImageF& img, Encoding encoding) {
  cv::Mat out(img.height, img.width, CV_64F);
  const bool grey = img.channels < 3;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      double rgb[3];
      for (int c = 0; c < 3; ++c) {
        const double v = std::clamp(static_cast<double>(img.at(x, y, grey ? 0 : c)), 0.0, 1.0);
        rgb[c] = encoding == Encoding::srgb ? srgb_to_linear(v) : v;
      }
      out.at<double>(y, x) = grey ? rgb[0] : 0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2];
    }
  return out;
}

// An odd side of about `deg` degrees, at least one pixel: windows centred on their pixel.
int odd_side_px(double deg, double ppd) {
  const int px = std::max(1, static_cast<int>(std::lround(deg * ppd)));
  return px % 2 ? px : px + 1;
}

// The mean of `m` over a square of side `side` around each pixel, over the pixels inside the image
// only (a window cut by the border is the mean of what it holds, not of made-up pixels).
cv::Mat windowed_mean(const cv::Mat& m, int side) {
  cv::Mat sum, count;
  const cv::Mat ones = cv::Mat::ones(m.size(), CV_64F);
  cv::boxFilter(m, sum, CV_64F, cv::Size(side, side), cv::Point(-1, -1), false, cv::BORDER_CONSTANT);
  cv::boxFilter(ones, count, CV_64F, cv::Size(side, side), cv::Point(-1, -1), false, cv::BORDER_CONSTANT);
  return sum / count;
}

}  // namespace

double frame_p_correct(double deviation, double weber) { return 0.5 * std::erfc(-deviation / (2.0 * weber)); }

double frame_p_detect(double p_correct) { return std::clamp((p_correct - 0.5) / 0.5, 0.0, 1.0); }

FrameDetection detect_difference(const image::ImageF& reference, Encoding reference_encoding, const image::ImageF& test,
                                 Encoding test_encoding, const FrameObserverParams& params) {
  check_image(reference, "reference");
  check_image(test, "test");
  if (reference.width != test.width || reference.height != test.height)
    throw std::invalid_argument("frame observer: image sizes differ (reference " + std::to_string(reference.width) + "×" +
                                std::to_string(reference.height) + ", test " + std::to_string(test.width) + "×" +
                                std::to_string(test.height) + ")");
  const FrameObserverParams& p = params;
  check_param(p.pixels_per_degree, p.pixels_per_degree > 0, "pixels_per_degree", "finite and positive");
  check_param(p.patch_deg, p.patch_deg > 0, "patch_deg", "finite and positive");
  check_param(p.criterion_f, p.criterion_f > 0 && p.criterion_f < 1, "criterion_f", "in (0, 1)");
  check_param(p.blur_sigma_arcmin, p.blur_sigma_arcmin >= 0, "blur_sigma_arcmin", "finite and >= 0");
  check_param(p.window_deg, p.window_deg > 0, "window_deg", "finite and positive");
  check_param(p.contrast_deg, p.contrast_deg > 0, "contrast_deg", "finite and positive");
  check_param(p.contrast_floor, p.contrast_floor > 0, "contrast_floor", "finite and positive");
  check_param(p.black_level, p.black_level > 0, "black_level", "finite and positive");
  check_param(p.weber, p.weber > 0, "weber", "finite and positive");

  cv::Mat ref = luminance(reference, reference_encoding), tst = luminance(test, test_encoding);
  const double sigma_px = p.blur_sigma_arcmin / 60.0 * p.pixels_per_degree;
  if (sigma_px > 0.05) {  // the image observer's cut: below it the blur moves nothing by a visible amount
    cv::GaussianBlur(ref, ref, cv::Size(0, 0), sigma_px, sigma_px, cv::BORDER_REPLICATE);
    cv::GaussianBlur(tst, tst, cv::Size(0, 0), sigma_px, sigma_px, cv::BORDER_REPLICATE);
  }
  // The reference's local contrast: the range of its luminance around the pixel (dilate and erode
  // ignore what lies outside the image), and the floor from its local mean.
  const int contrast_px = odd_side_px(p.contrast_deg, p.pixels_per_degree);
  const cv::Mat square = cv::getStructuringElement(cv::MORPH_RECT, cv::Size(contrast_px, contrast_px));
  cv::Mat high, low;
  cv::dilate(ref, high, square);
  cv::erode(ref, low, square);
  const cv::Mat mean = windowed_mean(ref, contrast_px);
  const cv::Mat denominator = (high - low) + p.contrast_floor * (mean + p.black_level);
  cv::Mat rel;
  cv::divide(tst - ref, denominator, rel);
  const int window_px = odd_side_px(p.window_deg, p.pixels_per_degree);
  cv::Mat rms;
  cv::sqrt(windowed_mean(rel.mul(rel), window_px), rms);

  FrameDetection out;
  out.patch_px = std::max(1, static_cast<int>(std::lround(p.patch_deg * p.pixels_per_degree)));
  out.window_px = window_px;
  out.pixels_per_degree = p.pixels_per_degree;
  out.criterion_f = p.criterion_f;
  out.patches_x = (reference.width + out.patch_px - 1) / out.patch_px;
  out.patches_y = (reference.height + out.patch_px - 1) / out.patch_px;
  for (int py = 0; py < out.patches_y; ++py)
    for (int px = 0; px < out.patches_x; ++px) {
      PatchDetection patch;
      patch.x_px = px * out.patch_px;
      patch.y_px = py * out.patch_px;
      patch.width_px = std::min(out.patch_px, reference.width - patch.x_px);
      patch.height_px = std::min(out.patch_px, reference.height - patch.y_px);
      double worst = 0;
      cv::minMaxLoc(rms(cv::Rect(patch.x_px, patch.y_px, patch.width_px, patch.height_px)), nullptr, &worst);
      patch.deviation = worst;
      patch.p_correct = frame_p_correct(worst, p.weber);
      patch.p_detect = frame_p_detect(patch.p_correct);
      out.deviation_max = std::max(out.deviation_max, patch.deviation);
      out.p_detect_max = std::max(out.p_detect_max, patch.p_detect);
      if (patch.p_detect > p.criterion_f) ++out.patches_visible;
      out.patches.push_back(patch);
    }
  out.visible = out.patches_visible > 0;
  return out;
}

}  // namespace penumbra::metrics
