#pragma once
// The walk along the path: every configuration of a technique (configurations.h) renders every
// frame of the plan (path.h), timed with the wall clock around glFinish; per frame the texels
// drawn and allocated, triangles drawn into the maps, SSIM against the engine baseline and
// flicker from the frame before; at the reference frames the error against the reference of the
// technique (metrics/ground_truth.h; ray-traced for an area light where Embree is built in),
// the thin casters' shadow and gaps, and the crops. Errors are taken where a surface faces the
// light (ray_traced.h's facing mask; without Embree, wherever a surface is drawn): elsewhere the
// shading's max(n·l, 0) makes the visibility invisible. At the reference frames also the
// perceptual difference of each timed configuration's lit frame against the reference's
// (perceptual.h: LDR-FLIP at the study display's pixels per degree); for PCSS against two
// references: PCSS itself at converged resolution and taps (what the rule controls) and the
// ray-traced sun (what a player sees).
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "apps/demo/configurations.h"
#include "apps/demo/path.h"
#include "apps/demo/perceptual.h"
#include "cli/progress_bar.h"
#include "gl/timer.h"
#include "io/image_io.h"
#include "metrics/ground_truth.h"
#include "metrics/image_error.h"
#include "metrics/ray_traced.h"
#include "metrics/surface_probe.h"
#include "scene/scene.h"
#include "shadows/renderer.h"

namespace penumbra::demo {

// What one frame's shadow gave the GPU to do, counted by the driver (shadows::PassWork), summed
// over every pass but the camera's: the maps, the virtual map's steps (the marking, the pages),
// the moments blur, the screen-space passes. The camera's passes are the floor's work too: the
// shading and the depth prepass (map.depth_prepass), and with that prepass on, the virtual map's
// position pass, which is its depth prepass with world positions written beside the depth (off:
// the floor draws no camera depth first, and the position pass is the virtual map's own work).
struct ShadowWork {
  double primitives = 0;           // submitted, after the CPU's culling
  double fragments = 0;            // fragment shader invocations
  double compute_invocations = 0;
  double depth_texels = 0;         // of those fragments, the maps' rasters' (shadow_map, virtual_draw)
};
ShadowWork shadow_work(const shadows::FrameInfo& info, bool depth_prepass);

// One configuration along the path, with everything measured about it.
struct Series {
  Configuration config;
  std::unique_ptr<shadows::Renderer> renderer;
  std::unique_ptr<gl::PassTimer> timer;
  // this frame
  shadows::FrameInfo info;
  io::Image8 color;
  io::ImageF visibility, previous;
  // per path frame
  std::vector<double> ms;         // median over --repeats renders of the frame
  std::vector<double> shadow_ms;  // ms minus the run's unshadowed floor at the same frame (TechniqueRun::floor_ms)
  std::vector<double> texels;     // drawn into its maps
  std::vector<double> allocated;  // the atlas allocated for them
  std::vector<double> map_triangles;  // drawn into all its maps after culling
  std::vector<double> ssim_vs_engine;  // timed configurations only
  std::vector<std::string> resolution;  // "928" or "1024+1024+512" (one per cascade)
  std::vector<double> flicker_mean_abs, flicker_share;  // per pair of consecutive frames
  std::vector<double> pcss_clamped;  // PCSS with the per-pixel requirement: share held at the minimum penumbra
  std::vector<double> pages_drawn, pages_invalidated;  // virtual map, per frame: pages drawn; dropped as the van moved
  std::vector<ShadowWork> work;                        // per frame
  shadows::ShadowReads reads;                          // the shading's shadow reads, summed over the reference frames
  int read_frames = 0;
  int resolution_changes = 0;
  // at the reference frames
  std::vector<metrics::ImageError> vs_reference;
  // Timed configurations, at the reference frames: FLIP of the lit frame against the target
  // reference (TechniqueRun::target_description: the reference for PCF, converged PCSS for PCSS),
  // and PCSS's RMSE against converged PCSS and FLIP against the ray-traced sun.
  FlipSeries flip, flip_ray_traced;
  ObserverSeries seen, seen_ray_traced;  // the frame observer on the same pairs
  std::vector<metrics::ImageError> vs_converged;
  double thin_shadow = 0, gaps = 0;  // masked sums (thin casters)
};

// Side-by-side crops of the visibility (reference, adaptive, engine baseline, fixed) at one frame.
struct Crops {
  std::vector<io::Image8> tiles;
  std::vector<std::string> labels;
  int frame = -1;
  double score = 0;  // what chose them: thin-shadow pixels, or the error the rule removes
};

struct TechniqueRun {
  std::string technique;
  std::vector<Series> series;  // in configurations() order
  std::size_t adaptive = 0, fixed = 1, engine = 1;  // indices into series
  // the reference
  std::string reference_description;
  std::string mask_description;  // where the errors are taken
  std::int64_t mask_pixels = 0;  // over the reference frames
  int reference_frames = 0;
  double reference_ms = 0;
  // thin casters (crane, wires) over the reference frames
  bool thin = false;
  std::int64_t thin_pixels = 0, gap_pixels = 0;
  double reference_thin_shadow = 0, reference_gaps = 0;
  // the fixed map's image against the adaptive one, per frame
  std::vector<double> ssim_fixed_adaptive, max_abs_fixed_adaptive, share_fixed_adaptive;
  io::Image8 shown_fixed, shown_adaptive;  // lit images at the path's middle frame
  std::size_t shown_at = 0;                // that frame's index in the plan (and in each series' per-frame vectors)
  Crops thin_crops;  // where the thin casters' shadow is densest
  Crops gain_crops;  // where the adaptive map is closest to the reference compared with the fixed map
  // the perceptual difference (perceptual.h)
  bool perceptual = false;           // FLIP was measured
  bool converged = false;            // PCSS: also against PCSS at converged resolution and taps
  std::string target_description;    // what FLIP is taken against (the converged PCSS, or the reference)
  double pixels_per_degree = 0;
  CodeDifference lit_code_difference;  // composed against the renderer's lit frames, over every frame compared
  double flip_ms = 0;                // wall time of the FLIP and frame observer evaluations
  double converged_ms = 0;           // rendering the converged PCSS reference
  int flip_frames_evaluated = 0;     // FLIP maps computed
  std::vector<io::Image8> flip_tiles;  // FLIP maps (magma) against the target, at the first reference frame
  std::vector<std::string> flip_labels;
  int flip_montage_frame = -1;
  std::string csv;   // frames.csv rows
  // The physical floor: per path frame, the frame without a meaningful shadow
  // (shadows::unshadowed_floor of the fixed map's settings), timed as the configurations are.
  std::vector<double> floor_ms;
};

struct WalkOptions {
  int width = 960, height = 540;
  int repeats = 1;  // renders per frame and configuration; the frame's time is their median
  bool reference = true;
  // Area-light reference: shadow rays per pixel when ray-traced (a directional light in a build
  // with Embree), else point-light maps averaged.
  int reference_samples = 256;
  // The perceptual difference at the reference frames (perceptual.h); pixels per degree of the
  // display the frames are seen on, pixel for pixel.
  bool perceptual = true;
  double pixels_per_degree = metrics::kFlipDefaultPixelsPerDegree;
  int threads = 2;  // FLIP evaluations in parallel
  double criterion_f = metrics::kStudyCriterionF;  // the frame observer's "visible" (the technique's calibration entry's F)
};

// Shared by every technique of a run: the scene, the surface probe, the thin casters' masks.
class Walk {
 public:
  Walk(const scene::Scene& scene, PathPlan plan, WalkOptions options, gl::TimingMethod method);
  ~Walk();
  const PathPlan& plan() const { return plan_; }
  // The criterion F of the next run's technique (its calibration entry's threshold.criterion_f).
  void set_criterion_f(double f) { options_.criterion_f = f; }
  // Walks the path with `configs` of technique `name`. `progress` counts frames from `done` of `total`.
  TechniqueRun run(const std::string& name, std::vector<Configuration> configs, ProgressBar& progress, int& done, int total);

 private:
  struct ThinMasks;
  const ThinMasks& thin_masks(int frame, const scene::Camera& camera, const io::Image8& compared);
  // The ray-traced scene with the moving objects (scene::ObjectPath) where they are at `frame`,
  // rebuilt when they moved since it was last built; null without ray tracing.
  const metrics::RayTracedScene* traced_at(int frame);
  // At reference frame `index` of the plan: FLIP of every timed configuration's lit frame against
  // the reference's (PCSS: against PCSS at converged resolution and taps, rendered here with
  // `ref_renderer` at `reference_texels`, and against `reference`, the ray-traced sun), and PCSS's
  // RMSE against the converged one over `mask`.
  void perceive(TechniqueRun& run, shadows::Renderer& ref_renderer, const shadows::ShadowSettings& ref_settings, int reference_texels,
                const io::ImageF& reference, const io::Image8& mask, std::size_t index);

  const scene::Scene& scene_;
  PathPlan plan_;
  WalkOptions options_;
  gl::TimingMethod method_;
  metrics::SurfaceProbe probe_;
  std::unique_ptr<metrics::RayTracedScene> traced_;  // the ray-traced reference, the facing mask and the thin masks
  int traced_frame_ = -1;                            // the frame whose poses traced_ holds (-1: the scene as built)
  bool thin_ = false;
  std::unique_ptr<shadows::Renderer> thin_with_, thin_without_;  // the thin masks' maps, only without traced_
  std::map<int, std::unique_ptr<ThinMasks>> thin_cache_;
};

// The thin casters: the objects a coarse map loses first (the crane's lattice, Kreuzer 2017 Fig.
// 6.1, and the wires between the poles).
const std::vector<std::string>& thin_casters();

// The frame's map resolutions, "928" or "1024+1024+512" (one per cascade).
std::string cascade_resolutions(const shadows::FrameInfo& info);

// The x, y of the w × h window (corners on an 8-pixel grid) with the largest sum of `score`
// (width × height values, row by row), and that sum.
struct Window {
  int x = 0, y = 0;
  double sum = 0;
};
Window best_window(const std::vector<double>& score, int width, int height, int w, int h);

}  // namespace penumbra::demo
