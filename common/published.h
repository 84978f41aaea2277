#pragma once
// Published values Penumbra starts from (docs/architecture.md, "Background").

namespace penumbra {

// c of the rule r = c·a, in texels: at a filter radius r = c·a the staircase of texels of size a is
// still detected at the study's criterion (QUEST at 82 % correct, a detection probability of about
// 0.65): it is a threshold, not the radius that hides the artifact; a lower visibility needs a
// larger c (adaptive::c_at_visibility). 10 expert observers in a yes/no task, the condition the
// thesis reports (that it is the single step at full contrast is an inference from its Figure 4.6);
// no interval was published. F. Kreuzer, diploma thesis, TU Wien 2017, eq. 5.1
// (data/calibration/default.json states its reading).
inline constexpr double kPublishedC = 3.47;

}  // namespace penumbra
