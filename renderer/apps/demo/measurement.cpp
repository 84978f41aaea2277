#include "apps/demo/measurement.h"

#include <epoxy/gl.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <exception>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <utility>

#include "metrics/temporal.h"
#include "shadows/frame_plan.h"
#include "shadows/virtual_shadow_map.h"
#include "stats/summary.h"

namespace penumbra::demo {

namespace {

double now_ms() {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// One frame: wall clock from the first GL call to glFinish (the method on software GL; on a GPU
// the per-pass GPU timer figures go to report.json beside it).
double timed_render(Series& s, int width, int height) {
  glFinish();
  const double t0 = now_ms();
  s.info = s.renderer->render(s.config.settings, width, height, s.timer.get());
  glFinish();
  return now_ms() - t0;
}

}  // namespace

ShadowWork shadow_work(const shadows::FrameInfo& info, bool depth_prepass) {
  ShadowWork w;
  for (const shadows::PassWork& p : info.work) {
    if (p.pass == "shading" || p.pass == "depth_prepass" || (depth_prepass && p.pass == "virtual_positions")) continue;
    w.primitives += static_cast<double>(p.primitives);
    w.fragments += static_cast<double>(p.fragments);
    w.compute_invocations += static_cast<double>(p.compute_invocations);
    if (p.pass == "shadow_map" || p.pass.starts_with("virtual_draw")) w.depth_texels += static_cast<double>(p.fragments);
  }
  return w;
}

namespace {

double texels_of(const shadows::FrameInfo& info) {
  if (info.virtual_map) {  // the pages drawn
    const double page = info.virtual_map->page_texels;
    return static_cast<double>(info.virtual_map->pages.drawn) * page * page;
  }
  double t = 0;
  for (const auto& c : info.cascades) t += static_cast<double>(c.resolution_texels) * c.resolution_texels;
  return t;
}

// The largest map side whose four cascades fit one atlas on this device (a 2 × 2 grid of cells
// with guard bands), at most 8192.
int four_cascade_reference_texels() {
  GLint max_size = 0;
  glGetIntegerv(GL_MAX_TEXTURE_SIZE, &max_size);
  return std::min(8192, max_size / 2 - 2 * shadows::kGuardTexels);
}

// Visibility as grey, cropped to the rectangle [x0, x0 + w) × [y0, y0 + h), under a dark band of
// `band` rows for the montage's (white) label.
io::Image8 grey_crop(const io::ImageF& v, int x0, int y0, int w, int h, int band) {
  io::Image8 out{w, h + band, 3, std::vector<std::uint8_t>(static_cast<std::size_t>(w) * (h + band) * 3, 48)};
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const float value = std::clamp(v.pixels[static_cast<std::size_t>(y0 + y) * v.width + (x0 + x)], 0.0f, 1.0f);
      for (int c = 0; c < 3; ++c) out.at(x, band + y, c) = static_cast<std::uint8_t>(std::lround(255 * value));
    }
  return out;
}

// sum over the mask of f(v): (1 - v) for the thin shadow, v for the gaps.
template <class F>
double masked_sum(const io::ImageF& v, const io::Image8& mask, F f) {
  double sum = 0;
  for (std::size_t p = 0; p < mask.pixels.size(); ++p)
    if (mask.pixels[p]) sum += f(v.pixels[p]);
  return sum;
}

// A magma FLIP map under a dark band of `band` rows for the montage's label.
io::Image8 banded(const io::Image8& map, int band) {
  io::Image8 out{map.width, map.height + band, 3, std::vector<std::uint8_t>(static_cast<std::size_t>(map.width) * (map.height + band) * 3, 32)};
  for (int y = 0; y < map.height; ++y)
    for (int x = 0; x < map.width; ++x)
      for (int c = 0; c < 3; ++c) out.at(x, band + y, c) = map.at(x, y, c);
  return out;
}

// A frames.csv field: quoted (RFC 4180) where it holds a comma or a quote, as the names
// "adaptive, no hysteresis" and "virtual rule, cached" do.
std::string csv_field(const std::string& text) {
  if (text.find_first_of(",\"") == std::string::npos) return text;
  std::string quoted = "\"";
  for (const char c : text) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
  return quoted + "\"";
}

// Runs job(i) for i in [0, n) on up to `threads` threads; the first exception is rethrown.
template <class F>
void parallel_for(std::size_t n, int threads, F job) {
  std::atomic<std::size_t> next{0};
  std::exception_ptr failed;
  std::mutex failed_mutex;
  const auto worker = [&] {
    for (std::size_t i = next++; i < n; i = next++) {
      try {
        job(i);
      } catch (...) {
        const std::lock_guard<std::mutex> lock(failed_mutex);
        if (!failed) failed = std::current_exception();
      }
    }
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < std::max(threads, 1) && static_cast<std::size_t>(t) < n; ++t) pool.emplace_back(worker);
  worker();
  for (auto& t : pool) t.join();
  if (failed) std::rethrow_exception(failed);
}

}  // namespace

const std::vector<std::string>& thin_casters() {
  static const std::vector<std::string> names = {"crane", "wires"};
  return names;
}

std::string cascade_resolutions(const shadows::FrameInfo& info) {
  if (info.virtual_map) return std::to_string(info.virtual_map->pages.requested) + "p";  // pages marked
  std::string res;
  for (const auto& c : info.cascades) res += (res.empty() ? "" : "+") + std::to_string(c.resolution_texels);
  return res;
}

Window best_window(const std::vector<double>& score, int width, int height, int w, int h) {
  w = std::clamp(w, 1, width), h = std::clamp(h, 1, height);
  // Summed-area table, one row and column of zeros in front.
  std::vector<double> sat(static_cast<std::size_t>(width + 1) * (height + 1), 0.0);
  auto at = [&](int x, int y) -> double& { return sat[static_cast<std::size_t>(y) * (width + 1) + x]; };
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      at(x + 1, y + 1) = score[static_cast<std::size_t>(y) * width + x] + at(x, y + 1) + at(x + 1, y) - at(x, y);
  Window best{(width - w) / 2, (height - h) / 2, -1e300};
  for (int y0 = 0; y0 + h <= height; y0 += 8)
    for (int x0 = 0; x0 + w <= width; x0 += 8) {
      const double sum = at(x0 + w, y0 + h) - at(x0, y0 + h) - at(x0 + w, y0) + at(x0, y0);
      if (sum > best.sum) best = {x0, y0, sum};
    }
  return best;
}

// Thin casters: their shadow is found with hard shadows toward the light's centre, once with every
// object as a blocker and once without them. With traced_ (Embree built in, a directional light)
// one shadow ray per pixel decides (RayTracedScene::hard_visibility_split: exact, no bias);
// otherwise (no Embree, or a spot light) four fitted cascades of 4096² (about 1 cm texels near the
// camera, with their biases) rendered with the scene and with the scene less those objects.
// `shadow` marks the pixels only they darken (umbra), `gaps` the lit pixels within two pixels of
// those (the holes between lattice members and the sides of a wire's shadow), both only where the
// errors are compared (a surface; ray-traced, one facing the light: a lattice's back faces, dark
// whatever the map says, are not its shadow). Each configuration
// keeps thin_shadow = sum over `shadow` of (1 - V) relative to the reference's, and gaps = sum over
// `gaps` of V relative to the reference's: a map too coarse for a caster drops its shadow
// (thin_shadow < 1) or closes its gaps (gaps < 1).
struct Walk::ThinMasks {
  io::Image8 shadow, gaps;  // one channel, 255 where selected
  std::int64_t shadow_pixels = 0, gap_pixels = 0;
};

Walk::Walk(const scene::Scene& scene, PathPlan plan, WalkOptions options, gl::TimingMethod method)
    : scene_(scene), plan_(std::move(plan)), options_(options), method_(method), probe_(scene) {
  const auto is_thin = [](const scene::Object& o) {
    return std::find(thin_casters().begin(), thin_casters().end(), o.name) != thin_casters().end();
  };
  thin_ = options_.reference && std::any_of(scene.objects.begin(), scene.objects.end(), is_thin);
#if PENUMBRA_HAS_RAY_TRACING
  if (options_.reference && scene.light.type == scene::Light::Type::directional) traced_ = std::make_unique<metrics::RayTracedScene>(scene);
#endif
  if (thin_ && !traced_) {  // the maps' thin masks
    scene::Scene without = scene;
    std::erase_if(without.objects, is_thin);
    thin_with_ = std::make_unique<shadows::Renderer>(), thin_without_ = std::make_unique<shadows::Renderer>();
    thin_with_->set_scene(scene), thin_without_->set_scene(without);
  }
}

Walk::~Walk() = default;

const metrics::RayTracedScene* Walk::traced_at(int frame) {
#if PENUMBRA_HAS_RAY_TRACING
  if (traced_ && !scene_.object_paths.empty() && traced_frame_ != frame) {
    traced_ = std::make_unique<metrics::RayTracedScene>(scene::posed_at(scene_, frame));
    traced_frame_ = frame;
  }
#else
  (void)frame;
#endif
  return traced_.get();
}

const Walk::ThinMasks& Walk::thin_masks(int frame, const scene::Camera& camera, const io::Image8& compared) {
  auto& cached = thin_cache_[frame];
  if (cached) return *cached;
  const int width = options_.width, height = options_.height;
  io::ImageF v, v_free;  // hard visibility with every object, and without the thin casters
  if (const metrics::RayTracedScene* traced = traced_at(frame)) {
    metrics::RayTracedScene::HardVisibility hard = traced->hard_visibility_split(camera, scene_.light, width, height, thin_casters());
    v = std::move(hard.all), v_free = std::move(hard.without);
  } else {
    shadows::ShadowSettings hard;
    hard.technique = shadows::Technique::hard;
    hard.map.resolution_texels = 4096;
    hard.map.cascades = scene_.light.type == scene::Light::Type::directional ? 4 : 1;
    thin_with_->scene().camera = thin_without_->scene().camera = camera;
    scene::pose_objects(scene_, frame, thin_with_->scene());
    scene::pose_objects(scene_, frame, thin_without_->scene());
    thin_with_->render(hard, width, height);
    thin_without_->render(hard, width, height);
    v = thin_with_->read_visibility(), v_free = thin_without_->read_visibility();
  }
  const std::size_t n = static_cast<std::size_t>(width) * height;
  cached = std::make_unique<ThinMasks>();
  ThinMasks& m = *cached;
  m.shadow = {width, height, 1, std::vector<std::uint8_t>(n)};
  m.gaps = {width, height, 1, std::vector<std::uint8_t>(n)};
  for (std::size_t p = 0; p < n; ++p)
    if (compared.pixels[p] && v.pixels[p] < 0.5f && v_free.pixels[p] >= 0.5f) m.shadow.pixels[p] = 255, ++m.shadow_pixels;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const std::size_t p = static_cast<std::size_t>(y) * width + x;
      if (!compared.pixels[p] || v.pixels[p] < 0.5f || v_free.pixels[p] < 0.5f) continue;
      bool near = false;
      for (int dy = -2; dy <= 2 && !near; ++dy)
        for (int dx = -2; dx <= 2 && !near; ++dx) {
          const int xx = x + dx, yy = y + dy;
          near = xx >= 0 && yy >= 0 && xx < width && yy < height && m.shadow.pixels[static_cast<std::size_t>(yy) * width + xx];
        }
      if (near) m.gaps.pixels[p] = 255, ++m.gap_pixels;
    }
  return m;
}

// PCSS converged: four cascades of the reference's size, twice the grid's taps per axis and the
// most blocker-search taps the settings allow. Under the crane (path frame 120) 32 against 64 taps
// per axis at 8188² differ by a mean FLIP of 0.003 (docs/adaptive.md).
constexpr int kConvergedGridTaps = 64;
constexpr int kConvergedBlockerTaps = 64;

void Walk::perceive(TechniqueRun& run, shadows::Renderer& ref_renderer, const shadows::ShadowSettings& ref_settings, int reference_texels,
                    const io::ImageF& reference, const io::Image8& mask, std::size_t index) {
  const int width = options_.width, height = options_.height;
  auto& series = run.series;
  run.perceptual = true;
  run.pixels_per_degree = options_.pixels_per_degree;
  run.converged = ref_settings.technique == shadows::Technique::pcss;
  io::ImageF converged;
  if (run.converged) {
    shadows::ShadowSettings c = ref_settings;
    c.map.resolution_texels = reference_texels;
    c.pcss.max_grid_taps = kConvergedGridTaps;
    c.pcss.blocker_taps = kConvergedBlockerTaps;
    const double t0 = now_ms();
    ref_renderer.render(c, width, height);
    converged = ref_renderer.read_visibility();
    run.converged_ms += now_ms() - t0;
    run.target_description = "PCSS at converged resolution and taps: 4 cascades of " + std::to_string(reference_texels) + "², " +
                             std::to_string(kConvergedGridTaps) + " grid taps per axis, " + std::to_string(kConvergedBlockerTaps) +
                             " blocker taps";
    metrics::CompareOptions masked;
    masked.mask = &mask;
    for (Series& s : series) s.vs_converged.push_back(metrics::compare(converged, s.visibility, masked));
  } else {
    run.target_description = run.reference_description;
  }
  const ShadingBasis basis = shading_basis(ref_renderer, ref_settings, width, height);
  const image::ImageF target = lit_frame(basis, run.converged ? converged : reference);
  const image::ImageF sun = run.converged ? lit_frame(basis, reference) : image::ImageF{};
  std::vector<std::size_t> timed;
  for (std::size_t k = 0; k < series.size(); ++k)
    if (series[k].config.timed()) timed.push_back(k);
  std::vector<image::ImageF> lit(timed.size());
  for (std::size_t j = 0; j < timed.size(); ++j) {
    lit[j] = lit_frame(basis, series[timed[j]].visibility);
    const CodeDifference d = code_difference(lit[j], series[timed[j]].color);
    run.lit_code_difference.max = std::max(run.lit_code_difference.max, d.max);
    run.lit_code_difference.above_2 += d.above_2, run.lit_code_difference.pixels += d.pixels;
  }
  // Every (configuration, reference) pair, over the threads the GL work leaves idle here.
  const std::size_t pairs = timed.size() * (run.converged ? 2 : 1);
  std::vector<metrics::FlipResult> flips(pairs);
  std::vector<metrics::FrameDetection> seen(pairs);
  metrics::FlipOptions fo;
  fo.pixels_per_degree = options_.pixels_per_degree;
  metrics::FrameObserverParams observer;
  observer.pixels_per_degree = options_.pixels_per_degree;
  observer.criterion_f = options_.criterion_f;
  const double t0 = now_ms();
  // Each reference's half of FLIP and of the observer once, then every configuration against it.
  const std::size_t references = run.converged ? 2 : 1;
  std::vector<std::optional<metrics::FlipReference>> flip_refs(references);
  std::vector<std::optional<metrics::ObserverReference>> observer_refs(references);
  parallel_for(2 * references, options_.threads, [&](std::size_t i) {
    const std::size_t r = i % references;
    const image::ImageF& against = r == 0 ? target : sun;
    if (i < references)
      flip_refs[r].emplace(against, metrics::Encoding::linear, fo);
    else
      observer_refs[r].emplace(against, metrics::Encoding::linear, observer);
  });
  parallel_for(pairs, options_.threads, [&](std::size_t p) {
    const std::size_t j = p % timed.size(), r = p / timed.size();
    flips[p] = flip_refs[r]->compare(lit[j], metrics::Encoding::linear);
    seen[p] = observer_refs[r]->judge(lit[j], metrics::Encoding::linear);
  });
  run.flip_ms += now_ms() - t0;
  run.flip_frames_evaluated += static_cast<int>(pairs);
  const bool montage = run.flip_tiles.empty();
  if (montage) run.flip_montage_frame = plan_.frames[index].frame;
  // The montage draws its 24 px text down to row 36 of a tile: a band of 40 rows at the tile's scale.
  const int tile = flip_montage_tile_width(width);
  const int band = (40 * width + tile - 1) / tile;
  for (std::size_t j = 0; j < timed.size(); ++j) {
    Series& s = series[timed[j]];
    s.flip.frames.push_back(flips[j].pooled);
    s.seen.add(seen[j]);
    if (run.converged) s.flip_ray_traced.frames.push_back(flips[timed.size() + j].pooled), s.seen_ray_traced.add(seen[timed.size() + j]);
    if (montage) {
      char label[160];
      std::snprintf(label, sizeof label, "%s: FLIP %.4f", s.config.name.c_str(), flips[j].pooled.mean);
      run.flip_tiles.push_back(banded(metrics::flip_magma(flips[j].map), band));
      run.flip_labels.push_back(label);
    }
  }
}

TechniqueRun Walk::run(const std::string& name, std::vector<Configuration> configs, ProgressBar& progress, int& done, int total) {
  const int width = options_.width, height = options_.height;
  TechniqueRun run;
  run.technique = name;
  run.thin = thin_;
  run.engine = engine_baseline(configs);
  for (Configuration& config : configs) {
    Series s;
    s.config = std::move(config);
    s.renderer = std::make_unique<shadows::Renderer>();
    s.renderer->set_scene(scene_);
    s.renderer->set_count_work(true);  // what each frame gave the GPU to do (Series::work)
    s.timer = std::make_unique<gl::PassTimer>(method_ == gl::TimingMethod::gpu_timer);
    run.series.push_back(std::move(s));
  }
  auto& series = run.series;

  // The reference (metrics/ground_truth.h): four cascades of (up to) 8192² with the same
  // world-space filter, or the mean of hard shadows over the light's area, each from four
  // cascades of 4096².
  shadows::ShadowSettings ref_settings = series[run.fixed].config.settings;
  if (scene_.light.type == scene::Light::Type::directional) ref_settings.map.cascades = 4;
  metrics::ReferenceOptions ref_options;
  ref_options.filter_resolution_texels = four_cascade_reference_texels();
  ref_options.area_samples = options_.reference_samples;
  ref_options.ray_traced = traced_ != nullptr;  // ref_options.traced: at each reference frame (traced_at)
  shadows::Renderer ref_renderer;
  if (options_.reference) ref_renderer.set_scene(scene_);
  // The floor each frame's shadow cost is taken above: the same camera and shading, no shadow.
  Series floor;
  floor.config.settings = shadows::unshadowed_floor(series[run.fixed].config.settings);
  floor.renderer = std::make_unique<shadows::Renderer>();
  floor.renderer->set_scene(scene_);
  floor.timer = std::make_unique<gl::PassTimer>(method_ == gl::TimingMethod::gpu_timer);
  // The moving objects (scene::ObjectPath) where they are at `frame`, in every scene drawn.
  const auto pose = [&](int frame) {
    if (scene_.object_paths.empty()) return;
    for (Series& s : series) scene::pose_objects(scene_, frame, s.renderer->scene());
    scene::pose_objects(scene_, frame, floor.renderer->scene());
    if (options_.reference) scene::pose_objects(scene_, frame, ref_renderer.scene());
    probe_.set_models(scene::posed_at(scene_, frame));
  };

  // Warm-up (shader compilation, allocation) at the path's first camera; not timed.
  pose(plan_.frames.front().frame);
  for (auto& s : series) {
    s.renderer->scene().camera = camera_at(scene_, plan_, plan_.frames.front().frame);
    s.renderer->render(s.config.settings, width, height);
  }
  floor.renderer->scene().camera = camera_at(scene_, plan_, plan_.frames.front().frame);
  floor.renderer->render(floor.config.settings, width, height);
  io::ImageF surface_previous;
  glm::mat4 view_projection_previous(1);
  const int crop_w = std::max(8, width / 4), crop_h = std::max(8, height / 4);
  const int band = crop_w >= 120 ? 20 : 0;  // room for the label (drawn 24 px high at twice the crop's size)
  auto take_crops = [&](Crops& crops, const io::ImageF& reference, Window at, int frame, double score) {
    crops = {{grey_crop(reference, at.x, at.y, crop_w, crop_h, band)}, {"reference (frame " + std::to_string(frame) + ")"}, frame, score};
    for (std::size_t k : {run.adaptive, run.engine, run.fixed}) {
      crops.tiles.push_back(grey_crop(series[k].visibility, at.x, at.y, crop_w, crop_h, band));
      crops.labels.push_back(series[k].config.name);
    }
  };

  for (std::size_t i = 0; i < plan_.frames.size(); ++i) {
    const PathFrame& pf = plan_.frames[i];
    progress(++done, total, name + " frame " + std::to_string(pf.frame) + (pf.reference && options_.reference ? " + reference" : ""));
    const scene::Camera camera = camera_at(scene_, plan_, pf.frame);
    pose(pf.frame);
    io::ImageF surface = probe_.render(camera, width, height);
    const glm::mat4 view_projection = metrics::camera_view_projection(camera, width, height);
    floor.renderer->scene().camera = camera;
    std::vector<double> floor_repeats;
    for (int r = 0; r < std::max(options_.repeats, 1); ++r) floor_repeats.push_back(timed_render(floor, width, height));
    run.floor_ms.push_back(stats::median(floor_repeats));
    for (Series& s : series) {
      s.renderer->scene().camera = camera;
      if (!pf.continues) s.renderer->camera_cut();  // late virtual-map marks of the last station lie elsewhere
      if (!pf.continues && (s.config.settings.adaptive.enabled || s.config.settings.map.virtual_marks_late)) {
        // A new station: the controller starts from this view, not from the last station's maps
        // (which a 30-frame shrink delay would keep), and one untimed frame measures the view's
        // PCSS requirement, or marks the virtual map's pages that late marks read a frame later
        // (the cut frame itself is shaded from the coarse floor). Consecutive frames (a full
        // path) keep the hysteresis and the marks.
        if (s.config.settings.adaptive.enabled) s.renderer->reset_adaptive();
        s.renderer->render(s.config.settings, width, height);
      }
      std::vector<double> repeats;
      for (int r = 0; r < std::max(options_.repeats, 1); ++r) repeats.push_back(timed_render(s, width, height));
      s.ms.push_back(stats::median(repeats));
      if (s.info.pcss_requirement.valid) s.pcss_clamped.push_back(s.info.pcss_requirement.clamped_fraction);
      if (s.info.virtual_map) {
        // A frame whose pool missed pages shades their pixels from a coarser level: its time is that
        // of lesser shadows, not the configuration's, and is not reported.
        if (const std::string w = shadows::missing_pages_warning(s.info.virtual_map->pages, s.info.virtual_map->pool_pages_per_side);
            !w.empty())
          throw std::runtime_error(name + ", " + s.config.name + ", path frame " + std::to_string(pf.frame) + ": not timed: " +
                                   w.substr(w.find(": ") + 2));
        s.pages_drawn.push_back(s.info.virtual_map->pages.drawn);
        s.pages_invalidated.push_back(s.info.virtual_map->pages.invalidated);
      }
      s.texels.push_back(texels_of(s.info));
      s.work.push_back(shadow_work(s.info, s.config.settings.map.depth_prepass));
      double triangles = 0;
      for (const std::uint64_t n : s.info.map_triangles) triangles += static_cast<double>(n);
      s.map_triangles.push_back(triangles);
      s.allocated.push_back(shadows::shadow_memory_texels(s.info));
      const std::string res = cascade_resolutions(s.info);
      if (!s.resolution.empty() && s.resolution.back() != res) ++s.resolution_changes;
      s.resolution.push_back(res);
      if (s.config.timed()) s.color = s.renderer->read_color();  // the lit image: compared in the tables only
      s.visibility = s.renderer->read_visibility();
      if (pf.reference && options_.reference && s.config.timed()) {
        // What the shading's lookups read, per pixel shown: a counting draw of this frame's
        // shading, untimed, changing nothing the next frame reads.
        const shadows::ShadowReads r = s.renderer->count_shading_reads();
        s.reads.pixels += r.pixels, s.reads.instructions += r.instructions, s.reads.texels += r.texels, s.reads.bytes += r.bytes;
        ++s.read_frames;
      }
      // Flicker (metrics/temporal.h): visibility of this frame against the previous one at the
      // pixels whose surface point stayed in view.
      if (pf.continues) {
        const metrics::Flicker fl =
            metrics::flicker({&s.previous, &surface_previous, view_projection_previous}, {&s.visibility, &surface, view_projection});
        s.flicker_mean_abs.push_back(fl.mean_abs);
        s.flicker_share.push_back(fl.share_changed);
      }
    }
    for (Series& s : series)
      if (s.config.timed()) s.ssim_vs_engine.push_back(metrics::compare(series[run.engine].color, s.color).ssim);
    const metrics::ImageError e = metrics::compare(series[run.fixed].color, series[run.adaptive].color);
    run.ssim_fixed_adaptive.push_back(e.ssim), run.max_abs_fixed_adaptive.push_back(e.max_abs);
    run.share_fixed_adaptive.push_back(e.share_above_threshold);

    if (pf.reference && options_.reference) {
      ref_renderer.scene().camera = camera;
      const metrics::RayTracedScene* traced = traced_at(pf.frame);
      ref_options.traced = traced;
      const metrics::Reference ref = metrics::make_reference(ref_renderer, ref_settings, width, height, ref_options);
      run.reference_description = ref.description + (ref.note.empty() ? "" : " (" + ref.note + ")");
      run.reference_ms += ref.render_ms;
      ++run.reference_frames;
      // Compared where a surface is drawn (the sky is lit in every image) and, ray-traced, faces the
      // light (on the other side max(n·l, 0) hides the visibility).
      io::Image8 mask = traced ? traced->facing_light(camera, scene_.light, width, height)
                                : io::Image8{width, height, 1, std::vector<std::uint8_t>(static_cast<std::size_t>(width) * height, 255)};
      bool any = false;
      for (std::size_t p = 0; p < mask.pixels.size(); ++p) {
        if (surface.pixels[4 * p + 3] <= 0) mask.pixels[p] = 0;
        any = any || mask.pixels[p];
      }
      run.mask_pixels += std::count_if(mask.pixels.begin(), mask.pixels.end(), [](std::uint8_t m) { return m != 0; });
      run.mask_description = traced_ ? "surfaces facing the light" : "surfaces";
      metrics::CompareOptions masked;
      masked.mask = &mask;
      if (any)
        for (Series& s : series) s.vs_reference.push_back(metrics::compare(ref.visibility, s.visibility, masked));
      if (options_.perceptual) perceive(run, ref_renderer, ref_settings, ref_options.filter_resolution_texels, ref.visibility, mask, i);
      // What the rule buys where the fixed map fails: per pixel, how much closer to the reference
      // the adaptive visibility is than the fixed map's; the crop goes where that is largest.
      std::vector<double> gain(mask.pixels.size(), 0.0);
      const auto& va = series[run.adaptive].visibility.pixels;
      const auto& vf = series[run.fixed].visibility.pixels;
      for (std::size_t p = 0; p < gain.size(); ++p)
        if (mask.pixels[p]) gain[p] = std::abs(vf[p] - ref.visibility.pixels[p]) - std::abs(va[p] - ref.visibility.pixels[p]);
      const Window g = best_window(gain, width, height, crop_w, crop_h);
      if (run.gain_crops.tiles.empty() || g.sum > run.gain_crops.score) take_crops(run.gain_crops, ref.visibility, g, pf.frame, g.sum);
      // Side-by-side crops where the thin casters' shadows are densest, or the middle of the first
      // reference frame.
      if (thin_) {
        const ThinMasks& m = thin_masks(pf.frame, camera, mask);
        run.thin_pixels += m.shadow_pixels, run.gap_pixels += m.gap_pixels;
        auto dark = [](float v) { return 1.0 - v; };
        auto lit = [](float v) { return static_cast<double>(v); };
        run.reference_thin_shadow += masked_sum(ref.visibility, m.shadow, dark);
        run.reference_gaps += masked_sum(ref.visibility, m.gaps, lit);
        for (Series& s : series) s.thin_shadow += masked_sum(s.visibility, m.shadow, dark), s.gaps += masked_sum(s.visibility, m.gaps, lit);
        if (run.thin_crops.tiles.empty() || static_cast<double>(m.shadow_pixels) > run.thin_crops.score) {
          const std::vector<double> shadow(m.shadow.pixels.begin(), m.shadow.pixels.end());
          const Window at = m.shadow_pixels > 0 ? best_window(shadow, width, height, crop_w, crop_h)
                                                : Window{(width - crop_w) / 2, (height - crop_h) / 2, 0};
          take_crops(run.thin_crops, ref.visibility, at, pf.frame, static_cast<double>(m.shadow_pixels));
        }
      } else if (run.thin_crops.tiles.empty()) {
        take_crops(run.thin_crops, ref.visibility, {(width - crop_w) / 2, (height - crop_h) / 2, 0}, pf.frame, 0);
      }
    }
    for (std::size_t k = 0; k < series.size(); ++k) {
      const Series& s = series[k];
      char row[320];
      std::snprintf(row, sizeof row, "%s,%s,%d,%.4f,%.0f,%s,%.6f,%.6f\n", name.c_str(), csv_field(s.config.name).c_str(), pf.frame, s.ms.back(),
                    s.texels.back(), s.resolution.back().c_str(), s.config.timed() ? s.ssim_vs_engine.back() : std::nan(""),
                    pf.continues ? s.flicker_mean_abs.back() : std::nan(""));
      run.csv += row;
    }
    if (i == plan_.frames.size() / 2) {
      run.shown_fixed = series[run.fixed].color, run.shown_adaptive = series[run.adaptive].color;
      run.shown_at = i;
    }
    for (Series& s : series) s.previous = std::move(s.visibility);
    surface_previous = std::move(surface);
    view_projection_previous = view_projection;
  }
  for (Series& s : series) {
    s.timer->poll(true);
    // What the shadow costs above the floor, frame by frame (a noisy frame may come out below it).
    for (std::size_t i = 0; i < s.ms.size(); ++i) s.shadow_ms.push_back(s.ms[i] - run.floor_ms[i]);
  }
  return run;
}

}  // namespace penumbra::demo
