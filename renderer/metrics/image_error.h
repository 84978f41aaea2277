#pragma once
// Image error between a reference and a test image of the same size: max / mean absolute
// difference, RMSE, PSNR, SSIM (OpenCV's quality module) and the share of pixels that differ by
// more than a threshold, optionally inside a mask.
//
// Value scale: every difference is reported in normalized units, so 8-bit and float images read
// the same way: an 8-bit code value counts 1/255, a float (visibility) value counts as stored
// (visibility is in [0, 1]).
//
// Channels compared:
//   Image8 (sRGB-encoded): 1 channel, or R, G, B of 3- and 4-channel images (alpha is ignored).
//   ImageF: every channel.
// A pixel counts toward `share_above_threshold` when any compared channel differs by strictly
// more than `threshold` (with the default 1/255, a one-code 8-bit difference does not count).
//
// SSIM (Wang et al. 2004, as cv::quality::QualitySSIM: 11×11 Gaussian window, σ = 1.5, reflected
// borders, C1 = (0.01·255)², C2 = (0.03·255)²), so the values must lie on a 0..255 scale:
//   Image8: on the luma Y' = 0.299 R' + 0.587 G' + 0.114 B' of the sRGB-encoded values (0..255,
//           computed in float, not rounded), the signal SSIM was designed and validated on;
//   ImageF: each channel times 255 (dynamic range 1 for visibility), the mean over channels.
// With a mask, SSIM is the mean of the SSIM map over the masked pixels (the windows still see
// their unmasked neighbours).
#include <cstdint>
#include <limits>

#include <nlohmann/json_fwd.hpp>

#include "io/image_io.h"

namespace penumbra::metrics {

struct ImageError {
  std::int64_t pixels = 0;  // pixels compared (inside the mask)
  int channels = 0;         // channels compared per pixel
  double max_abs = 0;       // largest |test − reference| over compared pixels and channels
  double mean_abs = 0;      // mean |test − reference| over compared pixels and channels
  double rmse = 0;          // root of the mean squared difference, same set
  double psnr_db = std::numeric_limits<double>::infinity();  // 10 log10(1 / mse), peak 1; +inf when identical
  double ssim = 1;          // see the header comment; 1 when identical
  double threshold = 0;     // the threshold used for share_above_threshold
  double share_above_threshold = 0;  // fraction of compared pixels with a channel differing by > threshold
};

struct CompareOptions {
  double threshold = 1.0 / 255.0;     // normalized units; must be >= 0
  const io::Image8* mask = nullptr;   // one channel, the images' size; non-zero pixels are compared
};

// Throw std::invalid_argument with one line naming what is wrong: an empty image, different
// sizes or channel counts, an unsupported channel count, a malformed pixel buffer, a non-finite
// float value (naming the pixel), a bad mask, a mask that selects nothing, a negative threshold.
ImageError compare(const io::Image8& reference, const io::Image8& test, const CompareOptions& options = {});
ImageError compare(const io::ImageF& reference, const io::ImageF& test, const CompareOptions& options = {});

// {"pixels", "channels", "max_abs", "mean_abs", "rmse", "psnr_db" (null when infinite), "ssim",
//  "threshold", "share_above_threshold"}.
nlohmann::json to_json(const ImageError& e);

}  // namespace penumbra::metrics
