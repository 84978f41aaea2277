#pragma once
// Cascade sizing for directional lights: where to split the view, and how many cascades the
// filter-to-resolution rule needs. No GL and no GLM: another engine can call these with its own
// light frames.
//
//   splits    practical scheme (Zhang et al. 2006): boundary i of n is
//             lambda * near (far/near)^(i/n) + (1 - lambda) * (near + (far - near) i/n);
//             lambda = 1 is logarithmic (constant texel-to-pixel ratio), 0 uniform.
//   count     the fewest cascades (1..max_count) whose every requirement, in texels from the rule
//             res = c · L_i / r_ws, fits the largest map; a scene that fits one map gets one.
#include <functional>
#include <vector>

namespace penumbra::adaptive {

// count + 1 increasing view depths from `near_ws` to `far_ws` (both included). Degenerate input
// is repaired rather than propagated: near <= 0 is raised to far * 1e-4 (the logarithmic term
// needs near > 0), far <= near gives a range of near * (1 + 1e-3), lambda is clamped to [0, 1],
// count to >= 1.
std::vector<double> cascade_splits(double near_ws, double far_ws, int count, double lambda);

struct CascadeChoice {
  int count = 1;
  std::vector<double> required_texels;  // per cascade, before clamping
  bool fits = true;                     // false when even max_count cascades need more than max
};

// `required(n)` returns the per-cascade requirement (texels) when the view is split into n
// cascades. Tries n = 1, 2, ..., max_count and returns the first whose requirements are all
// <= max_texels (NaN counts as not fitting); otherwise max_count with fits = false.
CascadeChoice choose_cascade_count(int max_count, double max_texels,
                                   const std::function<std::vector<double>(int)>& required);

}  // namespace penumbra::adaptive
