#pragma once
// The light's view and projection, optionally fitted to the potential shadow receivers
// PSR = L ∩ V ∩ S (light volume, camera frustum, scene bounds) as in Eisemann et al. and
// Kreuzer 2017 §3.4.2/§5.1.2. Casters outside the fitted depth range are kept by depth clamp.
#include <array>
#include <vector>

#include <glm/glm.hpp>

#include "scene/scene.h"

namespace penumbra::shadows {

using Polygon = std::vector<glm::dvec3>;
using Polyhedron = std::vector<Polygon>;  // convex, as a list of faces

Polyhedron box_polyhedron(const scene::Aabb& box);
// Keeps the part where dot(plane.xyz, p) + plane.w >= 0, closing the cut with a cap face.
Polyhedron clip(const Polyhedron& poly, const glm::dvec4& plane);
// The six inward planes of the frustum of a view-projection matrix (GL clip space).
std::array<glm::dvec4, 6> frustum_planes(const glm::dmat4& view_projection);
// Distinct vertices of a polyhedron.
std::vector<glm::dvec3> vertices(const Polyhedron& poly);

struct LightFrame {
  glm::mat4 view{1};        // world → light view (looks down -z)
  glm::mat4 projection{1};  // light view → clip, fitting crop included
  bool perspective = false;
  float near_ws = 0;        // light-view depth range covered by the map's depth
  float far_ws = 1;
  float fov_deg = 0;        // spot: full field of view of the unfitted projection
  // Directional: world-space side of the square the map covers (after fitting).
  // Spot: width of the unfitted near plane, 2 near tan(fov/2); UV at depth z spans
  // 2 z tan(fov/2) / s_xy world units.
  float extent_ws = 1;
  float s_xy = 1;           // fitting scale: how much the fit magnifies UV (1 when unfitted)
  bool fitted = false;
  bool receivers_visible = true;  // false when L ∩ V ∩ S is empty (nothing can show a shadow)

  glm::mat4 view_projection() const { return projection * view; }
  // World-space size of one texel at light-view depth `depth_ws` for a map of `resolution` texels.
  float texel_ws(float depth_ws, int resolution) const;
};

struct FitRequest {
  bool fit = true;
  float camera_aspect = 16.0f / 9.0f;
  int resolution_texels = 2048;
  float pad_texels = 0;  // filter radius in texels (capped at a quarter of the map)
  float pad_ws = 0;      // extra world-space margin (e.g. the PCSS search radius)
};

LightFrame compute_light_frame(const scene::Scene& scene, const FitRequest& request);

// PSR vertices (world space) for the scene's camera and light; empty when nothing is visible.
std::vector<glm::dvec3> potential_receivers(const scene::Scene& scene, float camera_aspect);

}  // namespace penumbra::shadows
