#include "scene/gpu_mesh.h"

#include <cstdint>
#include <unordered_map>

namespace penumbra::scene {

GpuMesh::GpuMesh(const MeshData& mesh, std::uint32_t cluster_triangles)
    : vertices_(mesh.vertices.size() * sizeof(Vertex), mesh.vertices.data()),
      indices_(mesh.indices.size() * sizeof(std::uint32_t), mesh.indices.data()),
      index_count_(mesh.indices.size()),
      clustered_(cluster_units(mesh, cluster_triangles)) {
  const GLuint vao = vao_.id();
  glVertexArrayVertexBuffer(vao, 0, vertices_.id(), 0, sizeof(Vertex));
  glVertexArrayElementBuffer(vao, indices_.id());
  glEnableVertexArrayAttrib(vao, 0);
  glVertexArrayAttribFormat(vao, 0, 3, GL_FLOAT, GL_FALSE, offsetof(Vertex, position));
  glVertexArrayAttribBinding(vao, 0, 0);
  glEnableVertexArrayAttrib(vao, 1);
  glVertexArrayAttribFormat(vao, 1, 3, GL_FLOAT, GL_FALSE, offsetof(Vertex, normal));
  glVertexArrayAttribBinding(vao, 1, 0);
}

void GpuMesh::draw() const {
  if (index_count_ == 0) return;
  vao_.bind();
  glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(index_count_), GL_UNSIGNED_INT, nullptr);
}

void GpuMesh::draw(const DrawRanges& ranges) const {
  if (ranges.first_index.empty()) return;
  std::vector<GLsizei> counts(ranges.index_count.size());
  std::vector<const void*> offsets(ranges.first_index.size());
  for (std::size_t i = 0; i < counts.size(); ++i) {
    counts[i] = static_cast<GLsizei>(ranges.index_count[i]);
    offsets[i] = reinterpret_cast<const void*>(static_cast<std::uintptr_t>(ranges.first_index[i]) * sizeof(std::uint32_t));
  }
  vao_.bind();
  glMultiDrawElements(GL_TRIANGLES, counts.data(), GL_UNSIGNED_INT, offsets.data(), static_cast<GLsizei>(counts.size()));
}

GpuMeshes::GpuMeshes(const std::vector<Object>& objects, std::uint32_t cluster_triangles) {
  std::unordered_map<const MeshData*, const GpuMesh*> uploaded;
  for (const Object& o : objects) {
    const GpuMesh*& copy = uploaded[o.mesh.get()];
    if (!copy) copy = copies_.emplace_back(std::make_unique<GpuMesh>(*o.mesh, cluster_triangles)).get();
    of_object_.push_back(copy);
  }
}

}  // namespace penumbra::scene
