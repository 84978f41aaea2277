#include "scene/culling.h"

#include <glm/vec4.hpp>

namespace penumbra::scene {

bool may_touch(const glm::mat4& clip_from_box, const Aabb& box, CullVolume volume) {
  if (box.empty()) return false;
  // Bit k set: the corner is outside plane k (-x, +x, -y, +y, -z, +z).
  unsigned outside_all = volume == CullVolume::view ? 0x3fu : 0x0fu;
  for (int i = 0; i < 8 && outside_all != 0; ++i) {
    const glm::vec4 p = clip_from_box * glm::vec4(box.corner(i), 1.0f);
    const unsigned out = (p.x < -p.w ? 1u : 0u) | (p.x > p.w ? 2u : 0u) | (p.y < -p.w ? 4u : 0u) | (p.y > p.w ? 8u : 0u) |
                         (p.z < -p.w ? 16u : 0u) | (p.z > p.w ? 32u : 0u);
    outside_all &= out;
  }
  return outside_all == 0;
}

DrawRanges cull_units(const std::vector<DrawUnit>& units, const glm::mat4& clip_from_mesh, CullVolume volume) {
  DrawRanges r;
  for (const DrawUnit& u : units) {
    if (u.index_count == 0 || !may_touch(clip_from_mesh, u.bounds, volume)) continue;
    if (!r.first_index.empty() && r.first_index.back() + r.index_count.back() == u.first_index) {
      r.index_count.back() += u.index_count;
    } else {
      r.first_index.push_back(u.first_index);
      r.index_count.push_back(u.index_count);
    }
    r.triangles += u.index_count / 3;
  }
  return r;
}

}  // namespace penumbra::scene
