#pragma once
// The study's image observer (study/observers/image_observer.h) generalized from a known straight
// edge to any frame with its reference: the probability that a participant of the 2AFC study, shown
// the frame and its reference ("which one is the reference?"), picks the reference out, per patch
// of a few degrees and for the frame. A model of an observer, calibrated on the study's step
// stimulus against the image observer; it has never been compared with people on frames
// (docs/compare.md, docs/results/frame-observer.md).
//
// The image observer's ingredients, with the meaning of its parameters kept:
//   luminance  the displayed values decoded to linear luminance Y (sRGB for PNG, linear for EXR;
//              Rec. 709 weights for colour), values clamped to [0, 1] (white = 1);
//   optics     a Gaussian blur of sigma `blur_sigma_arcmin` at `pixels_per_degree`, on both images;
//   position   an edge displaced by δ with penumbra width w is judged by δ/w (Weber's law for the
//              position of blurred edges). Without knowing where the edges are: a displacement δ of
//              an edge of contrast C and width w changes the luminance by ΔY ≈ C·δ/w, so
//                rel = (Y_test − Y_ref) / (C_ref + floor)
//              with C_ref the reference's local contrast, the range (max − min) of its blurred
//              luminance in a square of side `contrast_deg` around the pixel (an edge's whole
//              contrast as long as its penumbra is narrower than that), and
//                floor = contrast_floor · (local mean of Y_ref + black_level).
//              Where the reference has no edge (C_ref ≈ 0) a change is then a luminance contrast
//              against the surround (Weber's law for luminance), and a dark region is seen against
//              the display's black and flare; without it rel would divide by ~0 in flat regions.
//              contrast_floor = 0.25 is set so that a uniform change of 1 % of the surround's
//              luminance (the classic Weber fraction for fields of a fraction of a degree and more)
//              reaches the criterion (82 % correct) with the calibrated weber: 0.01 / 0.25 = 0.04 ≈
//              1.29·weber. Both terms scale with the light, so a frame and its reference both dimmed
//              by one factor give the same rel (the study's full and half contrast alike);
//   slices     the image observer fits the edge's position per 1-px slice across the edge, which
//              averages the slice's pixels: here the signed rel is pooled by a Gaussian of sigma
//              `pool_arcmin` before it is squared, so that 8-bit rounding that differs from pixel to
//              pixel between two renders cancels instead of adding up;
//   windows    the image observer removes the best straight line from the trace in each window (a
//              shift of the whole edge is not a bend). Here, in each square window, the part of rel
//              explained by a displacement of the reference (rel ≈ (∇Y_ref / den)·t, least squares)
//              is removed and the RMS of the rest is the window's deviation: positions are compared
//              within a window, not across the two images shown side by side, so a shadow that
//              moves as a whole is not seen, one that moves against its occluder or bends is.
//              The image observer's windows are 0.5 filter radii long, so they grow with the blur;
//              here windows of `window_deg`, twice that, ... up to `window_max_deg` are tried at
//              every pixel and the largest deviation is kept (a bend is seen at the scale that holds
//              it: the step's bend at a = 20 px and r = 3.5 a spans about 3.7° at 38.2 px/deg, so
//              the windows and the contrast's square reach 4°; with 2° the step's threshold at a = 20
//              came out twice the one at a = 10). The largest window deviation whose centre lies in
//              a patch is the patch's, so a patch sees up to half the largest window beyond itself;
//   decision   Gaussian decision noise of sd `weber` on each look. The reference's own deviation is
//              0, so the 2AFC p_correct = Φ(deviation / (√2·weber)), and the guess-corrected
//              p_detect = (p_correct − 0.5) / 0.5 in [0, 1], the scale of a calibration entry's
//              threshold.criterion_f.
// weber was chosen once, on the study's step at a = 10 px (PCF disk, full contrast, the study's
// display: 38.2 px/deg, blur 1 arcmin): the frame observer's threshold there equals the image
// observer's (3.43 a on the same radii). The stair, the other artifact sizes, the half contrast and
// other kernels are a validation it was not fitted to, and it has never been compared with people
// on frames: docs/results/frame-observer.md, docs/compare.md.
//
// GL-free (OpenCV and the CPU images of common/image; library penumbra_frame_observer).
#include <memory>
#include <vector>

#include "image/image.h"
#include "metrics/flip.h"

namespace penumbra::metrics {

// The study's default display (data/studies/default.json): 1.57 arcmin per pixel.
inline constexpr double kStudyPixelsPerDegree = 38.2;
// 2AFC detection probability at 82 % correct with QUEST's delta 0.01: adaptive::ThresholdDefinition's
// default, the criterion of the image observer's predictions.
inline constexpr double kStudyCriterionF = 0.6465;

struct FrameObserverParams {
  double pixels_per_degree = kStudyPixelsPerDegree;  // > 0
  double patch_deg = 2.0;                            // side of the square patches, degrees
  double criterion_f = kStudyCriterionF;             // "visible": some patch's p_detect above this, in (0, 1)
  double blur_sigma_arcmin = 1.0;                    // optical blur (the image observer's default); 0 = none
  double window_deg = 0.25;                          // side of the smallest RMS window, degrees
  double pool_arcmin = 1.5;                          // signed change pooled by a Gaussian of this sigma before the windows
  double window_max_deg = 4.0;                       // the largest, degrees: windows from window_deg up to it in octaves
  double contrast_deg = 4.0;                         // side of the square whose luminance range is the local contrast
  double contrast_floor = 0.25;                      // floor of the local contrast, a fraction of the local mean luminance
  double black_level = 0.01;                         // the display's black and flare, fraction of white, > 0
  double weber = 0.0304;                             // decision noise sd, relative deviation
};

struct PatchDetection {
  int x_px = 0, y_px = 0, width_px = 0, height_px = 0;  // top-left corner (top row first) and size
  double deviation = 0;  // largest windowed RMS of rel with its centre in the patch
  double p_correct = 0.5;
  double p_detect = 0;
};

struct FrameDetection {
  std::vector<PatchDetection> patches;  // row by row from the top left; edge patches are cut to the frame
  int patches_x = 0, patches_y = 0;
  int patch_px = 0;   // a whole patch's side, pixels
  int window_px = 0;  // an RMS window's side, pixels
  double pixels_per_degree = 0;
  double deviation_max = 0;  // the largest patch deviation
  double p_detect_max = 0;   // the largest patch p_detect: the frame's detection probability
  int patches_visible = 0;   // patches with p_detect > criterion_f
  double criterion_f = 0;
  bool visible = false;      // patches_visible > 0
};

// 2AFC p_correct for a deviation seen against a reference of deviation 0: Φ(deviation / (√2·weber)).
double frame_p_correct(double deviation, double weber);
// Guess-corrected: (p_correct − 0.5) / 0.5, clamped to [0, 1].
double frame_p_detect(double p_correct);

// The observer on `test` against `reference`: same width and height, 1 to 4 channels each (alpha
// ignored). Throws std::invalid_argument with one line naming what is wrong: an empty or malformed
// image, different sizes, an unsupported channel count, a non-finite value, a parameter out of range.
FrameDetection detect_difference(const image::ImageF& reference, Encoding reference_encoding, const image::ImageF& test,
                                 Encoding test_encoding, const FrameObserverParams& params = {});

// The reference's half of the observer, computed once: its blurred luminance, local contrast,
// gradients and their windowed sums. Judging n frames against one reference then prepares n + 1
// images instead of 2n, with the same values to the bit as detect_difference on each pair. Throws
// like detect_difference for a bad reference or parameter.
class ObserverReference {
 public:
  ObserverReference(const image::ImageF& reference, Encoding encoding, const FrameObserverParams& params = {});
  ~ObserverReference();
  ObserverReference(ObserverReference&&) noexcept;
  ObserverReference& operator=(ObserverReference&&) noexcept;

  const FrameObserverParams& params() const { return params_; }

  // Throws like detect_difference for a bad test image or one of another size.
  FrameDetection judge(const image::ImageF& test, Encoding test_encoding) const;

 private:
  struct Planes;
  FrameObserverParams params_;
  int width_ = 0, height_ = 0;
  std::unique_ptr<Planes> planes_;  // OpenCV matrices, kept out of this header
};

}  // namespace penumbra::metrics
