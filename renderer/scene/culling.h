#pragma once
// Culling of draw units (scene/mesh.h) against what a pass rasterizes: the camera's view volume,
// or a shadow map's. GL-free: the planner's tests and an engine's own loop can use it.
#include <cstdint>
#include <vector>

#include <glm/mat4x4.hpp>
#include <glm/vec2.hpp>

#include <penumbra/scene/mesh.h>

namespace penumbra::scene {

enum class CullVolume {
  view,    // the six planes of the clip volume: what the camera sees
  caster,  // a shadow map's four sides only: its box extended without end along the light's rays,
           // so that a caster in front of the fitted near plane (or behind the far one) that covers
           // a texel is still drawn; anything dropped covers no texel of the map
};

// False only when all eight corners of `box` (in the space `clip_from_box` maps to clip space)
// lie outside one plane of `volume` (x = ±w, y = ±w; for view also z = ±w): such a box cannot
// produce a fragment, so dropping it changes no pixel. Conservative otherwise. For an affine
// `clip_from_box` (last row 0 0 0 1: the sun's maps, w = 1) the corners' bounds are taken as the
// centre's image ± |M| · half extent, widened by rounding's margin (16 float epsilons of the terms'
// magnitude): a quarter of the work, and never a box dropped that the corners keep.
bool may_touch(const glm::mat4& clip_from_box, const Aabb& box, CullVolume volume);

// The index ranges of `units` that may touch `volume`, neighbouring units merged into one range,
// and the triangles they hold: one multi-draw's arguments.
struct DrawRanges {
  std::vector<std::uint32_t> first_index;
  std::vector<std::uint32_t> index_count;
  std::uint64_t triangles = 0;
};
DrawRanges cull_units(const std::vector<DrawUnit>& units, const glm::mat4& clip_from_mesh, CullVolume volume);

// Culling against many orthographic windows of one light view (a virtual shadow map's pages):
// each unit's footprint across the light, the x, y bounds of its box's corners in light space,
// taken once (centre and extent for an affine light_from_mesh, as may_touch; the corners divided by
// w otherwise); then a window is a rectangle test. A unit whose footprint misses the window
// [lo, hi] is one that may_touch(ortho(lo.x, hi.x, lo.y, hi.y, near, far) · light_from_mesh,
// bounds, CullVolume::caster) drops (that volume's four sides are the window's edges; the two differ
// only by rounding at an edge), without transforming eight corners per unit and window.
struct Footprint {
  glm::vec2 lo{0}, hi{-1};  // empty by default
};
std::vector<Footprint> unit_footprints(const std::vector<DrawUnit>& units, const glm::mat4& light_from_mesh);
DrawRanges cull_units(const std::vector<DrawUnit>& units, const std::vector<Footprint>& footprints, const Footprint& window);

// The same by clusters (mesh.h's cluster_units): a window keeps the clusters whose footprints meet
// it, among those of the units whose footprints do (a unit's box holds its clusters' boxes, so the
// unit test drops no cluster the window would keep; it spares testing the clusters of units
// elsewhere). Neighbouring clusters merge into one range, a unit kept whole into its own.
struct ClusterFootprints {
  std::vector<Footprint> units, clusters;
};
ClusterFootprints cluster_footprints(const ClusteredUnits& c, const glm::mat4& light_from_mesh);
DrawRanges cull_clusters(const ClusteredUnits& c, const ClusterFootprints& footprints, const Footprint& window);

// By clusters against one volume (a shadow map's or a cascade's, whose matrix may be a spot's
// perspective or a fitted crop): the clusters may_touch keeps, among the units it keeps. The same
// plane test as cull_units, so a unit it drops is dropped here too, and a cluster, whose box lies in
// its unit's, is kept only where its own corners say so. Footprints would need an orthographic light
// frame shared by the windows (the virtual map's); here each map has its own matrix, tested once.
DrawRanges cull_clusters(const ClusteredUnits& c, const glm::mat4& clip_from_mesh, CullVolume volume);

}  // namespace penumbra::scene
