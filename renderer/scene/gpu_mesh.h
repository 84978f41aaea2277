#pragma once
// The GPU copy of a CPU mesh (scene/mesh.h).
#include <cstddef>
#include <vector>

#include <penumbra/gl/objects.h>
#include <penumbra/scene/culling.h>
#include <penumbra/scene/mesh.h>

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

}  // namespace penumbra::scene
