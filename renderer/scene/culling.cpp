#include "scene/culling.h"

#include <limits>

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

namespace {
// Adds `u` to `r`, merged with the last range when it follows it.
void keep(DrawRanges& r, const DrawUnit& u) {
  if (!r.first_index.empty() && r.first_index.back() + r.index_count.back() == u.first_index) {
    r.index_count.back() += u.index_count;
  } else {
    r.first_index.push_back(u.first_index);
    r.index_count.push_back(u.index_count);
  }
  r.triangles += u.index_count / 3;
}
}  // namespace

DrawRanges cull_units(const std::vector<DrawUnit>& units, const glm::mat4& clip_from_mesh, CullVolume volume) {
  DrawRanges r;
  for (const DrawUnit& u : units)
    if (u.index_count != 0 && may_touch(clip_from_mesh, u.bounds, volume)) keep(r, u);
  return r;
}

std::vector<Footprint> unit_footprints(const std::vector<DrawUnit>& units, const glm::mat4& light_from_mesh) {
  std::vector<Footprint> out(units.size());
  for (std::size_t k = 0; k < units.size(); ++k) {
    if (units[k].bounds.empty()) continue;  // stays empty: never kept
    Footprint& f = out[k];
    f.lo = glm::vec2(std::numeric_limits<float>::infinity());
    f.hi = -f.lo;
    for (int i = 0; i < 8; ++i) {
      const glm::vec4 p = light_from_mesh * glm::vec4(units[k].bounds.corner(i), 1.0f);
      f.lo = glm::min(f.lo, glm::vec2(p) / p.w);
      f.hi = glm::max(f.hi, glm::vec2(p) / p.w);
    }
  }
  return out;
}

namespace {
bool overlaps(const Footprint& f, const Footprint& window) {
  return f.lo.x <= f.hi.x && f.hi.x >= window.lo.x && f.lo.x <= window.hi.x && f.hi.y >= window.lo.y && f.lo.y <= window.hi.y;
}
}  // namespace

DrawRanges cull_units(const std::vector<DrawUnit>& units, const std::vector<Footprint>& footprints, const Footprint& window) {
  DrawRanges r;
  for (std::size_t k = 0; k < units.size() && k < footprints.size(); ++k)
    if (units[k].index_count != 0 && overlaps(footprints[k], window)) keep(r, units[k]);
  return r;
}

ClusterFootprints cluster_footprints(const ClusteredUnits& c, const glm::mat4& light_from_mesh) {
  return {unit_footprints(c.units, light_from_mesh), unit_footprints(c.clusters, light_from_mesh)};
}

DrawRanges cull_clusters(const ClusteredUnits& c, const ClusterFootprints& footprints, const Footprint& window) {
  DrawRanges r;
  for (std::size_t u = 0; u < c.units.size() && u < footprints.units.size() && u + 1 < c.first_cluster.size(); ++u) {
    if (c.units[u].index_count == 0 || !overlaps(footprints.units[u], window)) continue;
    for (std::size_t k = c.first_cluster[u]; k < c.first_cluster[u + 1] && k < c.clusters.size() && k < footprints.clusters.size(); ++k)
      if (c.clusters[k].index_count != 0 && overlaps(footprints.clusters[k], window)) keep(r, c.clusters[k]);
  }
  return r;
}

DrawRanges cull_clusters(const ClusteredUnits& c, const glm::mat4& clip_from_mesh, CullVolume volume) {
  DrawRanges r;
  for (std::size_t u = 0; u < c.units.size() && u + 1 < c.first_cluster.size(); ++u) {
    if (c.units[u].index_count == 0 || !may_touch(clip_from_mesh, c.units[u].bounds, volume)) continue;
    for (std::size_t k = c.first_cluster[u]; k < c.first_cluster[u + 1] && k < c.clusters.size(); ++k)
      if (c.clusters[k].index_count != 0 && may_touch(clip_from_mesh, c.clusters[k].bounds, volume)) keep(r, c.clusters[k]);
  }
  return r;
}

}  // namespace penumbra::scene
