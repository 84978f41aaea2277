#include "sampling/poisson_disk.h"

#include <algorithm>
#include <random>

#include <glm/geometric.hpp>

namespace penumbra::sampling {

std::vector<glm::vec2> poisson_disk(int taps) {
  taps = std::clamp(taps, 1, 64);
  // The standard library's distribution (not sampling::Random): the taps of every image made so
  // far come from this sequence.
  std::mt19937 rng(20170815u + static_cast<unsigned>(taps));
  std::uniform_real_distribution<float> u(-1, 1);
  std::vector<glm::vec2> pts;
  auto random_in_disk = [&] {
    for (;;) {
      glm::vec2 p(u(rng), u(rng));
      if (glm::dot(p, p) <= 1) return p;
    }
  };
  // Mitchell's best candidate: each new tap is the candidate farthest from those placed so far.
  for (int i = 0; i < taps; ++i) {
    glm::vec2 best{};
    float best_d = -1;
    for (int c = 0; c < 32 * (i + 1); ++c) {
      const glm::vec2 p = random_in_disk();
      float d = 1e9f;
      for (const auto& q : pts) d = std::min(d, glm::distance(p, q));
      if (d > best_d) best_d = d, best = p;
    }
    pts.push_back(best);
  }
  float r_max = 0;
  for (const auto& p : pts) r_max = std::max(r_max, glm::length(p));
  if (r_max > 0)
    for (auto& p : pts) p /= r_max;
  return pts;
}

}  // namespace penumbra::sampling
