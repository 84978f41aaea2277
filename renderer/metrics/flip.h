#pragma once
// LDR-FLIP, the perceptual difference between two low-dynamic-range images as a person flipping
// between them sees it: Andersson, Nilsson, Akenine-Möller, Oskarsson, Åström, Fairchild, "FLIP: A
// Difference Evaluator for Alternating Images", Proc. ACM Comput. Graph. Interact. Tech. 3(2), 15
// (HPG 2020). Constants and the order of the steps follow the paper and the authors' reference
// implementation (github.com/NVlabs/flip, v1.6: its separable filters); this is our own code.
//
// Per pixel, in [0, 1] (0: no visible difference):
//   colour   sRGB → linear RGB → YCxCz; each opponent channel blurred by its contrast-sensitivity
//            Gaussian(s), sized in degrees (so by pixels per degree); back to linear RGB, clamped
//            to [0, 1]; CIE L*a*b* (D65), Hunt-adjusted (a, b scaled by L/100); HyAB distance
//            |ΔL| + ‖Δ(a, b)‖, raised to q_c = 0.7 and remapped to [0, 1] with c_max (the HyAB^q_c of
//            green against blue), p_c = 0.4, p_t = 0.95: ΔE_c
//   features edges (1st) and points (2nd Gaussian derivative, σ = w/2 degrees, w = 0.082°) of the
//            normalized luminance Y/Y_n; ΔE_f = (max(|Δ‖edge‖|, |Δ‖point‖|) / √2)^q_f, q_f = 0.5
//   FLIP     ΔE_c^(1 − ΔE_f)
// Borders repeat the edge pixels (as the reference implementation does).
//
// GL-free: OpenCV and the CPU images of common/image only (the library penumbra_flip); files are
// read and written by the caller (renderer/io/image_io.h). docs/compare.md.
#include <cstdint>
#include <vector>

#include "image/image.h"

namespace penumbra::metrics {

// The published constants (the paper's, as the reference implementation's FLIP.h v1.6 states
// them). The contrast-sensitivity Gaussians are a·√(π/b)·exp(−π²x²/b), x in degrees, one for the
// achromatic and red-green channels, the sum of two for blue-yellow.
struct FlipConstants {
  static constexpr double qc = 0.7;    // exponent of the HyAB distance
  static constexpr double pc = 0.4;    // share of c_max below which errors are spread over [0, p_t]
  static constexpr double pt = 0.95;   // where p_c·c_max lands
  static constexpr double qf = 0.5;    // exponent of the feature difference
  static constexpr double w_deg = 0.082;  // peak-to-trough width of the edge detector, degrees (σ = w/2)
  static constexpr double a1[3] = {1.0, 1.0, 34.1};
  static constexpr double b1[3] = {0.0047, 0.0053, 0.04};
  static constexpr double a2[3] = {0.0, 0.0, 13.5};
  static constexpr double b2[3] = {1.0e-5, 1.0e-5, 0.025};
};

// FLIP's default viewer: a 0.7 m wide 3840-pixel monitor seen from 0.7 m, π/180 · 3840 ≈ 67.02
// pixels per degree (the reference tool's default and the viewing of its published results).
inline constexpr double kFlipDefaultPixelsPerDegree = 3840.0 * 3.14159265358979323846 / 180.0;

// Pixels in the central degree of a display `width_px` pixels and `width_m` wide seen from
// `distance_m`: 2·d·tan(0.5°)·width_px/width_m (the study's Display::pixels_per_degree). FLIP's own
// tool uses the small-angle d·(π/180)·width_px/width_m, 0.0025 % less. Throws
// std::invalid_argument unless all three are finite and positive.
double pixels_per_degree(double width_px, double width_m, double distance_m);

// How an image's values encode light: sRGB code values in [0, 1] (PNG) or linear RGB (EXR; values
// are clamped to [0, 1] first, LDR-FLIP has no tone mapping).
enum class Encoding { srgb, linear };

struct FlipOptions {
  double pixels_per_degree = kFlipDefaultPixelsPerDegree;  // > 0
  double threshold = 0.05;  // share_above counts pixels with FLIP strictly above this, in [0, 1]
};

// Pooled values of a FLIP map. The weighted median and quartiles are FLIP's: each pixel weighs as
// much as its own value, so the weighted median is the smallest value v such that the pixels of
// value <= v carry more than half of the map's total error (the reference tool's
// getPercentile(p, weighted)). A map of zeros has them all 0.
struct FlipPooled {
  std::int64_t pixels = 0;
  double mean = 0;
  double weighted_median = 0;
  double weighted_q1 = 0;  // 1st weighted quartile (25 % of the total error)
  double weighted_q3 = 0;  // 3rd weighted quartile
  double min = 0;
  double max = 0;
  double threshold = 0.05;
  double share_above = 0;  // fraction of pixels with FLIP > threshold
};

struct FlipResult {
  image::ImageF map;        // one channel, the images' size, values in [0, 1], top row first
  double pixels_per_degree = 0;
  FlipPooled pooled;
};

// LDR-FLIP of `test` against `reference`: same width and height, 1 (grey), 2 (grey, alpha), 3 (RGB)
// or 4 (RGBA) channels each; alpha is ignored. Throws std::invalid_argument with one line naming
// what is wrong: an empty or malformed image, different sizes, an unsupported channel count, a
// non-finite value (naming the pixel), pixels_per_degree or threshold out of range.
FlipResult ldr_flip(const image::ImageF& reference, Encoding reference_encoding, const image::ImageF& test, Encoding test_encoding,
                    const FlipOptions& options = {});

// The reference's half of LDR-FLIP, computed once: its filtered colours (Hunt-adjusted L*a*b*) and
// its edge and point strengths. Comparing n test images against one reference costs n + 1 image
// preparations instead of 2n, with the same values to the bit as ldr_flip on each pair. Throws like
// ldr_flip for a bad reference or options.
class FlipReference {
 public:
  FlipReference(const image::ImageF& reference, Encoding encoding, const FlipOptions& options = {});

  int width() const { return width_; }
  int height() const { return height_; }
  const FlipOptions& options() const { return options_; }

  // Throws like ldr_flip for a bad test image or one of another size.
  FlipResult compare(const image::ImageF& test, Encoding test_encoding) const;

 private:
  int width_ = 0, height_ = 0;
  FlipOptions options_;
  std::vector<double> lab_;  // 3 per pixel, row by row from the top
  std::vector<float> edge_, point_;
};

// The pooled values of any one-channel map (FLIP's or another's in [0, 1]).
FlipPooled pool_flip(const image::ImageF& map, double threshold);

// The map as FLIP shows it: each value v in [0, 1] through matplotlib's magma colour map (256
// entries, entry round(255·v)), 3-channel sRGB.
image::Image8 flip_magma(const image::ImageF& map);

}  // namespace penumbra::metrics
