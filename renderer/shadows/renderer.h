#pragma once
// The frame: a plan (frame_plan.h: cascades, the resolution rule and its hysteresis, the atlas
// layout, which passes run), then the passes it lists (passes.h): shadow_map → (vsm_blur) →
// (gbuffer → post) → shading → (pcss_requirement). FrameInfo lists those that ran.
//
// Storage: every map is a region of one atlas texture, surrounded by a guard band cleared to the
// far depth. `adaptive.storage = subrect` keeps an atlas sized for adaptive.max_texels per cascade
// and renders into the part the frame needs (UVs scaled accordingly); `realloc` sizes the atlas
// to the frame and reallocates it whenever a resolution changes.
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <penumbra/gl/context.h>
#include <penumbra/gl/objects.h>
#include <penumbra/gl/shader_library.h>
#include <penumbra/gl/timer.h>
#include <penumbra/io/image_io.h>
#include <penumbra/scene/gpu_mesh.h>
#include <penumbra/scene/scene.h>
#include <penumbra/shadows/fitting.h>
#include <penumbra/shadows/frame_plan.h>
#include <penumbra/shadows/pass_work.h>
#include <penumbra/shadows/settings.h>
#include <penumbra/shadows/virtual_shadow_map.h>

namespace penumbra::shadows {

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
  // Triangles drawn this frame after culling: into each map or cascade (cascades order), by each
  // camera pass together (G-buffer and shading), and the scene's total for one full draw.
  std::vector<std::uint64_t> map_triangles;
  std::uint64_t camera_triangles = 0;
  std::uint64_t scene_triangles = 0;
  std::vector<PassWork> work;  // per pass (or step) run, in order; empty unless the renderer counts work (pass_work.h)
  // The sun's virtual shadow map (map.virtual_pages): what the frame marked and drew, the memory it
  // holds (the pool's resident pages and every level's table; the pool is allocated whole), and
  // the shading's pixels by where they found their pages.
  struct Virtual {
    int page_texels = 0;                         // texels per page side
    int pool_pages_per_side = 0;                 // the pool: this many² slots
    float near_ws = 0, far_ws = 0;               // the light-space depth range the pages hold (sun_virtual_view)
    VirtualMapStats pages;                       // marked (requested), cached, drawn, missing, floor, evicted, resident
    int search_pages = 0;                        // PCSS: of those, the blocker searches' (marked first)
    std::vector<std::int64_t> pixels_per_level;  // the marking's pixels on each level (PCSS: its filter's; lit pixels none)
    std::int64_t unmarked = 0;                   // pixels beyond the coarsest level
    std::uint64_t resident_bytes = 0, table_bytes = 0, pool_bytes = 0;
    std::uint64_t at_level = 0, coarser = 0, none = 0;  // shaded pixels: on their level, a coarser one, none (lit)
    // map.virtual_marks_late: the pages drawn are the previous frame's marks (pixels_per_level and
    // unmarked are that frame's), with `region_floor` pages over the sun's region; the shaded
    // pixels' counts are the previous frame's too (`shaded_of_previous_frame`; none on a first frame).
    bool marks_late = false;
    int region_floor = 0;
    bool shaded_of_previous_frame = false;
    // Read-backs of what this frame's GPU work wrote, each a wait for it: the marks (PCSS: two) and
    // the shaded pixels' counts without map.virtual_marks_late, none with it.
    int sync_reads = 0;
  };
  std::optional<Virtual> virtual_map;
};

// The frame's shadow memory in 4-byte texels: the atlas, or the virtual map's resident pages and
// its page tables (the pool is allocated whole; what the view holds is what the frame needs).
double shadow_memory_texels(const FrameInfo& info);

struct FrameResources;
class Pass;

class Renderer {
 public:
  Renderer();
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  // Uploads the scene's meshes, once per distinct mesh (instances share it); the scene is copied
  // (camera and light may be edited later through `scene()` without re-uploading). The maps, the
  // cascades and the virtual map's pages cull casters by clusters of at most `cluster_triangles`
  // (scene::cluster_units; 0: by whole units).
  void set_scene(const scene::Scene& s, std::uint32_t cluster_triangles = scene::kClusterTriangles);
  scene::Scene& scene() { return scene_; }
  std::size_t uploaded_meshes() const { return meshes_.copies(); }

  // Renders one frame at width × height. Throws std::runtime_error on GL failure (e.g. a map too
  // large for the device), naming the pass.
  FrameInfo render(const ShadowSettings& settings, int width_px, int height_px, gl::PassTimer* timer = nullptr);

  // Copies the last frame's lit colour into framebuffer `target` (0: the window) at its size.
  void present(GLuint target, int width_px, int height_px) const;
  // The last frame's shadow atlas (for debug views); 0 before the first frame.
  GLuint shadow_map_texture() const;
  // The min-max depth pyramid of the atlas as the last frame that built one left it (PCSS with
  // pcss.hierarchical): level k holds min and max depth over 2^(k+1)-texel blocks; 0 when none was.
  GLuint depth_minmax_texture() const;
  // Forgets the adaptive state (hysteresis, last PCSS requirement), e.g. after a scene change.
  void reset_adaptive();
  // The next frame's camera is not where the last frame's was heading (a cut): with
  // map.virtual_marks_late it draws no page of the last frame's marks (those pages lie where the
  // camera was), only the coarse floor, and marks for the frame after.
  void camera_cut();
  // Tints the image by cascade (debug overlay).
  void set_show_cascades(bool on) { show_cascades_ = on; }
  // Counts each pass's work with pipeline statistics queries (FrameInfo::work), read at the end of
  // the frame (a wait for the frame's GPU work: for measuring runs; off by default).
  void set_count_work(bool on) { count_work_ = on; }
  // Draws the last frame's shading pass again with its counting variant and returns what its
  // shadow lookups read per pixel shown (pass_work.h). Writes no image and changes no state a
  // later frame reads (maps, pages, the adaptive controller), so a measured run can count any
  // frame it times, untimed. Throws std::logic_error before the first frame.
  ShadowReads count_shading_reads();

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
  gl::ShaderLibrary shaders_;
  scene::Scene scene_;
  scene::GpuMeshes meshes_;
  std::unique_ptr<FrameResources> res_;
  std::vector<std::unique_ptr<Pass>> passes_;
  AdaptiveState adaptive_;
  std::vector<CascadeInfo> last_cascades_;
  bool show_cascades_ = false;
  bool count_work_ = false;
  WorkCounter work_;
  // The last frame's settings and plan (count_shading_reads draws its shading again).
  std::unique_ptr<ShadowSettings> last_settings_;
  std::unique_ptr<FramePlan> last_plan_;
};

}  // namespace penumbra::shadows
