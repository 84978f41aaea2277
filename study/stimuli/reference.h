#pragma once
// The reference filter size (Kreuzer 2017, sec. 4.4): the smallest filter radius at which the
// 8-bit stimulus drawn from the jagged shadow map and the one drawn from the straight original are
// pixel-identical, so that even a perfect observer cannot tell them apart. Images are drawn with
// the study's own stimulus code (StimulusRenderer) and compared with OpenCV.
//
// The difference between the two images need not shrink monotonically with r (8-bit rounding can
// make two images equal at one radius and differ again at a larger one), and it depends on the
// edge phase that the study randomizes per trial. So the search is, per seed (phase/orientation):
//   1. a geometric scan r_i = r_min * growth^i up to r_max, rendering every point;
//   2. the smallest scan point from which every larger scan point is identical;
//   3. bisection between it and the scan point below it, to `resolution_px`.
// The result for a (pattern, contrast, artifact size) is the largest over the seeds. Scan points
// below the result that were already identical are reported (`identical_below_px`): where that
// list is not empty the difference is not monotone in r. When the images differ at r_max the scan
// stops there (one render): no radius that a stimulus can show hides the difference.
//
// Partners. `original` compares with the study's straight partner, the original edge. Texel-centre
// rasterization moves a 45-degree edge by up to half a texel (the staircase's mean line is
// y = x + b_mean, not the original y = x + b), and a blur never hides a displaced edge, so for most
// phases no showable radius makes these pairs identical. `mean_line` (stair only) compares with the
// straight edge through the staircase's mean, which isolates the staircase itself: the bound the
// thesis meant by drawing the artifact-free line through the same staircase. `bresenham` is the
// thesis's own definition (sec. 4.4): the straight edge drawn at high resolution (here the display's:
// a map of 1 px texels whose centres sit on the pixel centres, the midpoint rule of Bresenham's
// algorithm) and filtered by the same path; any pattern. Run with `transfer` linear for the linear
// 8-bit intensities and with the display's transfer for what is shown.
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "stimuli/stimulus.h"

namespace penumbra::stimuli {

enum class Partner { original, mean_line, bresenham };
// "original" | "mean-line" | "bresenham"; throws std::invalid_argument
Partner parse_partner(const std::string& name);
std::string to_string(Partner partner);

struct ReferenceSearch {
  Partner partner = Partner::original;
  double r_min_px = 1.0;
  double r_max_px = 0;          // 0: the largest showable radius, size_px / 2
  double growth = 1.25;         // scan ratio
  double resolution_px = 0.05;  // bisection stops when the bracket is this narrow
  // Images count as identical when no pixel differs by more than this many 8-bit levels. 0 is the
  // definition; 1 forgives single-level flips, which the GL filter's float32 arithmetic alone
  // produces (the two images are computed along different paths; docs/fit.md has the numbers).
  int tolerance_levels = 0;
  std::vector<std::uint64_t> seeds = {1, 2, 3, 4};
};

// How two 8-bit stimuli differ.
struct ImageDifference {
  int differing_pixels = 0;
  int max_abs_levels = 0;  // largest |difference| in 8-bit levels
};
ImageDifference compare(const io::Image8& a, const io::Image8& b);

struct SeedReference {
  std::uint64_t seed = 0;
  // Smallest radius (to resolution_px) from which every checked radius gives identical images;
  // empty when the images still differ at r_max.
  std::optional<double> reference_px;
  double bracket_below_px = 0;  // largest checked radius below the result whose images differ
  ImageDifference at_r_max;     // the difference left at r_max
  std::vector<double> identical_below_px;  // scan points below the result with identical images
  int renders = 0;
};

struct Reference {
  StimulusSpec spec;  // pattern, contrast, artifact size, kernel, size, transfer (radius and seed unused)
  ReferenceSearch search;
  std::optional<double> reference_px;  // max over seeds; empty when any seed never becomes identical
  bool monotone = true;                // no seed had identical images below its result
  std::vector<SeedReference> seeds;
};

// Needs a current OpenGL context (through `renderer`). `progress(done, total)` after each seed.
Reference find_reference(StimulusRenderer& renderer, const StimulusSpec& spec, const ReferenceSearch& search,
                         const std::function<void(int, int)>& progress = {});

nlohmann::json to_json(const Reference& reference);

// The line offset b of the straight edge y = x + b through the mean of the staircase that
// `geometry`'s shadow map holds for a stair stimulus (texel-centre rule, canonical frame).
double stair_mean_line_b(const Geometry& geometry, double artifact_px);

}  // namespace penumbra::stimuli
