#include "scene/culling.h"

#include <limits>

#include <glm/common.hpp>
#include <glm/vec4.hpp>

namespace penumbra::scene {

namespace {

// True when `m` maps points affinely (its last row is 0 0 0 1: an orthographic light's or a
// model's matrix, not a perspective): w stays 1, and a box's image is bounded per axis by its
// centre's image ± the matrix's absolute values times its half extent.
bool affine(const glm::mat4& m) { return m[0][3] == 0.0f && m[1][3] == 0.0f && m[2][3] == 0.0f && m[3][3] == 1.0f; }

// The bounds of an affine `m`'s image of `box` along x, y, z: the centre's image ± the half extent
// through |m| (the least and greatest over the eight corners, in two matrix products instead of
// eight), widened by a few units in the last place of its magnitude, so that rounding never leaves
// a corner's image outside them: culling by them keeps at least what the corners keep.
void affine_bounds(const glm::mat4& m, const Aabb& box, glm::vec3& lo, glm::vec3& hi) {
  const glm::vec3 centre = 0.5f * box.lo + 0.5f * box.hi;  // halves first: no overflow near the float limit
  const glm::vec3 half = 0.5f * box.hi - 0.5f * box.lo;
  const glm::vec3 c = glm::vec3(m * glm::vec4(centre, 1.0f));
  // The centre's product, the extent's sum and the halves each round by a few units in the last
  // place of `scale` (the sum of the terms' magnitudes), and so does each corner's own product in
  // the eight-corner bounds these stand in for: 16 of them cover both.
  glm::vec3 e(0.0f), scale = glm::abs(glm::vec3(m[3]));
  for (int col = 0; col < 3; ++col) {
    const glm::vec3 column = glm::abs(glm::vec3(m[col]));
    e += column * half[col];
    scale += column * glm::max(glm::abs(box.lo[col]), glm::abs(box.hi[col]));
  }
  e += scale * (16.0f * std::numeric_limits<float>::epsilon());
  lo = c - e;
  hi = c + e;
}

}  // namespace

bool may_touch(const glm::mat4& clip_from_box, const Aabb& box, CullVolume volume) {
  if (box.empty()) return false;
  if (affine(clip_from_box)) {  // w = 1 at every corner: outside a plane is the bounds beyond ±1
    glm::vec3 lo, hi;
    affine_bounds(clip_from_box, box, lo, hi);
    const int axes = volume == CullVolume::view ? 3 : 2;
    for (int a = 0; a < axes; ++a)
      if (hi[a] < -1.0f || lo[a] > 1.0f) return false;
    return true;
  }
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
  const bool fast = affine(light_from_mesh);
  for (std::size_t k = 0; k < units.size(); ++k) {
    if (units[k].bounds.empty()) continue;  // stays empty: never kept
    Footprint& f = out[k];
    if (fast) {
      glm::vec3 lo, hi;
      affine_bounds(light_from_mesh, units[k].bounds, lo, hi);
      f.lo = glm::vec2(lo);
      f.hi = glm::vec2(hi);
      continue;
    }
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
