#pragma once
// The Poisson-disk kernel shared by the renderer's PCF/PCSS taps and the study's stimuli.
#include <vector>

#include <glm/vec2.hpp>

namespace penumbra::sampling {

// Poisson-disk taps in the unit disk (deterministic best-candidate set, outermost tap at radius 1);
// `taps` is clamped to [1, 64].
std::vector<glm::vec2> poisson_disk(int taps);

}  // namespace penumbra::sampling
