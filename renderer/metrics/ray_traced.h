#pragma once
// The area light's visibility by ray tracing (Embree): for each pixel the camera ray finds the
// surface, then shadow rays toward points of the light decide, without a shadow map, without a
// bias and at no resolution, whether the light is seen. This is the yardstick the shadow-map
// reference (ground_truth.h: the mean of hard shadows from maps) cannot be on the outdoor town:
// there four 4096² cascades per sample differ from four 8188² ones by RMSE 0.09, about the errors
// being measured, on thin receivers (the crane's lattice, the fence's bars, branches) whose
// self-shadowing the maps' texel-sized biases decide.
//
// Directional lights only (the sun disk of light.size degrees): per pixel, per_side² directions
// stratified over the disk with a jitter of the pixel's own (a hash of the pixel and the sample),
// mapped like ground_truth.h's samples (concentric map, the same tangent basis), so the mean
// converges per pixel instead of showing per_side² copies of a caster. Pixels without a surface
// are 1 (the sky is lit, as in the renderer's visibility image). A shadow ray starts 1e-4 of the
// camera distance (at least 1 mm) off the surface, on the side the camera sees.
//
// Also hard shadows toward the light's centre with and without some objects as blockers
// (hard_visibility_split): where Embree is built in and the light is directional, the demo's
// thin-caster masks (apps/demo/measurement.cpp) come from these, exact; without Embree, or for a
// spot light, from hard shadows of four 4096² cascades rendered with and without those objects.
#include <memory>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "io/image_io.h"
#include "scene/scene.h"

namespace penumbra::metrics {

class RayTracedScene {
 public:
  // Builds the acceleration structure over every object's triangles in world space. Throws
  // std::runtime_error with Embree's message if the device cannot be created.
  explicit RayTracedScene(const scene::Scene& scene);
  ~RayTracedScene();
  RayTracedScene(const RayTracedScene&) = delete;
  RayTracedScene& operator=(const RayTracedScene&) = delete;

  // One channel, rows top-down like Renderer::read_visibility: the share of per_side² light
  // directions each pixel's surface sees. Throws std::invalid_argument for a spot light or
  // per_side < 1. `threads` 0: one per hardware thread.
  io::ImageF area_light_visibility(const scene::Camera& camera, const scene::Light& light, int width_px, int height_px,
                                   int per_side, int threads = 0) const;

  // One channel, 255 where the pixel's surface faces the light (the interpolated normal, turned
  // to the side the camera sees as the shader turns it, has a positive dot product with the
  // direction to the light's centre), 0 elsewhere and on the sky. Visibility matters only there:
  // on the other side the shading's max(n·l, 0) is 0 whatever a map says.
  io::Image8 facing_light(const scene::Camera& camera, const scene::Light& light, int width_px, int height_px, int threads = 0) const;

  // Hard shadows toward the centre of a directional light: one shadow ray per pixel from the
  // pixel's surface (the camera rays and shadow-ray origins of area_light_visibility). `all` is 1
  // where nothing blocks that ray and 0 where something does; `without` the same with the objects
  // named in `excluded_names` left out as blockers (the camera still sees them, and they see the
  // light past themselves: their self-shadowing counts in `all` only). One channel, rows top-down,
  // the sky 1 in both. Names that no object has are ignored. Each distinct name has its own
  // Embree geometry mask bit: a pixel lit in `all` costs one shadow ray, a shadowed one a second
  // ray that skips the left-out bits. Where the library ignores ray masks (built without
  // EMBREE_RAY_MASK) or a left-out name shares a bit (past the 32nd distinct name) the second
  // ray steps past the left-out objects' hits instead, with the same result. Throws
  // std::invalid_argument for a spot light or an empty image.
  struct HardVisibility {
    io::ImageF all, without;
  };
  HardVisibility hard_visibility_split(const scene::Camera& camera, const scene::Light& light, int width_px, int height_px,
                                       const std::vector<std::string>& excluded_names, int threads = 0) const;

  std::size_t triangles() const { return triangles_; }

 private:
  struct Hit {
    glm::vec3 position, geometric, shading;  // normals on the side the camera sees
  };
  bool primary(const glm::vec3& origin, const glm::vec3& direction, Hit& out) const;
  // Calls seen(pixel, hit) for every pixel (y * width + x) whose camera ray hits the scene, rows
  // spread over `threads` (0: one per hardware thread); defined and used in ray_traced.cpp.
  template <class F>
  void for_each_seen_pixel(const scene::Camera& camera, int width_px, int height_px, int threads, F seen) const;

  struct Embree;
  std::unique_ptr<Embree> embree_;
  std::size_t triangles_ = 0;
};

}  // namespace penumbra::metrics
