#include "scene/mesh.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <glm/gtc/matrix_transform.hpp>

namespace penumbra::scene {

Aabb Aabb::transformed(const glm::mat4& m) const {
  Aabb out;
  if (empty()) return out;
  for (int i = 0; i < 8; ++i) out.extend(glm::vec3(m * glm::vec4(corner(i), 1.0f)));
  return out;
}

Aabb MeshData::bounds() const {
  Aabb b;
  for (const auto& v : vertices) b.extend(v.position);
  return b;
}

void MeshData::append(const MeshData& other, const glm::mat4& transform) {
  const auto base = static_cast<std::uint32_t>(vertices.size());
  const glm::mat3 normal_matrix = glm::transpose(glm::inverse(glm::mat3(transform)));
  for (const auto& v : other.vertices) {
    glm::vec3 n = normal_matrix * v.normal;
    const float len = glm::length(n);
    vertices.push_back({glm::vec3(transform * glm::vec4(v.position, 1.0f)), len > 0 ? n / len : glm::vec3(0, 1, 0)});
  }
  for (auto i : other.indices) indices.push_back(base + i);
}

namespace {
DrawUnit unit_of(const MeshData& m, std::uint32_t first, std::uint32_t end) {
  DrawUnit u{first, end - first, {}};
  for (std::uint32_t i = first; i < end; ++i) u.bounds.extend(m.vertices[m.indices[i]].position);
  return u;
}
std::uint32_t units_end(const MeshData& m) { return m.units.empty() ? 0 : m.units.back().first_index + m.units.back().index_count; }
}  // namespace

void MeshData::close_unit() {
  const std::uint32_t first = units_end(*this), end = static_cast<std::uint32_t>(indices.size());
  if (end > first) units.push_back(unit_of(*this, first, end));
}

std::vector<DrawUnit> MeshData::draw_units() const {
  std::vector<DrawUnit> out = units;
  const std::uint32_t first = units_end(*this), end = static_cast<std::uint32_t>(indices.size());
  if (end > first) out.push_back(unit_of(*this, first, end));
  return out;
}

ClusteredUnits cluster_units(const MeshData& mesh, std::uint32_t max_triangles) {
  ClusteredUnits out;
  out.units = mesh.draw_units();
  out.first_cluster.push_back(0);
  const std::uint64_t run = 3 * static_cast<std::uint64_t>(max_triangles);  // indices; no overflow for any size
  for (const DrawUnit& u : out.units) {
    if (max_triangles == 0 || u.index_count <= run) {
      out.clusters.push_back(u);
    } else {
      const auto step = static_cast<std::uint32_t>(run);  // less than the unit's index count
      for (std::uint32_t first = u.first_index, end = u.first_index + u.index_count; first < end; first += std::min(step, end - first))
        out.clusters.push_back(unit_of(mesh, first, first + std::min(step, end - first)));
    }
    out.first_cluster.push_back(static_cast<std::uint32_t>(out.clusters.size()));
  }
  return out;
}

namespace {
// Adds a quad with corners a, b, c, d (counter-clockwise seen from the side `normal` points to).
void add_quad(MeshData& m, glm::vec3 a, glm::vec3 b, glm::vec3 c, glm::vec3 d, glm::vec3 normal) {
  const auto base = static_cast<std::uint32_t>(m.vertices.size());
  for (const auto& p : {a, b, c, d}) m.vertices.push_back({p, normal});
  for (std::uint32_t i : {0u, 1u, 2u, 0u, 2u, 3u}) m.indices.push_back(base + i);
}
}  // namespace

MeshData make_plane(float size_x, float size_z) {
  MeshData m;
  const float x = size_x / 2, z = size_z / 2;
  add_quad(m, {-x, 0, z}, {x, 0, z}, {x, 0, -z}, {-x, 0, -z}, {0, 1, 0});
  return m;
}

MeshData make_box(const glm::vec3& size) {
  MeshData m;
  const glm::vec3 h = size / 2.0f;
  // +x, -x, +y, -y, +z, -z faces.
  add_quad(m, {h.x, -h.y, h.z}, {h.x, -h.y, -h.z}, {h.x, h.y, -h.z}, {h.x, h.y, h.z}, {1, 0, 0});
  add_quad(m, {-h.x, -h.y, -h.z}, {-h.x, -h.y, h.z}, {-h.x, h.y, h.z}, {-h.x, h.y, -h.z}, {-1, 0, 0});
  add_quad(m, {-h.x, h.y, h.z}, {h.x, h.y, h.z}, {h.x, h.y, -h.z}, {-h.x, h.y, -h.z}, {0, 1, 0});
  add_quad(m, {-h.x, -h.y, -h.z}, {h.x, -h.y, -h.z}, {h.x, -h.y, h.z}, {-h.x, -h.y, h.z}, {0, -1, 0});
  add_quad(m, {-h.x, -h.y, h.z}, {h.x, -h.y, h.z}, {h.x, h.y, h.z}, {-h.x, h.y, h.z}, {0, 0, 1});
  add_quad(m, {h.x, -h.y, -h.z}, {-h.x, -h.y, -h.z}, {-h.x, h.y, -h.z}, {h.x, h.y, -h.z}, {0, 0, -1});
  return m;
}

MeshData make_sphere(float radius, int segments, int rings) {
  MeshData m;
  for (int r = 0; r <= rings; ++r) {
    const float theta = std::numbers::pi_v<float> * static_cast<float>(r) / static_cast<float>(rings);
    for (int s = 0; s <= segments; ++s) {
      const float phi = 2 * std::numbers::pi_v<float> * static_cast<float>(s) / static_cast<float>(segments);
      const glm::vec3 n(std::sin(theta) * std::cos(phi), std::cos(theta), -std::sin(theta) * std::sin(phi));
      m.vertices.push_back({radius * n, n});
    }
  }
  const auto row = static_cast<std::uint32_t>(segments + 1);
  for (std::uint32_t r = 0; r < static_cast<std::uint32_t>(rings); ++r) {
    for (std::uint32_t s = 0; s < static_cast<std::uint32_t>(segments); ++s) {
      const std::uint32_t a = r * row + s, b = a + row;
      m.indices.insert(m.indices.end(), {a, b, a + 1, a + 1, b, b + 1});
    }
  }
  return m;
}

MeshData make_lattice(float width, float height, int bars_x, int bars_y, float bar_width) {
  MeshData m;
  const MeshData vertical = make_box({bar_width, height, bar_width});
  const MeshData horizontal = make_box({width, bar_width, bar_width});
  for (int i = 0; i < bars_x; ++i) {
    const float x = bars_x == 1 ? 0.0f : -width / 2 + width * static_cast<float>(i) / static_cast<float>(bars_x - 1);
    m.append(vertical, glm::translate(glm::mat4(1), glm::vec3(x, 0, 0)));
  }
  for (int j = 0; j < bars_y; ++j) {
    const float y = bars_y == 1 ? 0.0f : -height / 2 + height * static_cast<float>(j) / static_cast<float>(bars_y - 1);
    m.append(horizontal, glm::translate(glm::mat4(1), glm::vec3(0, y, 0)));
  }
  return m;
}

MeshData make_tube(const std::vector<glm::vec3>& points, const std::vector<float>& radii, int sides) {
  MeshData m;
  const std::size_t n = points.size();
  if (n < 2 || radii.size() != n || sides < 3) return m;
  // Ring frames: the first normal is any perpendicular of the first tangent; each next one is the
  // previous normal with its component along the new tangent removed (parallel transport).
  glm::vec3 normal(0);
  for (std::size_t i = 0; i < n; ++i) {
    const glm::vec3 prev = points[i > 0 ? i - 1 : 0], next = points[i + 1 < n ? i + 1 : n - 1];
    glm::vec3 tangent = next - prev;
    tangent = glm::length(tangent) > 0 ? glm::normalize(tangent) : glm::vec3(0, 1, 0);
    if (i == 0) {
      const glm::vec3 helper = std::abs(tangent.y) < 0.9f ? glm::vec3(0, 1, 0) : glm::vec3(1, 0, 0);
      normal = glm::normalize(glm::cross(helper, tangent));
    } else {
      const glm::vec3 projected = normal - tangent * glm::dot(normal, tangent);
      if (glm::length(projected) > 1e-6f) normal = glm::normalize(projected);
    }
    const glm::vec3 binormal = glm::cross(tangent, normal);
    for (int s = 0; s < sides; ++s) {
      const float a = 2 * std::numbers::pi_v<float> * static_cast<float>(s) / static_cast<float>(sides);
      const glm::vec3 radial = std::cos(a) * normal + std::sin(a) * binormal;
      m.vertices.push_back({points[i] + radii[i] * radial, radial});
    }
  }
  const auto ring = static_cast<std::uint32_t>(sides);
  for (std::uint32_t i = 0; i + 1 < static_cast<std::uint32_t>(n); ++i) {
    for (std::uint32_t s = 0; s < ring; ++s) {
      const std::uint32_t a = i * ring + s, b = i * ring + (s + 1) % ring, c = a + ring, d = b + ring;
      m.indices.insert(m.indices.end(), {a, b, d, a, d, c});
    }
  }
  return m;
}

MeshData make_beam(const glm::vec3& a, const glm::vec3& b, float width) {
  const glm::vec3 axis = b - a;
  const float length = glm::length(axis);
  if (!(length > 0)) return {};
  const glm::vec3 dir = axis / length;
  const glm::vec3 helper = std::abs(dir.y) < 0.9f ? glm::vec3(0, 1, 0) : glm::vec3(1, 0, 0);
  const glm::vec3 side = glm::normalize(glm::cross(helper, dir));
  const glm::vec3 up = glm::cross(dir, side);
  // The box's x runs along the beam; the columns are a right-handed frame (no mirroring).
  glm::mat4 m(glm::vec4(dir, 0), glm::vec4(up, 0), glm::vec4(glm::cross(dir, up), 0), glm::vec4((a + b) * 0.5f, 1));
  MeshData out;
  out.append(make_box({length, width, width}), m);
  return out;
}

}  // namespace penumbra::scene
