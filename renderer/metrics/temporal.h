#pragma once
// Temporal stability of shadows along a camera path: how much the light visibility of a surface
// point changes from one frame to the next although neither the point nor the light moved.
//
// Each pixel p of frame t shows the world point X (SurfaceProbe). X is projected with frame t−1's
// camera; where it lands on the same object, on a continuous patch of surface (the four pixels
// around the landing point lie within a few pixel spacings of X: no occlusion edge, no
// disocclusion), frame t−1's visibility is interpolated there bilinearly and compared with
// frame t's. The lights must not move between the two frames (the paths here move the camera
// only), so every matched change is the shadow's own: cascades sliding under the texel grid,
// resolutions changing, cascade bands moving.
//
// Floor: bilinear interpolation of frame t−1 is exact where visibility is linear across a pixel,
// not across hard edges narrower than a pixel, so a general camera move measures a small floor
// even for a shadow that is fixed in the world. A camera that moves by whole pixels parallel to
// an orthographic image plane lands on pixel centres and measures exactly zero for such a shadow
// (tested). penumbra-demo measures the floor of its path with a world-fixed map (one unfitted map,
// which does not depend on the camera) and reports it beside every configuration.
#include <cstdint>

#include <glm/glm.hpp>

#include "io/image_io.h"

namespace penumbra::metrics {

// One frame as the flicker measure needs it.
struct FrameSample {
  const io::ImageF* visibility = nullptr;  // one channel, top-down rows (Renderer::read_visibility)
  const io::ImageF* surface = nullptr;     // SurfaceProbe::render of the same camera and size
  glm::mat4 view_projection{1};            // camera_view_projection of that camera
};

struct FlickerOptions {
  double changed_threshold = 1.0 / 255.0;  // a matched pixel "changed" when |Δ visibility| exceeds this
  double continuity_spacings = 3.0;        // neighbours farther from X than this many pixel spacings break continuity
};

struct Flicker {
  std::int64_t surface_pixels = 0;   // pixels of frame t that show a surface
  std::int64_t matched_pixels = 0;   // of those, found on the same surface in frame t−1
  double mean_abs = 0;               // mean |V_t − V_{t−1}| over the matched pixels
  double rms = 0;                    // root mean square of the same
  double share_changed = 0;          // share of matched pixels with |Δ| > changed_threshold
};

// Throws std::invalid_argument naming what is wrong (missing images, different sizes, wrong
// channel counts).
Flicker flicker(const FrameSample& previous, const FrameSample& current, const FlickerOptions& options = {});

}  // namespace penumbra::metrics
