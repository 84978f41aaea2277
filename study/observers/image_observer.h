#pragma once
// An observer that answers a 2AFC trial from the two images actually shown, the way a careful eye
// might: it sees the 8-bit display values (decoded to luminance through the display's transfer
// function), optionally blurred by the eye's optics (Gaussian, sigma in arcmin at the display's
// pixels per degree), with independent Gaussian internal noise per pixel. It knows the edge's
// direction, fits the best straight filtered edge (offset only) to each image, and calls the
// image with the larger residual energy the jagged one.
#include <cstdint>

#include "io/image_io.h"
#include "observers/random.h"
#include "stimuli/stimulus.h"

namespace penumbra::observers {

struct ImageObserverParams {
  double noise_sd = 0.1;            // internal noise per pixel, linear luminance (white = 1)
  double blur_sigma_arcmin = 0.0;   // optical blur; 0 = none
  double pixels_per_degree = 60.0;  // display geometry, for the blur
};

class ImageObserver {
 public:
  ImageObserver(ImageObserverParams params, std::uint64_t seed) : params_(params), random_(seed) {}
  // True when the observer judges `first` to be the jagged one. Both images show the same edge
  // (same geometry and radius); `spec` is what was drawn.
  bool first_is_jagged(const io::Image8& first, const io::Image8& second, const stimuli::StimulusSpec& spec,
                       const stimuli::Geometry& geometry);
  // Residual energy of one image against its best straight edge (no noise): the signal the noise hides.
  double straightness_residual(const io::Image8& image, const stimuli::StimulusSpec& spec,
                               const stimuli::Geometry& geometry, bool add_noise);

 private:
  ImageObserverParams params_;
  Random random_;
};

}  // namespace penumbra::observers
