#pragma once
// Published values Penumbra starts from (docs/architecture.md, "Background").

namespace penumbra {

// c of the rule r = c·a, in texels: a filter of radius r hides the staircase of texels of size a
// when r >= c·a. 10 expert observers, worst case (single step at full contrast); no interval was
// published. F. Kreuzer, diploma thesis, TU Wien 2017, eq. 5.1 (data/calibration/default.json).
inline constexpr double kPublishedC = 3.47;

}  // namespace penumbra
