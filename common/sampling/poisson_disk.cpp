#include "sampling/poisson_disk.h"

#include <algorithm>
#include <cstddef>
#include <iterator>

namespace penumbra::sampling {
namespace {

// The frozen sets of n = 1..64 taps, one after the other, x and y per tap (how they were made: the
// file's header).
constexpr float kTaps[] = {
#include "sampling/poisson_disk_taps.inc"
};
static_assert(std::size(kTaps) == 2 * 64 * 65 / 2, "one set of n taps for every n in [1, 64]");

}  // namespace

std::vector<glm::vec2> poisson_disk(int taps) {
  const auto n = static_cast<std::size_t>(std::clamp(taps, 1, 64));
  const float* first = kTaps + n * (n - 1);  // 2 floats a tap, sets 1..n-1 before this one
  std::vector<glm::vec2> pts(n);
  for (std::size_t i = 0; i < n; ++i) pts[i] = {first[2 * i], first[2 * i + 1]};
  return pts;
}

}  // namespace penumbra::sampling
