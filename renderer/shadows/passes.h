#pragma once
// The passes of a frame and what they share. Each pass states its name (as reported in
// FrameInfo.passes and timed), whether a plan needs it, the resources it reads and writes, and
// executes against the frame's resources:
//   virtual_pages     scene → virtual pages: the camera's world positions (and its depth), the
//                     pages they mark, those not cached drawn into the pool (map.virtual_pages)
//   shadow_map        scene → depth atlas (+ the moments of a filtered-moments technique)
//   vsm_blur          moments → moments (box blur in place, through a temporary)
//   depth_minmax      depth atlas → min-max depth pyramid (PCSS's bounds)
//   gbuffer           scene, depth atlas → G-buffer + camera depth (screen-space techniques)
//   post              G-buffer, depth atlas → screen visibility (the technique's post passes,
//                     each reported under its own name)
//   shading           scene, depth atlas, moments, screen visibility → colour, visibility
//                     (+ the per-pixel PCSS requirement image)
//   pcss_requirement  requirement image → requirement buffer (read back one frame later)
// Renderer::render runs, in this order, the passes its FramePlan lists.
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <penumbra/gl/objects.h>
#include <penumbra/gl/shader_library.h>
#include <penumbra/gl/timer.h>
#include <penumbra/scene/culling.h>
#include <penumbra/scene/gpu_mesh.h>
#include <penumbra/scene/scene.h>
#include <penumbra/shadows/frame_plan.h>
#include <penumbra/shadows/scoped_pass.h>
#include <penumbra/shadows/screen_space.h>
#include <penumbra/shadows/virtual_shadow_map.h>

namespace penumbra::shadows {

struct FrameInfo;

// Programs compiled on first use and kept by key.
class ProgramCache {
 public:
  const gl::Program& get(const gl::ShaderLibrary& shaders, const std::string& key, const std::vector<gl::ShaderStage>& stages,
                         const std::vector<gl::ShaderDefine>& defines = {});

 private:
  std::map<std::string, gl::Program> programs_;
};

// Everything the passes share across frames: the atlas, the camera targets, samplers, programs,
// the screen-space state and the PCSS requirement buffers.
struct FrameResources {
  struct Maps {
    int width = 0, height = 0;
    GLenum moments_format = 0;  // gl_format(MomentsLayout::format); 0: depth only
    gl::Texture depth;
    gl::Framebuffer depth_fbo;
    gl::Texture moments_tex, moments_tmp;
    gl::Framebuffer moments_fbo;
    // Level k: min (r) and max (g) depth over 2^(k+1)-texel blocks of the atlas (depth_minmax pass).
    gl::Texture depth_minmax;
  };
  struct Targets {
    int width = 0, height = 0;
    bool requirement = false;
    bool virtual_status = false;  // the virtual map's per-pixel page status (R8UI, attachment 2)
    gl::Texture color, visibility, requirement_tex, virtual_status_tex, depth;
    gl::Framebuffer fbo;
  };
  // Two requirement buffers, so that a frame reads the one written a frame earlier and never
  // waits for the GPU.
  struct Requirement {
    gl::Buffer buffer[2];
    bool pending[2] = {false, false};
    int cascades[2] = {0, 0};
    float c[2] = {0, 0};
    int frame = 0;
  };

  // The sun's virtual shadow map, made on its first frame and kept (its pages are the cache): the
  // pool and tables, the marker, and the camera's world positions the marking reads, drawn with
  // the camera targets' depth, which the shading pass then tests with LEQUAL (one fragment a pixel).
  struct Virtual {
    int pool_pages = 0;
    std::unique_ptr<VirtualShadowMap> map;
    std::unique_ptr<PageMarker> marker;
    adaptive::MarkOptions options;
    double radius_ws = 0;         // PCF's world radius
    std::optional<VirtualPcss> pcss;  // PCSS: its search and penumbra
    int targets_generation = -1;  // of the camera targets whose depth `fbo` holds
    gl::Texture positions;
    gl::Texture pcss_radii;  // PCSS: each pixel's penumbra as the marking's search found it (R32F)
    gl::Framebuffer fbo;
    gl::Buffer shading_counts;  // contract::VirtualShadingResult
    bool shading_counts_pending = false;  // map.virtual_marks_late: the counts hold the previous frame's, not yet read
    // map.virtual_marks_late: the marks of the previous frame (PCSS: its searches' and its
    // penumbrae'), read by this one; where its camera stood in light space, and how it marked.
    struct Late {
      gl::Buffer filter, search;
      bool pending = false;
      adaptive::LightXY camera_xy;
      glm::mat4 light_view{1};
      bool pcss = false;
    } late;
  };

  explicit FrameResources(const gl::ShaderLibrary& library);

  // (Re)allocates the atlas and the camera targets for `plan`; true when the atlas was.
  bool prepare(const FramePlan& plan);

  const gl::ShaderLibrary& shaders;
  gl::Program depth_program, requirement_program, minmax_program;
  ProgramCache programs;
  gl::Sampler cmp_linear, cmp_nearest, raw_nearest, moments_linear;
  gl::Buffer shadow_frame;  // the ShadowFrame uniform block (shaders/shadow_contract.h)
  std::unique_ptr<Maps> maps;
  std::unique_ptr<Targets> targets;
  int targets_generation = 0;  // counts the targets' allocations (a framebuffer holding their depth must follow)
  std::unique_ptr<ScreenSpace> screen_space;  // made on the first screen-space frame
  const gl::Texture* screen_result = nullptr;  // this frame's post-pass output
  Requirement requirement;
  std::map<int, std::vector<glm::vec2>> poisson;  // Poisson disks by tap count
  std::unique_ptr<Virtual> virtual_map;  // made on the first virtual frame
  gl::Buffer shadow_reads;  // contract::ShadowReadsResult, made on the first counting run
};

// One frame being executed.
struct FrameContext {
  const ShadowSettings& settings;
  const FramePlan& plan;
  const scene::Scene& scene;
  const scene::GpuMeshes& meshes;  // per object
  FrameResources& res;
  FrameInfo& info;
  gl::PassTimer* timer = nullptr;
  WorkCounter* work = nullptr;  // counts each pass's work when the renderer counts work
  bool show_cascades = false;

  // Draws what of every mesh may touch `volume` of `clip_from_world` (all of it with map.culling
  // off) with `program`; `shading` also sets normal matrix and albedo. Returns the triangles drawn.
  // A caster volume (a map or a cascade) culls by clusters (scene::cull_clusters), as the virtual
  // map's pages do, so that the two draw into their maps like for like; the view culls by units.
  std::uint64_t draw_scene(const gl::Program& program, bool shading, const glm::mat4& clip_from_world, scene::CullVolume volume) const;
  // The camera's clip-from-world matrix (as ShadowFrame's u_view_projection).
  glm::mat4 camera_view_projection() const;
  // Fills the ShadowFrame block (cameras, light frame, cascades, biases, the fixed filter radius)
  // from the plan, uploads it and binds it for every program of the frame: once per frame.
  void upload_shadow_frame() const;
  // The technique's own uniforms (its settings, Poisson taps, light size), shared by both camera
  // passes and the screen-space compute passes (uniforms a program lacks are ignored).
  void set_technique_uniforms(const gl::Program& program) const;
  // Binds the depth atlas, its min-max pyramid and the moments to their units (contract::UNIT_*).
  void bind_shadow_maps() const;
  // Where the frame's passes (and their steps) report: the timer, the work counter, the pass list.
  PassReport report() const;
  // The shading program of the frame's technique; `gbuffer`: the first camera pass of a
  // screen-space technique; `count_reads`: the variant that counts its shadow reads
  // (read_count.glsl).
  const gl::Program& shading_program(bool gbuffer, bool count_reads = false) const;
};

class Pass {
 public:
  virtual ~Pass() = default;
  virtual PassId id() const = 0;
  // The name its time is reported under (pass_name: "shadow_map", "vsm_blur", ...); what it
  // reads and writes is pass_io(id(), plan), checked for the whole frame by plan_problem.
  const char* name() const { return pass_name(id()).data(); }
  // Whether the pass reports its own sub-passes (post) instead of being timed as one.
  virtual bool reports_subpasses() const { return false; }
  bool needed(const FramePlan& plan) const { return plan.runs(id()); }
  virtual void execute(FrameContext& frame) = 0;
};

// The frame's passes, in execution order (PassId order).
std::vector<std::unique_ptr<Pass>> make_passes();

// Draws the shading pass of the frame `f` planned once more with its counting variant, over the
// depth the frame left and writing no colour, and returns what its shadow lookups read
// (Renderer::count_shading_reads). Needs the frame's resources as its passes left them.
ShadowReads count_shading_reads(FrameContext& f);

}  // namespace penumbra::shadows
