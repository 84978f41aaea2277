#pragma once
// What each pixel of a camera view shows: the world position of its surface and which object it
// belongs to. The probe rasterizes the scene's meshes with the same transform as the renderer's
// camera pass (u_view_projection · u_model · position, `invariant gl_Position`), so its pixels
// are the renderer's pixels. Used to reproject a frame into the previous one (flicker) and to
// tell which object a pixel shows (thin features). Needs a current GL 4.5 context.
#include <memory>
#include <vector>

#include <glm/glm.hpp>

#include "gl/objects.h"
#include "io/image_io.h"
#include "scene/scene.h"

namespace penumbra::metrics {

// The camera pass's view-projection for an image of width × height pixels (as the renderer
// computes it).
glm::mat4 camera_view_projection(const scene::Camera& camera, int width_px, int height_px);

class SurfaceProbe {
 public:
  // Uploads the scene's meshes (its own copy, one per distinct mesh; the scene's object order is kept).
  explicit SurfaceProbe(const scene::Scene& scene);
  ~SurfaceProbe();
  SurfaceProbe(const SurfaceProbe&) = delete;
  SurfaceProbe& operator=(const SurfaceProbe&) = delete;

  // Four channels, rows top-down like Renderer::read_visibility: world x, y, z of the nearest
  // surface and its object's index + 1 (0 where no surface was drawn).
  io::ImageF render(const scene::Camera& camera, int width_px, int height_px);
  // Takes the placements of `scene`'s objects (moved objects: the constructor's scene posed,
  // scene::pose_objects). Throws std::invalid_argument when it has another number of objects.
  void set_models(const scene::Scene& scene);

 private:
  struct Gpu;
  std::unique_ptr<Gpu> gpu_;
  std::vector<glm::mat4> models_;
};

}  // namespace penumbra::metrics
