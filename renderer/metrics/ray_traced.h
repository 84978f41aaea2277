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
#include <memory>

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

  std::size_t triangles() const { return triangles_; }

 private:
  struct Hit {
    glm::vec3 position, geometric, shading;  // normals on the side the camera sees
  };
  bool primary(const glm::vec3& origin, const glm::vec3& direction, Hit& out) const;

  struct Embree;
  std::unique_ptr<Embree> embree_;
  std::size_t triangles_ = 0;
};

}  // namespace penumbra::metrics
