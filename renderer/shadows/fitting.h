#pragma once
// The light's view and projection, optionally fitted to the potential shadow receivers
// PSR = L ∩ V ∩ S (light volume, camera frustum, scene bounds) as in Eisemann et al. and
// Kreuzer 2017 §3.4.2/§5.1.2. Casters outside the fitted depth range are kept by depth clamp.
#include <array>
#include <vector>

#include <glm/glm.hpp>

#include <penumbra/scene/scene.h>

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

// Cascades for a directional light: the camera's view depth range where receivers can be seen
// (PSR) is split, and each slice gets its own orthographic window in the shared light view and
// depth range (so one receiver-plane gradient serves all), fitted to the slice's receivers (the
// scene bounds clipped by the slice's frustum). Stabilized cascades round the window's size up to
// quarter-octave steps (small camera moves keep it) and snap its centre to whole texels, so
// shadow edges do not crawl as the camera moves.
struct CascadeRequest {
  int count = 1;
  float lambda = 0.75f;                  // adaptive::cascade_splits
  bool stabilize = true;
  float camera_aspect = 16.0f / 9.0f;
  std::vector<int> resolution_texels;    // per cascade (snapping, padding); missing entries use the last
  float pad_texels = 0;
  float pad_ws = 0;
  bool fit = true;                       // one map only: fit it to the receivers (cascades always are)
};

struct Cascades {
  std::vector<LightFrame> frames;
  std::vector<float> splits_ws;  // count + 1 camera view depths; cascade i covers [splits[i], splits[i+1]]
};

// count <= 1, a spot light (never cascaded) or an empty PSR give one frame, fitted as
// `request.fit` says (an empty PSR cannot be fitted). splits_ws always has frames + 1 entries.
Cascades compute_cascades(const scene::Scene& scene, const CascadeRequest& request);

// What a directional light's shadows must hold, in the frame of `rotation` (world → light: x and y
// across the light, -z along it): the objects that can cast onto the potential receivers, within
// 1000 receiver sizes of them (farther casters are depth-clamped), and the receivers; lo and hi
// with z the depth along the light (a distance along -z). The one bounded fit of the sun's maps
// and cascades (compute_light_frame) and of its virtual shadow map (sun_virtual_view): an object
// at 1e20 or a box of 1e30 stretches neither.
struct SunRegion {
  glm::dvec3 lo{0}, hi{0};
};
SunRegion sun_shadow_region(const scene::Scene& scene, float camera_aspect, const glm::dmat3& rotation);

// Diagonal of what a directional light's frame holds: the objects that can cast onto the
// potential receivers, within 1000 receiver sizes of them (not the scene's bounds: one object at
// 1e20 would make it 1e20).
float shadow_region_diagonal_ws(const scene::Scene& scene, float camera_aspect);

// Camera view-depth range [near, far] of the potential receivers; {cam near, cam far} when empty.
std::array<float, 2> receiver_depth_range(const scene::Scene& scene, float camera_aspect);

// PSR vertices (world space) for the scene's camera and light; empty when nothing is visible.
std::vector<glm::dvec3> potential_receivers(const scene::Scene& scene, float camera_aspect);

}  // namespace penumbra::shadows
