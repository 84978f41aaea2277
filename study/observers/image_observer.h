#pragma once
// An observer that answers from the images actually shown, the way a careful eye might: it sees
// the 8-bit display values (decoded to luminance through the display's transfer function),
// optionally blurred by the eye's optics (Gaussian, sigma in arcmin at the display's pixels per
// degree), with independent Gaussian internal noise per pixel. It knows the edge's direction.
//
// Two criteria:
//  - local (default): it traces the edge's position along its length (the offset of the best
//    straight filtered edge fitted to each 1-px slice across the edge: the iso-contour), and asks
//    how far that trace departs from a straight line *locally*: the RMS deviation from the best
//    line within windows `window_r` filter radii long, the largest over the edge, relative to the
//    filter radius (position judgements of blurred edges scale with the blur: Weber's law). The
//    decision adds Gaussian noise of sd `weber` to that relative deviation. A single step that
//    shifts the whole edge by a fraction of a texel is then seen by its bend, not by the shift.
//  - global: one straight edge fitted to the whole image; the residual energy decides. It sees
//    the sub-step shift of the *step* pattern that people do not (kept for comparison).
#include <cstdint>
#include <vector>

#include "io/image_io.h"
#include "sampling/random.h"
#include "stimuli/stimulus.h"

namespace penumbra::observers {

enum class StraightnessCriterion { local, global };

struct ImageObserverParams {
  double noise_sd = 0.0;            // internal noise per pixel, linear luminance (white = 1)
  double blur_sigma_arcmin = 0.0;   // optical blur; 0 = none
  double pixels_per_degree = 60.0;  // display geometry, for the blur
  StraightnessCriterion criterion = StraightnessCriterion::local;
  // local: window length along the edge in filter radii (at least 4 px), and the decision noise
  // (sd of the relative deviation). Chosen once, on the step (docs/study.md): `weber` was set so
  // that the step's threshold lands near the published 3.47 a at a = 10, so the step's closeness
  // to 3.47 is partly built in. penumbra-observer-fit fits it properly (0.00280 for the step's 3.47
  // over 8 radius grids; 0.003 gives 3.21 there) and holds the stair out: 2.08 against people's
  // 2.5, -17 %; fitted to the stair instead, the step comes out +9.5 % (docs/study.md, "The
  // observer against people"). The default stays 0.003: predicted.json was made with it.
  double window_r = 0.5;
  double weber = 0.003;
  double false_alarm = 0.05;        // yes/no: rate of "jagged" for a straight edge
};

class ImageObserver {
 public:
  ImageObserver(ImageObserverParams params, std::uint64_t seed) : params_(params), random_(seed) {}
  // 2afc: true when the observer judges `first` to be the jagged one. Both images show the same
  // edge (same geometry and radius); `spec` is what was drawn.
  bool first_is_jagged(const io::Image8& first, const io::Image8& second, const stimuli::StimulusSpec& spec,
                       const stimuli::Geometry& geometry);
  // yes/no: true when the observer judges the one image jagged ("the original was not straight").
  // The criterion is set for the false-alarm rate: a straight edge exceeds it with probability
  // `false_alarm` (local criterion only).
  bool judges_jagged(const io::Image8& image, const stimuli::StimulusSpec& spec, const stimuli::Geometry& geometry);

  // The criteria's signals without decision noise (`add_noise` adds the per-pixel noise):
  // global: residual energy against the best straight edge (luminance^2 summed over the band);
  double straightness_residual(const io::Image8& image, const stimuli::StimulusSpec& spec,
                               const stimuli::Geometry& geometry, bool add_noise);
  // local: the largest windowed RMS deviation of the traced edge from straight, over the radius.
  double local_deviation(const io::Image8& image, const stimuli::StimulusSpec& spec,
                         const stimuli::Geometry& geometry, bool add_noise);
  // The traced edge: perpendicular offset (px) of the edge per 1-px slice along it, for the slices
  // that cross the whole band around the edge.
  std::vector<double> edge_trace(const io::Image8& image, const stimuli::StimulusSpec& spec,
                                 const stimuli::Geometry& geometry, bool add_noise);

 private:
  struct Sample {
    double s;  // along the edge (px)
    double v;  // across the edge (px, signed perpendicular distance; lit side positive)
    double luminance;
  };
  std::vector<Sample> band_samples(const io::Image8& image, const stimuli::StimulusSpec& spec,
                                   const stimuli::Geometry& geometry, bool add_noise);
  double decision(const io::Image8& image, const stimuli::StimulusSpec& spec, const stimuli::Geometry& geometry);

  ImageObserverParams params_;
  sampling::Random random_;
};

}  // namespace penumbra::observers
