#pragma once
// The GPU copy of a CPU mesh (scene/mesh.h).
#include <cstddef>
#include <memory>
#include <vector>

#include <penumbra/gl/objects.h>
#include <penumbra/scene/culling.h>
#include <penumbra/scene/mesh.h>
#include <penumbra/scene/scene.h>

namespace penumbra::scene {

// GPU copy: interleaved position/normal vertex buffer, 32-bit index buffer, one VAO.
class GpuMesh {
 public:
  explicit GpuMesh(const MeshData& mesh);
  void draw() const;
  // The ranges culling kept (scene/culling.h), in one glMultiDrawElements.
  void draw(const DrawRanges& ranges) const;
  std::size_t index_count() const { return index_count_; }
  const std::vector<DrawUnit>& units() const { return units_; }

 private:
  gl::Buffer vertices_;
  gl::Buffer indices_;
  gl::VertexArray vao_;
  std::size_t index_count_ = 0;
  std::vector<DrawUnit> units_;  // MeshData::draw_units()
};

// A scene's meshes on the GPU: one copy per distinct MeshData, however many objects share it
// (instances: the outdoor town's crane and fence panels, or a scene file's objects that name one
// model), and for each object the copy it draws with its own model matrix.
class GpuMeshes {
 public:
  GpuMeshes() = default;
  explicit GpuMeshes(const std::vector<Object>& objects);
  std::size_t size() const { return of_object_.size(); }                     // objects
  const GpuMesh& operator[](std::size_t object) const { return *of_object_[object]; }
  std::size_t copies() const { return copies_.size(); }                      // distinct meshes uploaded

 private:
  std::vector<std::unique_ptr<GpuMesh>> copies_;
  std::vector<const GpuMesh*> of_object_;
};

}  // namespace penumbra::scene
