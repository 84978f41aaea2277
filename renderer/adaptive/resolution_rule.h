#pragma once
// The filter-to-resolution rule r = c·a (Kreuzer 2017, eq. 5.1–5.6): the staircase of texels of
// size a under a filter of radius r is detected with no more than the calibration's criterion
// probability when a <= r / c (c is a threshold: at r = c·a it is still seen at that criterion;
// choose a lower visibility with a larger c, calibration.h's c_at_visibility). So the smallest
// shadow map at that visibility has res = c / r_uv texels per side, or res = c · L_ws / r_ws for a world-space radius over a
// light view plane of extent L_ws (with fitting, L_ws is the fitted extent: r_uv = r_ws / L_ws · s_xy
// with L_ws unfitted is the same thing).
//
// This header and its .cpp need neither GL, the study nor Ceres: another engine can link
// `penumbra_adaptive` alone.
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include <penumbra/adaptive/calibration.h>
#include <penumbra/published.h>

namespace penumbra::adaptive {

// The limits of the maps a renderer allocates: 32 to 4096 texels per side in steps of 32 by
// default, the one set of defaults of Penumbra (shadows::AdaptiveParams, and so the tools'
// adaptive.min_texels, max_texels and quantum_texels, take theirs from here). 4096² keeps a 32-bit
// depth map at 64 MiB (a sub-rectangle atlas allocates max_texels² per cascade); an engine that
// can afford larger maps raises max_texels, one that cannot lowers it.
struct ResolutionLimits {
  int min_texels = 32;
  int max_texels = 4096;
  int quantum_texels = 32;  // results are rounded *up* to a multiple of this (never below the rule)
};

// The lengths the rule takes, each a type of its own: a call names what it passes
// (required_texels_ws(c, LightExtentWs{20.0}, FilterRadiusWs{0.05})), and the light's extent and
// the filter radius, both world units, cannot be swapped or given as bare numbers (the
// constructors are explicit). The rule throws std::invalid_argument, naming the parameter, for a
// value that is not positive and finite.
struct LightExtentWs {  // side of the light's view plane the map is spread over (fitted), world units
  constexpr explicit LightExtentWs(double v) : value(v) {}
  double value;
};
struct FilterRadiusWs {  // the shadow filter's radius, world units
  constexpr explicit FilterRadiusWs(double v) : value(v) {}
  double value;
};
struct FilterRadiusUv {  // the shadow filter's radius in shadow-map uv (a fraction of the map's side)
  constexpr explicit FilterRadiusUv(double v) : value(v) {}
  double value;
};

// The rule before clamping and quantization, in texels per side: c / r_uv. c (texels, from the
// calibration) and the radius must be positive and finite: anything else throws
// std::invalid_argument naming the parameter. The result is positive, and +inf only where the
// quotient overflows (clamp_resolution gives max_texels then).
double required_texels_uv(double c, FilterRadiusUv radius);
// c · L_ws / r_ws for a world-space radius over a light view plane of extent L_ws; c, L_ws and
// r_ws positive and finite, or std::invalid_argument naming the one that is not.
double required_texels_ws(double c, LightExtentWs light_extent, FilterRadiusWs radius);

// Clamped to [min, max] and rounded up to the quantum (then clamped again), always finite:
// +inf (r → 0) or NaN gives max, 0 or less (r huge, L → 0) gives min.
int clamp_resolution(double required_texels, const ResolutionLimits& limits);

// Rate limits resolution changes so edges do not wobble: grows at once to the (quantized)
// requirement, shrinks only after the requirement has stayed below `shrink_fraction` of the
// current resolution for `shrink_delay_frames` consecutive frames, and then to the largest
// requirement seen during that wait.
class ResolutionController {
 public:
  struct Params {
    ResolutionLimits limits;
    int shrink_delay_frames = 30;  // also the renderer's default (shadows::AdaptiveParams)
    double shrink_fraction = 0.8;
  };
  explicit ResolutionController(Params params);
  // Feeds one frame's requirement (texels, unclamped) and returns the resolution to use.
  int update(double required_texels);
  int current() const { return current_; }
  int changes() const { return changes_; }  // how often the resolution changed

 private:
  Params params_;
  int current_ = 0;
  int frames_below_ = 0;
  int pending_max_ = 0;
  int changes_ = 0;
};

}  // namespace penumbra::adaptive
