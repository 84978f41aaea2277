#include "scene/gpu_mesh.h"

#include <cstdint>

namespace penumbra::scene {

GpuMesh::GpuMesh(const MeshData& mesh)
    : vertices_(mesh.vertices.size() * sizeof(Vertex), mesh.vertices.data()),
      indices_(mesh.indices.size() * sizeof(std::uint32_t), mesh.indices.data()),
      index_count_(mesh.indices.size()) {
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

}  // namespace penumbra::scene
