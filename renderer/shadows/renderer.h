#pragma once
// The frame: shadow-map pass(es) → (VSM blur) → (G-buffer and screen-space passes) → shading
// pass, each with a contract:
//   shadow_map  reads the scene, writes the depth map (and, for VSM, the moments)
//   vsm_blur    reads/writes the moments (VSM only)
//   gbuffer + post passes   screen-space techniques only (screen_space.h)
//   shading     reads the maps, writes lit colour (sRGB 8-bit) and visibility (float)
// A frame runs only the passes its technique needs; FrameInfo lists those that ran.
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "gl/context.h"
#include "gl/objects.h"
#include "gl/shader_library.h"
#include "gl/timer.h"
#include "io/image_io.h"
#include "scene/scene.h"
#include "shadows/fitting.h"
#include "shadows/settings.h"

namespace penumbra::shadows {

struct FrameInfo {
  LightFrame light;
  int resolution_texels = 0;
  int width_px = 0;
  int height_px = 0;
  std::vector<std::string> passes;
  float filter_radius_texels = 0;  // PCF/VSM radius in texels (directional light; spot: at mid depth)
};

// Poisson-disk taps in the unit disk (deterministic best-candidate set, outermost tap at radius 1).
std::vector<glm::vec2> poisson_disk(int taps);

class ScreenSpace;

class Renderer {
 public:
  Renderer();
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  // Uploads the scene's meshes; the scene is copied (camera and light may be edited later
  // through `scene()` without re-uploading).
  void set_scene(const scene::Scene& s);
  scene::Scene& scene() { return scene_; }

  // Renders one frame at width × height. Throws std::runtime_error on GL failure (e.g. a map too
  // large for the device), naming the pass.
  FrameInfo render(const ShadowSettings& settings, int width_px, int height_px, gl::PassTimer* timer = nullptr);

  // Copies the last frame's lit colour into framebuffer `target` (0: the window) at its size.
  void present(GLuint target, int width_px, int height_px) const;
  // The last frame's depth map (for debug views); 0 before the first frame.
  GLuint shadow_map_texture() const;

  io::Image8 read_color() const;       // RGBA, sRGB-encoded
  io::ImageF read_visibility() const;  // one channel
  io::ImageF read_shadow_depth() const;  // the depth map of the last frame, one channel
  // The input (hard) visibility of the last screen-space frame, before its post passes.
  io::ImageF read_screen_space_input() const;

 private:
  struct Maps;
  struct Targets;
  // `gbuffer`: the first camera pass of a screen-space technique.
  const gl::Program& shading_program(const ShadowSettings& s, bool gbuffer = false);
  void draw_scene(const gl::Program& program, bool shading);

  gl::ShaderLibrary shaders_;
  gl::Program depth_program_;
  gl::Program moments_program_;
  gl::Program blur_program_;
  std::map<std::string, gl::Program> shading_programs_;
  gl::Sampler cmp_linear_, cmp_nearest_, raw_nearest_, moments_linear_;
  scene::Scene scene_;
  std::vector<std::unique_ptr<scene::GpuMesh>> meshes_;
  std::unique_ptr<Maps> maps_;
  std::unique_ptr<Targets> targets_;
  std::map<int, std::vector<glm::vec2>> poisson_;
  std::unique_ptr<ScreenSpace> screen_space_;  // made on the first screen-space frame
};

}  // namespace penumbra::shadows
