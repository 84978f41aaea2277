#pragma once
// The GPU copy of a CPU mesh (scene/mesh.h).
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include <penumbra/gl/objects.h>
#include <penumbra/scene/culling.h>
#include <penumbra/scene/mesh.h>
#include <penumbra/scene/scene.h>

namespace penumbra::scene {

// The most triangles a cluster of a GpuMesh holds (cluster_units): what a virtual shadow map's page,
// a shadow map and a cascade cull casters by. Measured on the street (docs/results/virtual-maps.md,
// 2026-12-06 clusters entry).
inline constexpr std::uint32_t kClusterTriangles = 16;

// GPU copy: interleaved position/normal vertex buffer, 32-bit index buffer, one VAO.
class GpuMesh {
 public:
  explicit GpuMesh(const MeshData& mesh, std::uint32_t cluster_triangles = kClusterTriangles);
  void draw() const;
  // The ranges culling kept (scene/culling.h), in one glMultiDrawElements.
  void draw(const DrawRanges& ranges) const;
  std::size_t index_count() const { return index_count_; }
  const std::vector<DrawUnit>& units() const { return clustered_.units; }
  // The units and their clusters of at most cluster_triangles (cluster_units).
  const ClusteredUnits& clustered() const { return clustered_; }

 private:
  gl::Buffer vertices_;
  gl::Buffer indices_;
  gl::VertexArray vao_;
  std::size_t index_count_ = 0;
  ClusteredUnits clustered_;  // its units are MeshData::draw_units()
};

// A scene's meshes on the GPU: one copy per distinct MeshData, however many objects share it
// (instances: the outdoor town's crane and fence panels, or a scene file's objects that name one
// model), and for each object the copy it draws with its own model matrix.
class GpuMeshes {
 public:
  GpuMeshes() = default;
  explicit GpuMeshes(const std::vector<Object>& objects, std::uint32_t cluster_triangles = kClusterTriangles);
  std::size_t size() const { return of_object_.size(); }                     // objects
  const GpuMesh& operator[](std::size_t object) const { return *of_object_[object]; }
  std::size_t copies() const { return copies_.size(); }                      // distinct meshes uploaded

 private:
  std::vector<std::unique_ptr<GpuMesh>> copies_;
  std::vector<const GpuMesh*> of_object_;
};

}  // namespace penumbra::scene
