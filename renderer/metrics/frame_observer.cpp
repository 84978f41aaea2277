#include "metrics/frame_observer.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "metrics/image_checks.h"

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

// The sum of `m` over a square of side `side` around each pixel, over the pixels inside the image
// only (a window cut by the border holds what it holds, no made-up pixels).
cv::Mat windowed_sum(const cv::Mat& m, int side) {
  cv::Mat sum;
  cv::boxFilter(m, sum, CV_64F, cv::Size(side, side), cv::Point(-1, -1), false, cv::BORDER_CONSTANT);
  return sum;
}

cv::Mat windowed_mean(const cv::Mat& m, int side) { return windowed_sum(m, side) / windowed_sum(cv::Mat::ones(m.size(), CV_64F), side); }

// The reference's windowed sums for one window side: the normal equations of the local
// displacement (gradients g divided by den, like rel) and the count of pixels inside the image.
struct WindowSums {
  int side = 0;
  cv::Mat sxx, sxy, syy, count;
};

WindowSums window_sums(const cv::Mat& gx, const cv::Mat& gy, int side) {
  return {side, windowed_sum(gx.mul(gx), side), windowed_sum(gx.mul(gy), side), windowed_sum(gy.mul(gy), side),
          windowed_sum(cv::Mat::ones(gx.size(), CV_64F), side)};
}

// Per window of side `w.side` around each pixel: the RMS of rel = d / den left after the best local
// displacement t of the reference, d ≈ g·t (least squares, weighted like rel: g and d divided by
// den). What a shift explains is not seen (positions are compared within a window, not across the
// two images); what is left is the change of shape.
cv::Mat residual_rms(const cv::Mat& gx, const cv::Mat& gy, const cv::Mat& d, const WindowSums& w) {
  const cv::Mat bx = windowed_sum(gx.mul(d), w.side), by = windowed_sum(gy.mul(d), w.side), dd = windowed_sum(d.mul(d), w.side);
  cv::Mat out(d.size(), CV_64F);
  for (int y = 0; y < d.rows; ++y)
    for (int x = 0; x < d.cols; ++x) {
      // A small ridge keeps a window without gradient (flat) or with one direction only (a straight
      // edge) solvable: the missing direction then explains nothing.
      const double ridge = 1e-9 * (w.sxx.at<double>(y, x) + w.syy.at<double>(y, x)) + 1e-300;
      const double a = w.sxx.at<double>(y, x) + ridge, b = w.sxy.at<double>(y, x), c = w.syy.at<double>(y, x) + ridge;
      const double u = bx.at<double>(y, x), v = by.at<double>(y, x), det = a * c - b * b;
      const double explained = det > 0 ? (c * u * u - 2 * b * u * v + a * v * v) / det : 0.0;
      out.at<double>(y, x) = std::sqrt(std::max(0.0, dd.at<double>(y, x) - explained) / w.count.at<double>(y, x));
    }
  return out;
}

void check_params(const FrameObserverParams& p) {
  check_param(p.pixels_per_degree, p.pixels_per_degree > 0, "pixels_per_degree", "finite and positive");
  check_param(p.patch_deg, p.patch_deg > 0, "patch_deg", "finite and positive");
  check_param(p.criterion_f, p.criterion_f > 0 && p.criterion_f < 1, "criterion_f", "in (0, 1)");
  check_param(p.blur_sigma_arcmin, p.blur_sigma_arcmin >= 0, "blur_sigma_arcmin", "finite and >= 0");
  check_param(p.window_deg, p.window_deg > 0, "window_deg", "finite and positive");
  check_param(p.pool_arcmin, p.pool_arcmin >= 0, "pool_arcmin", "finite and >= 0");
  check_param(p.window_max_deg, p.window_max_deg > 0, "window_max_deg", "finite and positive");
  check_param(p.contrast_deg, p.contrast_deg > 0, "contrast_deg", "finite and positive");
  check_param(p.contrast_floor, p.contrast_floor > 0, "contrast_floor", "finite and positive");
  check_param(p.black_level, p.black_level > 0, "black_level", "finite and positive");
  check_param(p.weber, p.weber > 0, "weber", "finite and positive");
}

// Linear luminance through the optics' blur.
cv::Mat seen_luminance(const image::ImageF& img, Encoding encoding, const FrameObserverParams& p) {
  cv::Mat y = luminance(img, encoding);
  const double sigma_px = p.blur_sigma_arcmin / 60.0 * p.pixels_per_degree;
  if (sigma_px > 0.05)  // the image observer's cut: below it the blur moves nothing by a visible amount
    cv::GaussianBlur(y, y, cv::Size(0, 0), sigma_px, sigma_px, cv::BORDER_REPLICATE);
  return y;
}

// The signed change pooled over a small neighbourhood before it is squared, as the image
// observer's fit of the edge's position per slice averages the slice's pixels: a change of one
// code value here and there (8-bit rounding of two renders) cancels instead of adding up.
void pool(cv::Mat& m, const FrameObserverParams& p) {
  if (const double pool_px = p.pool_arcmin / 60.0 * p.pixels_per_degree; pool_px > 0.05)
    cv::GaussianBlur(m, m, cv::Size(0, 0), pool_px, pool_px, cv::BORDER_REPLICATE);
}

}  // namespace

double frame_p_correct(double deviation, double weber) { return 0.5 * std::erfc(-deviation / (2.0 * weber)); }

double frame_p_detect(double p_correct) { return std::clamp((p_correct - 0.5) / 0.5, 0.0, 1.0); }

struct ObserverReference::Planes {
  cv::Mat ref;          // blurred luminance
  cv::Mat denominator;  // local contrast + floor
  cv::Mat gx, gy;       // gradients over the denominator, pooled
  std::vector<WindowSums> windows;
};

ObserverReference::ObserverReference(const image::ImageF& reference, Encoding encoding, const FrameObserverParams& params)
    : params_(params), planes_(std::make_unique<Planes>()) {
  check_image(reference, "reference");
  check_params(params);
  const FrameObserverParams& p = params_;
  width_ = reference.width;
  height_ = reference.height;
  Planes& r = *planes_;
  r.ref = seen_luminance(reference, encoding, p);
  // The reference's local contrast: the range of its luminance around the pixel (dilate and erode
  // ignore what lies outside the image), and the floor from its local mean.
  const int contrast_px = odd_side_px(p.contrast_deg, p.pixels_per_degree);
  const cv::Mat square = cv::getStructuringElement(cv::MORPH_RECT, cv::Size(contrast_px, contrast_px));
  cv::Mat high, low;
  cv::dilate(r.ref, high, square);
  cv::erode(r.ref, low, square);
  const cv::Mat mean = windowed_mean(r.ref, contrast_px);
  r.denominator = (high - low) + p.contrast_floor * (mean + p.black_level);
  cv::Sobel(r.ref, r.gx, CV_64F, 1, 0, 1, 0.5, 0, cv::BORDER_REPLICATE);  // central differences, luminance per pixel
  cv::Sobel(r.ref, r.gy, CV_64F, 0, 1, 1, 0.5, 0, cv::BORDER_REPLICATE);
  cv::divide(r.gx, r.denominator, r.gx);
  cv::divide(r.gy, r.denominator, r.gy);
  pool(r.gx, p);
  pool(r.gy, p);
  // Windows from window_deg up to the patch in octaves, the largest residual at each pixel: the
  // window that holds the whole change (a blurred edge's bend spans its penumbra, which the
  // image observer's windows of 0.5 r followed).
  for (double deg = p.window_deg; deg <= std::max(p.window_deg, p.window_max_deg) * 1.0001; deg *= 2)
    r.windows.push_back(window_sums(r.gx, r.gy, odd_side_px(deg, p.pixels_per_degree)));
}

ObserverReference::~ObserverReference() = default;
ObserverReference::ObserverReference(ObserverReference&&) noexcept = default;
ObserverReference& ObserverReference::operator=(ObserverReference&&) noexcept = default;

FrameDetection ObserverReference::judge(const image::ImageF& test, Encoding test_encoding) const {
  check_image(test, "test");
  check_same_size("frame observer", width_, height_, test.width, test.height);
  const FrameObserverParams& p = params_;
  const Planes& r = *planes_;
  const cv::Mat tst = seen_luminance(test, test_encoding, p);
  cv::Mat rel;
  cv::divide(tst - r.ref, r.denominator, rel);
  pool(rel, p);
  cv::Mat rms = cv::Mat::zeros(r.ref.size(), CV_64F);
  for (const WindowSums& w : r.windows) rms = cv::max(rms, residual_rms(r.gx, r.gy, rel, w));

  FrameDetection out;
  out.patch_px = std::max(1, static_cast<int>(std::lround(p.patch_deg * p.pixels_per_degree)));
  out.window_px = odd_side_px(p.window_deg, p.pixels_per_degree);
  out.pixels_per_degree = p.pixels_per_degree;
  out.criterion_f = p.criterion_f;
  out.patches_x = (width_ + out.patch_px - 1) / out.patch_px;
  out.patches_y = (height_ + out.patch_px - 1) / out.patch_px;
  for (int py = 0; py < out.patches_y; ++py)
    for (int px = 0; px < out.patches_x; ++px) {
      PatchDetection patch;
      patch.x_px = px * out.patch_px;
      patch.y_px = py * out.patch_px;
      patch.width_px = std::min(out.patch_px, width_ - patch.x_px);
      patch.height_px = std::min(out.patch_px, height_ - patch.y_px);
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

FrameDetection detect_difference(const image::ImageF& reference, Encoding reference_encoding, const image::ImageF& test,
                                 Encoding test_encoding, const FrameObserverParams& params) {
  check_image(reference, "reference");
  check_image(test, "test");
  check_same_size("frame observer", reference.width, reference.height, test.width, test.height);
  return ObserverReference(reference, reference_encoding, params).judge(test, test_encoding);
}

}  // namespace penumbra::metrics
