#pragma once
// The main job's perceptual yardstick (issue 46): a configuration's lit frame against the
// reference's lit frame by LDR-FLIP (metrics/flip.h), at the pixels per degree of the study's
// display, beside the RMSE of the visibility.
//
// The lit frames are composed from the visibility with the frame's own shading: the camera pass
// (shaders/shading.frag) writes albedo·light·(ambient + (1 − ambient)·max(n·l, 0)·V), linear in
// the visibility V, so per pixel lit(V) = base + V·direct in linear RGB. The ray-traced reference
// has a visibility and no lit frame; composing every frame, reference and configuration alike,
// from its visibility makes a configuration whose visibility equals the reference's score exactly
// 0, and the composition stays within a code value or two of the renderer's own lit frame but for
// isolated pixels of the virtual maps (8 of 20 736 at 192x108 on the street), whose lit colour
// and visibility disagree there (report.json's lit_frames says how close, measured on every
// frame compared).
#include <cstdint>
#include <string>
#include <vector>

#include "image/image.h"
#include "io/image_io.h"
#include "metrics/flip.h"
#include "metrics/frame_observer.h"
#include "shadows/renderer.h"
#include "shadows/settings.h"

namespace penumbra::demo {

// Per pixel, linear RGB: the radiance at V = 0 (ambient only) and what V = 1 adds.
struct ShadingBasis {
  image::ImageF base, direct;  // 3 channels each, the frame's size
};

// Two cheap renders of `renderer`'s scene at its camera and poses: the light's ambient at 1 (the
// radiance albedo·light whatever the shadow) and hard shadows whose depth bias leaves nothing
// in shadow (V = 1 everywhere; a pixel with V < 1 throws std::runtime_error). The scene's light is
// restored. `settings`: the reference's settings (only the map's placement is kept).
ShadingBasis shading_basis(shadows::Renderer& renderer, const shadows::ShadowSettings& settings, int width_px, int height_px);

// The lit frame for `visibility` (one channel, the basis's size): linear RGB in [0, 1] (what the
// display shows once sRGB-encoded), 3 channels, not rounded. FLIP and the observer read it as
// Encoding::linear: no sRGB round trip per comparison.
image::ImageF lit_frame(const ShadingBasis& basis, const io::ImageF& visibility);

// How far a composed lit frame (linear, lit_frame's) is from the renderer's own (RGB or RGBA,
// sRGB-encoded), in 8-bit code values of the sRGB encoding: the largest difference and the pixels
// differing by more than 2.
struct CodeDifference {
  int max = 0;
  std::int64_t above_2 = 0, pixels = 0;
};
CodeDifference code_difference(const image::ImageF& composed, const io::Image8& rendered);

// The FLIP montage (<technique>-flip-montage.png): 3 tiles a row, each this wide (the frame's
// half, at least 480 px: room for the longest label at the montage's 24 px text).
constexpr int kFlipMontageColumns = 3;
inline int flip_montage_tile_width(int frame_width_px) { return frame_width_px / 2 > 480 ? frame_width_px / 2 : 480; }

// The frame observer's verdict (metrics/frame_observer.h) on one configuration against one
// reference over the reference frames: per frame its largest patch p_detect and the patches above
// the criterion F.
struct ObserverSeries {
  struct Frame {
    double p_detect_max = 0;
    int patches_visible = 0, patches = 0;
    bool visible = false;
  };
  std::vector<Frame> frames;
  double criterion_f = 0;
  bool visible() const;          // in some frame
  double p_detect_max() const;   // over the frames
  void add(const metrics::FrameDetection& d);
};

// FLIP's pooled values of one configuration against one reference over the reference frames.
struct FlipSeries {
  std::vector<metrics::FlipPooled> frames;  // one per reference frame
  double mean() const;                      // of the frames' means: the error the front is read at
};

}  // namespace penumbra::demo
