#pragma once
// The frame as a plan, made without GL: which maps the frame renders (cascades, their light frames
// and resolutions from the resolution rule and its hysteresis), where they sit in the shadow
// atlas, and which passes run. Renderer::render executes the plan (passes.h); tests check it on
// the CPU.
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>

#include <penumbra/adaptive/resolution_rule.h>
#include <penumbra/shaders/shadow_contract.h>
#include <penumbra/scene/scene.h>
#include <penumbra/shadows/fitting.h>
#include <penumbra/shadows/settings.h>
#include <penumbra/shadows/technique.h>

namespace penumbra::shadows {

inline constexpr int kMaxCascades = contract::MAX_CASCADES;
inline constexpr int kGuardTexels = 2;  // far-depth band around each map in a shared atlas (atlas_uv in common.glsl)

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

// The passes a frame can run, in execution order.
enum class PassId { virtual_pages, shadow_map, moments_blur, depth_minmax, gbuffer, post, depth_prepass, shading, pcss_requirement };

// Region corners per cascade: one row of up to two cells, then a second row. `guard` texels of
// far depth surround every region.
struct AtlasLayout {
  int width = 0, height = 0;
  int guard = 0;
  std::vector<glm::ivec2> origin;  // inner corner of each region
};
AtlasLayout layout_atlas(const std::vector<int>& cell_texels, int guard);

// What the adaptive rule carries from frame to frame: the hysteresis of each cascade and the
// newest per-pixel PCSS requirement (measured on the GPU, read back a frame later).
struct AdaptiveState {
  std::string key;  // what the controllers were made for; a change restarts them
  std::vector<adaptive::ResolutionController> controllers;
  PcssRequirementInfo last;  // the newest measured requirement
  int last_cascades = 0;     // cascade count it was measured with
  float last_c = 0;
  // The automatic cascade count (map.cascades = 0) with hysteresis: the count in use, and the
  // frames a smaller count has sufficed (it drops after adaptive.shrink_delay_frames of them).
  int auto_count = 0;
  int auto_count_frames_below = 0;
  void reset() { *this = {}; }
};

struct FramePlan {
  int width_px = 0, height_px = 0;
  float aspect = 1;
  const TechniqueEntry* technique = nullptr;
  std::optional<MomentsLayout> moments;       // filtered-moments techniques
  std::optional<FilterRadius> filter_radius;  // fixed-filter techniques
  float tan_half_angle = 0;                   // of the light's angular size (directional)
  std::vector<CascadeInfo> cascades;          // one entry when not cascaded
  std::string resolution_source;              // "fixed", "rule", "pcss_per_pixel", "pcss_min_penumbra"
  bool subrect = false;                       // adaptive sub-rectangle storage (else a map per size)
  AtlasLayout atlas;
  bool pcss_requirement = false;              // the frame measures its per-pixel PCSS requirement
  bool depth_prepass = false;                 // the shading tests the camera depth a depth-only pass left (map.depth_prepass)
  PcssRequirementInfo used_requirement;       // the measurement this frame's resolution used
  float filter_radius_texels = 0;             // fixed filter, in texels of cascade 0 at mid depth
  // The sun's virtual shadow map (map.virtual_pages): the frame marks and draws pages instead of
  // maps; `cascades` then holds the fitted single map's light frame (its view and depth range
  // describe the frame) and no map is drawn.
  VirtualPages virtual_pages = VirtualPages::off;
  std::vector<PassId> passes;

  bool runs(PassId p) const;
  // Whether a pass before the shading leaves the camera's depth (kCameraDepth: the virtual map's
  // position pass, the screen-space G-buffer, or the depth prepass), which the shading then tests
  // with LEQUAL instead of clearing it.
  bool camera_depth_first() const;
  const LightFrame& light() const { return cascades.front().light; }
};

// What the passes of a frame hand each other. The scene's meshes are the frame's input; colour and
// visibility its output.
enum Resource : unsigned {
  kSceneMeshes = 1u << 0,
  kDepthAtlas = 1u << 1,
  kMoments = 1u << 2,
  kGbuffer = 1u << 3,
  kScreenVisibility = 1u << 4,
  kColor = 1u << 5,
  kVisibility = 1u << 6,
  kRequirementImage = 1u << 7,
  kRequirementBuffer = 1u << 8,
  kDepthMinmax = 1u << 9,
  kVirtualPages = 1u << 10,  // the virtual shadow map's page pool and tables
  kCameraDepth = 1u << 11,   // the camera's depth before shading (map.depth_prepass, the virtual map's position pass, the G-buffer)
};

// The resources a pass reads and writes in the frame `plan` describes (the shading pass reads the
// moments only when the plan has moments, ...): the frame's data flow, in one table.
struct PassIo {
  unsigned reads = 0, writes = 0;
};
PassIo pass_io(PassId pass, const FramePlan& plan);
std::string_view pass_name(PassId pass);  // "shadow_map", "vsm_blur", ... (the timers' names)
std::string resource_names(unsigned resources);  // "depth atlas, moments"

// "" when the plan is a frame: no pass twice or out of order, every resource a pass reads written
// by an earlier pass (or the scene's meshes), colour and visibility written; else one line naming
// the pass and what it lacks. Renderer::render refuses a plan that is not a frame.
std::string plan_problem(const FramePlan& plan);

// The techniques whose registry entry reads pages (TechniqueEntry::pages), "pcf, pcss or vsm".
std::string page_reading_techniques();
// "" when `s`'s technique can mark the sun's virtual shadow map's pages (its entry reads pages, and
// a fixed filter has a world radius), else why not ("pcf marks pages by a world radius
// (--pcf.radius_unit world)"): the debug views refuse with it.
std::string virtual_marking_unsupported(const ShadowSettings& s);
// "" when `s` can be drawn through the pages: it can mark them, and the shading's needs beyond
// marking hold (TechniqueEntry::pages_need: the pages' box filter); else why not, every missing
// setting in one line ("pcf reads pages only with --pcf.radius_unit world --pcf.kernel grid, not
// pcf kernel=poisson ..."): plan_frame refuses map.virtual_pages then.
std::string virtual_pages_unsupported(const ShadowSettings& s);
// "" when a frame of `scene` can draw `s` through the virtual shadow map (a sun, and a technique
// virtual_pages_unsupported accepts), else why not: plan_frame refuses map.virtual_pages with it.
std::string virtual_pages_refusal(const ShadowSettings& s, const scene::Scene& scene);

// Plans one frame of `scene` at width × height. Updates the hysteresis in `state`. Throws
// std::runtime_error for an empty image, a map below one texel or inconsistent adaptive limits.
FramePlan plan_frame(const ShadowSettings& s, const scene::Scene& scene, int width_px, int height_px, AdaptiveState& state);

// World-space radius the adaptive rule sizes texels for, for the technique's filter; 0 when the
// technique has none. Radii given in texels are taken at map.resolution_texels of the single
// fitted map `single`: "the filter the user sees at the configured resolution".
float rule_radius_ws(const ShadowSettings& s, const LightFrame& single, float mid_depth_ws);

}  // namespace penumbra::shadows
