#pragma once
// The frame: shadow-map pass(es) → (moments blur) → shading pass → (PCSS requirement), each
// with a contract:
//   shadow_map        reads the scene, writes the depth map of every cascade (and, for VSM, MSM
//                     and EVSM, the moments) into its region of the shadow atlas
//   vsm_blur          reads/writes the moments (the filtered-moments techniques VSM, MSM, EVSM)
//   gbuffer + post    screen-space techniques only (screen_space.h); they use one map
//   shading           reads the maps, writes lit colour (sRGB 8-bit) and visibility (float)
//   pcss_requirement  adaptive PCSS with per-pixel requirement only: reduces the shading pass's
//                     per-pixel c / r_filter to a maximum per cascade, read back one frame later
// A frame runs only the passes its technique needs; FrameInfo lists those that ran.
//
// Storage: every map is a region of one atlas texture, surrounded by a guard band cleared to the
// far depth. `adaptive.storage = subrect` keeps an atlas sized for adaptive.max_texels per cascade
// and renders into the part the frame needs (UVs scaled accordingly); `realloc` sizes the atlas
// to the frame and reallocates it whenever a resolution changes.
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

struct CascadeInfo {
  LightFrame light;
  int resolution_texels = 0;
  double required_texels = 0;     // the rule's requirement before clamping (adaptive; else 0)
  float split_near_ws = 0;        // camera view-depth range the cascade covers
  float split_far_ws = 0;
  int atlas_x = 0, atlas_y = 0;   // the region's corner in the atlas (texels)
};

// The per-pixel PCSS requirement of the frame it was measured in (adaptive, pcss = per_pixel).
struct PcssRequirementInfo {
  bool valid = false;              // false until a frame has been measured
  std::vector<double> required_texels;  // per cascade: c · max over pixels of 1 / r_filter_uv
  double evaluated_pixels = 0;     // pixels that ran a PCSS filter
  double clamped_fraction = 0;     // of those, share whose radius was raised to the minimum penumbra
  double above_max_fraction = 0;   // share that needed more than adaptive.max_texels
};

struct FrameInfo {
  LightFrame light;                // cascade 0
  int resolution_texels = 0;       // cascade 0
  int width_px = 0;
  int height_px = 0;
  std::vector<std::string> passes;
  float filter_radius_texels = 0;  // PCF/RPCF/VSM/MSM/EVSM radius in texels (directional light; spot: at mid depth)
  std::vector<CascadeInfo> cascades;  // one entry when not cascaded
  bool adaptive = false;
  std::string resolution_source;   // "fixed", "rule", "pcss_per_pixel", "pcss_min_penumbra"
  std::string storage;             // "subrect" or "realloc"
  int atlas_width = 0, atlas_height = 0;
  bool reallocated = false;        // the atlas was (re)allocated this frame
  PcssRequirementInfo pcss_requirement;  // as used for this frame's resolution (measured one frame earlier)
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
  // The last frame's shadow atlas (for debug views); 0 before the first frame.
  GLuint shadow_map_texture() const;
  // Forgets the adaptive state (hysteresis, last PCSS requirement), e.g. after a scene change.
  void reset_adaptive();
  // Tints the image by cascade (debug overlay).
  void set_show_cascades(bool on) { show_cascades_ = on; }

  io::Image8 read_color() const;       // RGBA, sRGB-encoded
  io::ImageF read_visibility() const;  // one channel
  io::ImageF read_shadow_depth(int cascade = 0) const;  // a depth map of the last frame, one channel
  // The input (hard) visibility of the last screen-space frame, before its post passes.
  io::ImageF read_screen_space_input() const;
  // The last frame's per-pixel PCSS requirement (adaptive, pcss = per_pixel), two channels:
  // 1 / filter radius in map uv (0 where no filter ran) and cascade + 0.5 where the minimum
  // penumbra clamped it; what pcss_requirement.comp reduces.
  io::ImageF read_pcss_requirement() const;

 private:
  struct Maps;
  struct Targets;
  struct Adaptive;
  // `gbuffer`: the first camera pass of a screen-space technique.
  const gl::Program& shading_program(const ShadowSettings& s, bool gbuffer = false);
  // The program built from `stages` with `defines`, compiled on first use and kept under `key`.
  const gl::Program& cached_program(const std::string& key, const std::vector<gl::ShaderStage>& stages,
                                    const std::vector<gl::ShaderDefine>& defines = {});
  void draw_scene(const gl::Program& program, bool shading);

  gl::ShaderLibrary shaders_;
  gl::Program depth_program_;
  gl::Program requirement_program_;
  std::map<std::string, gl::Program> programs_;  // shading, moments and blur programs by key
  gl::Sampler cmp_linear_, cmp_nearest_, raw_nearest_, moments_linear_;
  scene::Scene scene_;
  std::vector<std::unique_ptr<scene::GpuMesh>> meshes_;
  std::unique_ptr<Maps> maps_;
  std::unique_ptr<Targets> targets_;
  std::unique_ptr<Adaptive> adaptive_;
  std::vector<CascadeInfo> last_cascades_;
  bool show_cascades_ = false;
  std::unique_ptr<ScreenSpace> screen_space_;  // made on the first screen-space frame
  std::map<int, std::vector<glm::vec2>> poisson_;
};

}  // namespace penumbra::shadows
