#pragma once
// Triangle meshes on the CPU (procedural shapes, loaded models); GL-free (the GPU copy:
// scene/gpu_mesh.h).
#include <cstdint>
#include <limits>
#include <vector>

#include <glm/glm.hpp>

namespace penumbra::scene {

struct Vertex {
  glm::vec3 position;
  glm::vec3 normal;
};

struct Aabb {
  glm::vec3 lo{std::numeric_limits<float>::max()};
  glm::vec3 hi{std::numeric_limits<float>::lowest()};

  bool empty() const { return lo.x > hi.x || lo.y > hi.y || lo.z > hi.z; }
  void extend(const glm::vec3& p) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  void extend(const Aabb& b) {
    if (!b.empty()) {
      extend(b.lo);
      extend(b.hi);
    }
  }
  // Corner i (bit 0: x, bit 1: y, bit 2: z picks hi).
  glm::vec3 corner(int i) const { return {i & 1 ? hi.x : lo.x, i & 2 ? hi.y : lo.y, i & 4 ? hi.z : lo.z}; }
  Aabb transformed(const glm::mat4& m) const;
};

// One draw unit of a mesh: a run of its index list (a building, a tree, a pole, one node of a
// model) with the bounds of the vertices it uses, in the mesh's space. Culling keeps or drops a
// unit as a whole.
struct DrawUnit {
  std::uint32_t first_index = 0;
  std::uint32_t index_count = 0;
  Aabb bounds;
};

struct MeshData {
  std::vector<Vertex> vertices;
  std::vector<std::uint32_t> indices;  // triangle list
  // Units in index order, each starting where the previous one ended; empty: the whole mesh is one
  // unit (draw_units()).
  std::vector<DrawUnit> units;

  Aabb bounds() const;
  // Appends `other`'s triangles (its units are not kept: close_unit() marks what the caller calls one).
  void append(const MeshData& other, const glm::mat4& transform);
  // Ends a unit at the current end of the index list: the indices since the previous unit's end
  // (none: nothing is added). Indices appended after the last close_unit() become a unit of their own.
  void close_unit();
  // The units to draw: `units` plus the indices after the last of them, or one unit for the whole
  // mesh when none was closed. Together they cover every index exactly once.
  std::vector<DrawUnit> draw_units() const;
};

// A mesh's units split into clusters of at most `max_triangles` consecutive triangles, for culling
// finer than a unit: a unit over a virtual shadow map's page sends all its triangles to it (a
// building's body, ledges and windows over every page it crosses), a cluster only those near the
// page. Runs of the index list, not a spatial sort: the shapes here are appended part by part (a
// box, a window, a tube's segment), so consecutive triangles lie together, and an index list kept
// as it is draws every image as before (reordered, it changed which of two coplanar triangles wins
// a depth tie: 8 pixels of the street's image; clusters of 16 sorted in space held 2 % fewer
// triangles there, docs/results/virtual-maps.md). A model whose triangles come in no spatial order
// clusters poorly.
struct ClusteredUnits {
  std::vector<DrawUnit> units;  // MeshData::draw_units()
  // In index order, covering every index exactly once, each inside one unit, with the bounds of
  // the vertices it uses. Unit u's clusters are [first_cluster[u], first_cluster[u + 1]).
  std::vector<DrawUnit> clusters;
  std::vector<std::uint32_t> first_cluster;  // units.size() + 1 entries
};
// 0: no split (the clusters are the units).
ClusteredUnits cluster_units(const MeshData& mesh, std::uint32_t max_triangles);

// Procedural shapes, centred on the origin.
MeshData make_plane(float size_x, float size_z);                      // in y = 0, normal +y
MeshData make_box(const glm::vec3& size);
MeshData make_sphere(float radius, int segments = 48, int rings = 24);
// A lattice of thin square bars in the xy plane: `bars_x` vertical and `bars_y` horizontal bars of
// width `bar_width` over a `width` × `height` frame of depth `bar_width`.
MeshData make_lattice(float width, float height, int bars_x, int bars_y, float bar_width);
// An open tube (no end caps) of `sides` sides along the polyline `points`, radius `radii[i]` at
// point i (same count, at least two points): branches, wires, poles. Its rings follow the polyline
// by parallel transport, so a bent tube does not twist.
MeshData make_tube(const std::vector<glm::vec3>& points, const std::vector<float>& radii, int sides);
// A straight bar of square cross-section `width` from `a` to `b` (a lattice member).
MeshData make_beam(const glm::vec3& a, const glm::vec3& b, float width);

}  // namespace penumbra::scene
