// penumbra-demo: adaptive shadow-map resolution against a fixed resolution.
//
//   --headless  for each technique, walks the scene's camera path (the outdoor town: --path short
//               or full; other scenes: an orbit) and renders every frame in each configuration:
//               the adaptive rule res = c / r_uv (rule-sized cascades, count chosen), a fixed map
//               (default 2048²), and the baselines engines ship (one map of twice that size, four
//               stabilized cascades of it: the engine baseline). Per configuration: frame time
//               (median and spread; per pass), texels drawn and allocated, SSIM against the
//               engine baseline, error of the visibility against a reference of the technique
//               (metrics/ground_truth.h) at the reference frames, and flicker from frame to frame
//               (metrics/temporal.h) beside the adaptive rule without hysteresis and the
//               measure's floor. Writes report.json, frames.csv, side-by-side images, crops and
//               the plots (scripts/plot_demo.py) into -o DIR; prints the tables.
//   windowed    the same renderer in a window with a panel: technique and filter, fitting,
//               adaptive on/off, c and its calibration file, the resolution in use per cascade,
//               shadow-map and cascade overlays, fps and per-pass times.
#include <epoxy/gl.h>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <glm/gtc/constants.hpp>

#include "adaptive/resolution_rule.h"
#include "cli/main.h"
#include "cli/progress_bar.h"
#include "io/atomic_file.h"
#include "json/json_input.h"
#include "apps/cli_options.h"
#include "apps/run_python.h"
#include "gl/context.h"
#include "gl/timer.h"
#include "io/image_io.h"
#include "io/report.h"
#include "io/staged_dir.h"
#include "metrics/ground_truth.h"
#include "metrics/image_error.h"
#include "metrics/surface_probe.h"
#include "metrics/temporal.h"
#include "scene/scene.h"
#include "shadows/frame_plan.h"
#include "shadows/renderer.h"
#include "stats/summary.h"

#if PENUMBRA_DEMO_GUI
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <imgui.h>

#include "gl/window.h"
#include "gui/settings_panel.h"
#endif

namespace penumbra::stats {
// {"median", "p10", "p90", "min", "max"}; here beside its one user, so that stats/summary.h stays free of JSON.
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(Spread, median, p10, p90, min, max)
}  // namespace penumbra::stats

using namespace penumbra;
namespace fs = std::filesystem;

namespace {

// The demo's defaults: filters sized in world units (the rule needs a world-space radius), grid
// kernels (exact, deterministic: the two images differ only by the map's resolution), and the
// rule as a careful engine applies it: no texel finer than a pixel footprint at its cascade's
// near end (adaptive.min_texel_px; 0 gives the rule alone).
shadows::ShadowSettings demo_defaults() {
  shadows::ShadowSettings s;
  s.technique = shadows::Technique::pcf;
  s.map.resolution_texels = 2048;
  s.pcf.kernel = shadows::Kernel::grid;
  s.pcf.radius = 0.12f;
  s.pcf.radius_unit = shadows::RadiusUnit::world;
  s.pcss.kernel = shadows::Kernel::grid;
  s.pcss.min_penumbra_ws = 0.12f;
  s.vsm.radius = 0.12f;
  s.vsm.radius_unit = shadows::RadiusUnit::world;
  s.adaptive.min_texel_px = 1;
  return s;
}

// The fixed camera path: a quarter orbit around the scene camera's target while zooming in to
// 60 % of the distance and back, at the scene camera's elevation.
scene::Camera path_camera(const scene::Camera& start, int i, int n) {
  scene::Camera c = start;
  const glm::vec3 d = start.position - start.target;
  const float distance = glm::length(d);
  const float pitch = std::asin(std::clamp(d.y / std::max(distance, 1e-6f), -1.0f, 1.0f));
  const float t = n > 1 ? static_cast<float>(i) / static_cast<float>(n - 1) : 0.0f;
  const float yaw = std::atan2(d.x, d.z) + glm::radians(90.0f) * (t - 0.5f);
  const float r = distance * (1.0f - 0.4f * std::sin(glm::pi<float>() * t));
  c.position = c.target + r * glm::vec3(std::cos(pitch) * std::sin(yaw), std::sin(pitch), std::cos(pitch) * std::cos(yaw));
  return c;
}

using stats::Spread;
using stats::spread;

double now_ms() {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// One frame: wall clock from the first GL call to glFinish (the method on software GL; on a GPU
// the per-pass GPU timer figures go to report.json beside it).
struct Timed {
  shadows::FrameInfo info;
  double ms = 0;
};
Timed timed_render(shadows::Renderer& r, const shadows::ShadowSettings& s, int w, int h, gl::PassTimer& timer) {
  glFinish();
  const double t0 = now_ms();
  Timed t;
  t.info = r.render(s, w, h, &timer);
  glFinish();
  t.ms = now_ms() - t0;
  return t;
}

// The frame's map resolutions, "928" or "1024+1024+512" (one per cascade).
std::string cascade_resolutions(const shadows::FrameInfo& info) {
  std::string res;
  for (const auto& c : info.cascades) res += (res.empty() ? "" : "+") + std::to_string(c.resolution_texels);
  return res;
}

// Fixed | adaptive | |difference| × 10 (grey), side by side.
io::Image8 side_by_side(const io::Image8& a, const io::Image8& b) {
  io::Image8 out{a.width * 3, a.height, 4, std::vector<std::uint8_t>(static_cast<std::size_t>(a.width) * 3 * a.height * 4)};
  for (int y = 0; y < a.height; ++y)
    for (int x = 0; x < a.width; ++x) {
      int diff = 0;
      for (int c = 0; c < 3; ++c) diff = std::max(diff, std::abs(int(a.at(x, y, c)) - int(b.at(x, y, c))));
      for (int c = 0; c < 4; ++c) {
        out.at(x, y, c) = a.at(x, y, c);
        out.at(x + a.width, y, c) = b.at(x, y, c);
        out.at(x + 2 * a.width, y, c) = c == 3 ? 255 : static_cast<std::uint8_t>(std::min(255, diff * 10));
      }
    }
  return out;
}

// The frames a comparison visits. A scene with a camera path (the outdoor town) is walked along
// it: `short` visits stations of three consecutive frames spread evenly over the whole path (the
// street, the site, the climb, the overview), `full` every frame; a scene without one is orbited
// (path_camera) over --frames frames. Flicker is measured only between consecutive frames; the
// error against the reference at each station's middle frame (every 30th frame of a full path,
// the orbit's middle frame).
struct PathFrame {
  int frame = 0;           // frame of the scene's camera path, or of the orbit
  bool continues = false;  // the frame visited before it is frame - 1
  bool reference = false;  // measured against the reference here
};
struct PathPlan {
  std::string kind;  // "orbit", "short" or "full"
  int length = 0;    // frames of the whole path
  std::vector<PathFrame> frames;
};

PathPlan plan_path(const scene::Scene& scene, const std::string& path, int frames) {
  PathPlan p;
  if (scene.camera_path.empty()) {
    p.kind = "orbit";
    p.length = frames;
    for (int i = 0; i < frames; ++i) p.frames.push_back({i, i > 0, i == frames / 2});
    return p;
  }
  p.length = scene.camera_path.frames();
  if (path == "full") {
    p.kind = "full";
    const int every = std::min(30, p.length);
    for (int i = 0; i < p.length; ++i) p.frames.push_back({i, i > 0, i % every == every / 2});
    return p;
  }
  p.kind = "short";
  const int per_station = std::min({3, frames, p.length});
  const int stations = std::max(1, frames / per_station);
  for (int s = 0; s < stations; ++s) {
    const int span = p.length - per_station;
    const int start = stations == 1 ? span / 2 : static_cast<int>(std::lround(static_cast<double>(s) * span / (stations - 1)));
    for (int j = 0; j < per_station; ++j) p.frames.push_back({start + j, j > 0, j == per_station / 2});
  }
  return p;
}

scene::Camera camera_at(const scene::Scene& scene, const PathPlan& plan, int frame) {
  return plan.kind == "orbit" ? path_camera(scene.camera, frame, plan.length) : scene.camera_path.at(scene.camera, frame);
}

struct Options {
  std::string scene = "outdoor";
  float light_size = -1;       // >= 0: overrides the scene light's size
  std::vector<std::string> techniques = {"pcf", "pcss"};
  std::string path = "short";  // scenes with a camera path: "short" or "full"
  int frames = 12;
  int width = 960, height = 540;
  apps::CalibrationOption calibration;
  bool ci_upper = false;
  std::string output = "out/demo";
  std::string python = "/usr/bin/python3";
  std::string plot_script = tool::script_file("plot_demo.py").string();
  bool plot = true;
  bool baselines = true;       // also the engine baselines: a single map of twice the fixed size, four cascades of it
  bool auto_cascades = true;   // adaptive: as many cascades as the rule needs (unless --map.cascades is given)
  bool reference = true;       // error against a reference of the technique at the reference frames
  // Area-light reference: point lights averaged. 64 against 256 differ by RMSE 0.015 on the street,
  // a sixth of the smallest PCSS error measured; 16 by 0.040 (AreaLightSlow.OutdoorReference...).
  int reference_samples = 64;
  std::string screenshot;      // windowed: write the window here after screenshot_frames frames, then exit
  int screenshot_frames = 10;
};

// One configuration drawn along the path, with everything measured about it.
struct Config {
  std::string name;
  shadows::ShadowSettings settings;
  std::unique_ptr<shadows::Renderer> renderer;
  std::unique_ptr<gl::PassTimer> timer;
  // this frame
  shadows::FrameInfo info;
  io::Image8 color;
  io::ImageF visibility, previous;
  // along the path
  std::vector<double> ms, texels, ssim_vs_engine, flicker_mean_abs, flicker_share;
  std::vector<double> map_triangles;  // per frame: triangles drawn into all its maps after culling
  std::vector<std::string> resolution;  // per frame, cascade_resolutions
  int resolution_changes = 0;
  double allocated = 0;
  std::vector<metrics::ImageError> vs_reference;
  double thin_shadow = 0, gaps = 0;  // masked sums over the reference frames (ThinMasks)
  std::vector<double> pcss_clamped;  // PCSS with the per-pixel requirement: share of filtered pixels clamped, per frame
};

double mean_of(const std::vector<double>& v) {
  double sum = 0;
  for (double x : v) sum += x;
  return v.empty() ? 0.0 : sum / static_cast<double>(v.size());
}

double texels_of(const shadows::FrameInfo& info) {
  double t = 0;
  for (const auto& c : info.cascades) t += static_cast<double>(c.resolution_texels) * c.resolution_texels;
  return t;
}

nlohmann::json reference_error_json(const std::vector<metrics::ImageError>& errors) {
  if (errors.empty()) return nullptr;
  double rmse = 0, mean_abs = 0, ssim = 0, ssim_min = 1;
  std::vector<double> per_frame;
  for (const auto& e : errors) {
    const double n = static_cast<double>(errors.size());
    rmse += e.rmse / n, mean_abs += e.mean_abs / n, ssim += e.ssim / n;
    ssim_min = std::min(ssim_min, e.ssim);
    per_frame.push_back(e.rmse);
  }
  return {{"frames", errors.size()}, {"rmse_mean", rmse},          {"rmse_per_frame", per_frame}, {"mean_abs_mean", mean_abs},
          {"ssim_mean", ssim},       {"ssim_min", ssim_min}};
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

// The largest map side whose four cascades fit one atlas on this device (a 2 × 2 grid of cells
// with guard bands), at most 8192.
int four_cascade_reference_texels() {
  GLint max_size = 0;
  glGetIntegerv(GL_MAX_TEXTURE_SIZE, &max_size);
  return std::min(8192, max_size / 2 - 2 * shadows::kGuardTexels);
}

// Thin casters: the objects a coarse map loses first (the crane's lattice, Kreuzer 2017 Fig. 6.1,
// and the wires between the poles). Their shadow is found with hard shadows from four fitted
// cascades of 4096² (about 1 cm texels near the camera), once with every object and once without
// them: `shadow` marks the pixels only they darken (umbra), `gaps` the lit pixels within two pixels
// of those (the holes between lattice members and the sides of a wire's shadow). Each
// configuration keeps thin_shadow = sum over `shadow` of (1 - V) relative to the reference's,
// and gaps = sum over `gaps` of V relative to the reference's: a map too coarse for a caster
// drops its shadow (thin_shadow < 1) or closes its gaps (gaps < 1).
const std::vector<std::string> kThinCasters = {"crane", "wires"};

struct ThinMasks {
  io::Image8 shadow, gaps;  // one channel, 255 where selected
  std::int64_t shadow_pixels = 0, gap_pixels = 0;
};

ThinMasks thin_masks(shadows::Renderer& with, shadows::Renderer& without, const scene::Camera& camera, const io::ImageF& surface,
                     int width, int height) {
  shadows::ShadowSettings hard;
  hard.technique = shadows::Technique::hard;
  hard.map.resolution_texels = 4096;
  hard.map.cascades = with.scene().light.type == scene::Light::Type::directional ? 4 : 1;
  with.scene().camera = without.scene().camera = camera;
  with.render(hard, width, height);
  without.render(hard, width, height);
  const io::ImageF v = with.read_visibility(), v_free = without.read_visibility();
  const std::size_t n = static_cast<std::size_t>(width) * height;
  ThinMasks m{{width, height, 1, std::vector<std::uint8_t>(n)}, {width, height, 1, std::vector<std::uint8_t>(n)}};
  for (std::size_t p = 0; p < n; ++p)
    if (surface.pixels[4 * p + 3] > 0 && v.pixels[p] < 0.5f && v_free.pixels[p] >= 0.5f) m.shadow.pixels[p] = 255, ++m.shadow_pixels;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const std::size_t p = static_cast<std::size_t>(y) * width + x;
      if (surface.pixels[4 * p + 3] <= 0 || v.pixels[p] < 0.5f || v_free.pixels[p] < 0.5f) continue;
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

// sum over the mask of f(v): (1 - v) for the thin shadow, v for the gaps.
template <class F>
double masked_sum(const io::ImageF& v, const io::Image8& mask, F f) {
  double sum = 0;
  for (std::size_t p = 0; p < mask.pixels.size(); ++p)
    if (mask.pixels[p]) sum += f(v.pixels[p]);
  return sum;
}

// The w × h window (a multiple of 8 pixels) holding the most pixels of `mask`, as x, y.
std::pair<int, int> densest_window(const io::Image8& mask, int w, int h) {
  std::pair<int, int> best{(mask.width - w) / 2, (mask.height - h) / 2};
  std::int64_t most = -1;
  for (int y0 = 0; y0 + h <= mask.height; y0 += 8)
    for (int x0 = 0; x0 + w <= mask.width; x0 += 8) {
      std::int64_t count = 0;
      for (int y = y0; y < y0 + h; y += 2)
        for (int x = x0; x < x0 + w; x += 2) count += mask.pixels[static_cast<std::size_t>(y) * mask.width + x] ? 1 : 0;
      if (count > most) most = count, best = {x0, y0};
    }
  return best;
}

int run_headless(const Options& opt, shadows::ShadowSettings base) {
  // Everything that can refuse the command comes before any output: the plotter, the output
  // directory, the scene and its path; then the first line of progress.
  if (opt.plot) apps::check_python(opt.python, opt.plot_script, "the chart");
  io::StagedDirectory out(opt.output, "report.json");
  gl::HeadlessContext ctx;
  const double t_scene = now_ms();
  scene::Scene scene = scene::load_scene(opt.scene);
  if (opt.light_size >= 0) scene.light.size = opt.light_size;
  const PathPlan plan = plan_path(scene, opt.path, opt.frames);
  std::fprintf(stderr, "scene %s built in %.1f s\n", scene.name.c_str(), (now_ms() - t_scene) / 1000);
  const gl::TimingMethod method = ctx.info().software ? gl::TimingMethod::wall_finish : gl::TimingMethod::gpu_timer;
  const bool directional = scene.light.type == scene::Light::Type::directional;

  nlohmann::json report;
  report["scene"] = scene.name;
  report["device"] = ctx.info();
  report["image_px"] = {opt.width, opt.height};
  report["light"] = {{"type", directional ? "directional" : "spot"}, {"size", scene.light.size}, {"size_unit", directional ? "deg" : "world"}};
  report["path"] = plan.kind;
  report["path_length"] = plan.length;
  report["path_frames"] = plan.frames.size();
  for (const PathFrame& f : plan.frames) report["path_frame_index"].push_back(f.frame);
  report["frame_time_method"] = "wall_finish";
  report["pass_time_method"] = gl::to_string(method);
  report["calibration"] = apps::calibration_json(opt.calibration, base);
  report["calibration"]["bound"] = opt.ci_upper ? "ci95_hi" : "c";
  std::string csv = "technique,configuration,path_frame,frame_ms,texels,cascades,ssim_vs_engine,flicker_mean_abs\n";

  std::printf("penumbra-demo: %s at %dx%d on %s; %zu frames of a %d-frame %s path; calibration %s\n", scene.name.c_str(), opt.width,
              opt.height, ctx.info().renderer.c_str(), plan.frames.size(), plan.length, plan.kind.c_str(),
              opt.calibration.loaded.source.c_str());
  for (const std::string& name : opt.techniques) {
    shadows::ShadowSettings s = base;
    s.technique = shadows::technique_from_string(name);
    apps::apply_calibration_for(opt.calibration, s);
    std::printf("%s\n", apps::calibration_line(opt.calibration, s).c_str());
  }
  const auto& ap = base.adaptive;
  std::printf("adaptive: res = c L / r per cascade, as many cascades as the rule needs; texels no finer than %s at a cascade's near end "
              "(--adaptive.min_texel_px), no wider than %s (--adaptive.max_texel_ws)\n",
              ap.min_texel_px > 0 ? (std::to_string(ap.min_texel_px).substr(0, 4) + " px").c_str() : "the rule's (off)",
              ap.max_texel_ws > 0 ? (std::to_string(ap.max_texel_ws).substr(0, 5) + " ws").c_str() : "the rule's (off)");
  std::printf("frame time: wall clock around glFinish, ms over the path (median [p10, p90])\n");
  std::printf("%-6s %24s %24s %8s %20s %8s %9s %9s\n", "tech", "fixed", "adaptive", "speedup", "adaptive cascades", "min SSIM",
              "max diff", ">1/255");
  const int total = static_cast<int>(opt.techniques.size() * plan.frames.size());
  int done = 0;
  ProgressBar progress("penumbra-demo", true, " frames");
  metrics::SurfaceProbe probe(scene);
  // Thin casters, when the scene has them: the scene with and without them for the masks, which
  // every technique shares (one per reference frame).
  scene::Scene without_thin = scene;
  std::erase_if(without_thin.objects, [](const scene::Object& o) {
    return std::find(kThinCasters.begin(), kThinCasters.end(), o.name) != kThinCasters.end();
  });
  const bool thin = opt.reference && without_thin.objects.size() < scene.objects.size();
  std::unique_ptr<shadows::Renderer> thin_with, thin_without;
  if (thin) {
    thin_with = std::make_unique<shadows::Renderer>(), thin_without = std::make_unique<shadows::Renderer>();
    thin_with->set_scene(scene), thin_without->set_scene(without_thin);
  }
  std::map<int, ThinMasks> thin_cache;
  for (const std::string& name : opt.techniques) {
    shadows::ShadowSettings fixed = base;
    fixed.technique = shadows::technique_from_string(name);
    apps::apply_calibration_for(opt.calibration, fixed);  // the technique's own c
    fixed.adaptive.enabled = false;
    shadows::ShadowSettings adapt = fixed;
    adapt.adaptive.enabled = true;
    if (opt.auto_cascades) adapt.map.cascades = 0;  // as many rule-sized cascades as the view needs (adaptive/cascades.h)
    // The same rule without quantization or hysteresis: every frame the rule's exact answer.
    shadows::ShadowSettings raw = adapt;
    raw.adaptive.quantum_texels = 1;
    raw.adaptive.shrink_delay_frames = 0;
    // The flicker measure's floor: one map of the fixed size, not fitted (fixed in the world).
    shadows::ShadowSettings world_fixed = fixed;
    world_fixed.map.fit = false;
    world_fixed.map.cascades = 1;

    // Configurations 0 and 1 are adaptive and fixed (the first table); then the baselines engines
    // ship, drawn along the same path: one map of twice the fixed size, and the cascaded default
    // (four cascades of the fixed size, practical split, stabilized, blended: the map.* defaults),
    // the engine baseline every image is compared with.
    std::vector<Config> configs;
    auto add = [&](std::string config, const shadows::ShadowSettings& settings) {
      Config c;
      c.name = std::move(config);
      c.settings = settings;
      c.renderer = std::make_unique<shadows::Renderer>();
      c.renderer->set_scene(scene);
      c.timer = std::make_unique<gl::PassTimer>(method == gl::TimingMethod::gpu_timer);
      configs.push_back(std::move(c));
    };
    const std::string fixed_name = "fixed-" + std::to_string(fixed.map.resolution_texels);
    add("adaptive", adapt);
    add(fixed_name, fixed);
    std::size_t engine = 1;
    if (opt.baselines) {
      shadows::ShadowSettings big = fixed, csm = fixed;
      big.map.resolution_texels = 2 * fixed.map.resolution_texels;
      big.map.cascades = 1;
      csm.map.cascades = 4;
      add("fixed-" + std::to_string(big.map.resolution_texels), big);
      add("4x" + std::to_string(csm.map.resolution_texels) + "-cascades", csm);
      engine = configs.size() - 1;
    }
    const std::size_t n_timed = configs.size();  // those in the tables; the next two only measure flicker
    add("adaptive, no hysteresis", raw);
    add("floor (world-fixed map)", world_fixed);

    // The reference (metrics/ground_truth.h): four cascades of (up to) 8192² with the same
    // world-space filter, or the mean of hard shadows over the light's area, each from four
    // cascades of 4096².
    shadows::ShadowSettings ref_settings = fixed;
    if (directional) ref_settings.map.cascades = 4;
    metrics::ReferenceOptions ref_options;
    ref_options.filter_resolution_texels = four_cascade_reference_texels();
    ref_options.area_samples = opt.reference_samples;
    shadows::Renderer ref_renderer;
    if (opt.reference) ref_renderer.set_scene(scene);
    std::string ref_description;
    double ref_ms = 0;
    int ref_frames = 0;
    double ref_thin_shadow = 0, ref_gaps = 0;
    std::int64_t thin_pixels = 0, gap_pixels = 0;
    int crop_frame = -1;
    std::int64_t crop_pixels = 0;

    // Warm-up (shader compilation, allocation) at the path's first camera; not timed.
    for (auto& c : configs) {
      c.renderer->scene().camera = camera_at(scene, plan, plan.frames.front().frame);
      c.renderer->render(c.settings, opt.width, opt.height);
    }
    io::Image8 shown_f, shown_a;
    std::vector<double> ssim_fa, max_abs_fa, share_fa;
    io::ImageF surface_previous;
    glm::mat4 view_projection_previous(1);
    std::vector<io::Image8> crops;
    std::vector<std::string> crop_labels;
    for (std::size_t i = 0; i < plan.frames.size(); ++i) {
      const PathFrame& pf = plan.frames[i];
      progress(++done, total, name + " frame " + std::to_string(pf.frame) + (pf.reference && opt.reference ? " + reference" : ""));
      const scene::Camera camera = camera_at(scene, plan, pf.frame);
      io::ImageF surface = probe.render(camera, opt.width, opt.height);
      const glm::mat4 view_projection = metrics::camera_view_projection(camera, opt.width, opt.height);
      for (std::size_t k = 0; k < configs.size(); ++k) {
        Config& c = configs[k];
        c.renderer->scene().camera = camera;
        if (!pf.continues && c.settings.adaptive.enabled) {
          // A new station: the controller starts from this view, not from the last station's maps
          // (which a 30-frame shrink delay would keep), and one untimed frame measures the view's
          // PCSS requirement. Consecutive frames (a full path) keep the hysteresis.
          c.renderer->reset_adaptive();
          c.renderer->render(c.settings, opt.width, opt.height);
        }
        const Timed t = timed_render(*c.renderer, c.settings, opt.width, opt.height, *c.timer);
        c.info = t.info;
        if (t.info.pcss_requirement.valid) c.pcss_clamped.push_back(t.info.pcss_requirement.clamped_fraction);
        c.ms.push_back(t.ms);
        c.texels.push_back(texels_of(t.info));
        double triangles = 0;
        for (const std::uint64_t n : t.info.map_triangles) triangles += static_cast<double>(n);
        c.map_triangles.push_back(triangles);
        c.allocated = static_cast<double>(t.info.atlas_width) * t.info.atlas_height;
        const std::string res = cascade_resolutions(t.info);
        if (!c.resolution.empty() && c.resolution.back() != res) ++c.resolution_changes;
        c.resolution.push_back(res);
        if (k < n_timed) c.color = c.renderer->read_color();  // the lit image: compared in the tables only
        c.visibility = c.renderer->read_visibility();
        // Flicker (metrics/temporal.h): visibility of this frame against the previous one at the
        // pixels whose surface point stayed in view.
        if (pf.continues) {
          const metrics::Flicker fl = metrics::flicker({&c.previous, &surface_previous, view_projection_previous},
                                                       {&c.visibility, &surface, view_projection});
          c.flicker_mean_abs.push_back(fl.mean_abs);
          c.flicker_share.push_back(fl.share_changed);
        }
      }
      for (std::size_t k = 0; k < n_timed; ++k) configs[k].ssim_vs_engine.push_back(metrics::compare(configs[engine].color, configs[k].color).ssim);
      const metrics::ImageError e = metrics::compare(configs[1].color, configs[0].color);
      ssim_fa.push_back(e.ssim), max_abs_fa.push_back(e.max_abs), share_fa.push_back(e.share_above_threshold);
      if (pf.reference && opt.reference) {
        ref_renderer.scene().camera = camera;
        const metrics::Reference ref = metrics::make_reference(ref_renderer, ref_settings, opt.width, opt.height, ref_options);
        ref_description = ref.description + (ref.note.empty() ? "" : " (" + ref.note + ")");
        ref_ms += ref.render_ms;
        ++ref_frames;
        // Compared where a surface is drawn (the sky is lit in every image).
        io::Image8 mask{opt.width, opt.height, 1, std::vector<std::uint8_t>(static_cast<std::size_t>(opt.width) * opt.height)};
        for (std::size_t p = 0; p < mask.pixels.size(); ++p) mask.pixels[p] = surface.pixels[4 * p + 3] > 0 ? 255 : 0;
        metrics::CompareOptions masked;
        masked.mask = &mask;
        bool any = false;
        for (std::uint8_t m : mask.pixels) any = any || m;
        if (any)
          for (auto& c : configs) c.vs_reference.push_back(metrics::compare(ref.visibility, c.visibility, masked));
        // Side-by-side crops (reference, adaptive, engine, fixed) of a quarter of the image: where
        // the thin casters' shadows are densest, or the middle of the first reference frame.
        const int w = std::max(8, opt.width / 4), h = std::max(8, opt.height / 4);
        std::pair<int, int> at{(opt.width - w) / 2, (opt.height - h) / 2};
        bool take_crop = crops.empty();
        if (thin) {
          if (!thin_cache.count(pf.frame)) thin_cache[pf.frame] = thin_masks(*thin_with, *thin_without, camera, surface, opt.width, opt.height);
          const ThinMasks& m = thin_cache[pf.frame];
          thin_pixels += m.shadow_pixels, gap_pixels += m.gap_pixels;
          auto dark = [](float v) { return 1.0 - v; };
          auto lit = [](float v) { return static_cast<double>(v); };
          ref_thin_shadow += masked_sum(ref.visibility, m.shadow, dark), ref_gaps += masked_sum(ref.visibility, m.gaps, lit);
          for (auto& c : configs) c.thin_shadow += masked_sum(c.visibility, m.shadow, dark), c.gaps += masked_sum(c.visibility, m.gaps, lit);
          if (m.shadow_pixels > crop_pixels) {
            crop_pixels = m.shadow_pixels, crop_frame = pf.frame, take_crop = true;
            at = densest_window(m.shadow, w, h);
          }
        }
        if (take_crop) {
          const int band = w >= 120 ? 20 : 0;  // room for the label (drawn 24 px high at twice the crop's size)
          crops = {grey_crop(ref.visibility, at.first, at.second, w, h, band)};
          crop_labels = {"reference"};
          for (std::size_t k : {std::size_t{0}, engine, std::size_t{1}}) {
            crops.push_back(grey_crop(configs[k].visibility, at.first, at.second, w, h, band));
            crop_labels.push_back(configs[k].name);
          }
          crop_labels.front() += " (frame " + std::to_string(pf.frame) + ")";
        }
      }
      for (std::size_t k = 0; k < configs.size(); ++k) {
        char row[320];
        std::snprintf(row, sizeof row, "%s,%s,%d,%.4f,%.0f,%s,%.6f,%.6f\n", name.c_str(), configs[k].name.c_str(), pf.frame,
                      configs[k].ms.back(), configs[k].texels.back(), configs[k].resolution.back().c_str(),
                      k < n_timed ? configs[k].ssim_vs_engine.back() : std::nan(""),
                      pf.continues ? configs[k].flicker_mean_abs.back() : std::nan(""));
        csv += row;
      }
      if (i == plan.frames.size() / 2) shown_f = configs[1].color, shown_a = configs[0].color;
      for (auto& c : configs) c.previous = std::move(c.visibility);
      surface_previous = std::move(surface);
      view_projection_previous = view_projection;
    }
    progress.clear();  // the technique's tables follow on stdout
    for (auto& c : configs) c.timer->poll(true);
    io::write_png(out.path() / (name + "-fixed-vs-adaptive.png"), side_by_side(shown_f, shown_a));
    if (!crops.empty())
      io::write_png(out.path() / (name + "-crops.png"),
                    io::montage(crops, crop_labels, static_cast<int>(crops.size()), std::min(2 * crops.front().width, 480)));

    const Config& ca = configs[0];
    const Config& cf = configs[1];
    std::vector<double> res_a;
    for (const auto& r : ca.resolution) res_a.push_back(std::stod(r.substr(0, r.find('+'))));
    const Spread sf = spread(cf.ms), sa = spread(ca.ms), sr = spread(res_a);
    // Every cascade of the adaptive maps, as most frames along the path had them ("2624+3904").
    std::map<std::string, int> seen;
    for (const auto& r : ca.resolution) ++seen[r];
    const std::string usual = std::max_element(seen.begin(), seen.end(), [](const auto& a, const auto& b) { return a.second < b.second; })->first;
    const double speedup = sf.median / std::max(sa.median, 1e-9);
    const double min_ssim = *std::min_element(ssim_fa.begin(), ssim_fa.end());
    const double worst_diff = *std::max_element(max_abs_fa.begin(), max_abs_fa.end());
    const double worst_share = *std::max_element(share_fa.begin(), share_fa.end());
    nlohmann::json t;
    t["technique"] = name;
    t["settings_fixed"] = shadows::to_json(fixed);
    t["settings_adaptive"] = shadows::to_json(adapt);
    t["calibration"] = apps::calibration_json(opt.calibration, adapt);
    t["calibration"]["bound"] = opt.ci_upper ? "ci95_hi" : "c";
    t["fixed"] = {{"resolution_texels", fixed.map.resolution_texels}, {"frame_ms", sf}, {"passes", io::to_json(cf.timer->stats())}};
    t["adaptive"] = {{"resolution_texels", sr},
                     {"cascades_most_frames", usual},
                     {"storage", ca.info.storage},
                     {"resolution_source", ca.info.resolution_source},
                     {"frame_ms", sa},
                     {"passes", io::to_json(ca.timer->stats())}};
    if (ca.info.pcss_requirement.valid)
      t["adaptive"]["pcss_requirement"] = {{"clamped_fraction", ca.info.pcss_requirement.clamped_fraction},
                                           {"clamped_fraction_mean", mean_of(ca.pcss_clamped)},
                                           {"above_max_fraction", ca.info.pcss_requirement.above_max_fraction}};
    t["speedup_median"] = speedup;
    t["image"] = {{"ssim_min", min_ssim}, {"ssim_mean", mean_of(ssim_fa)}, {"max_abs_max", worst_diff}, {"share_above_1_255_max", worst_share}};
    if (opt.reference && ref_frames > 0)
      t["reference"] = {{"description", ref_description}, {"frames", ref_frames}, {"render_ms_mean", ref_ms / ref_frames}};
    if (thin && ref_frames > 0)
      t["thin_casters"] = {{"objects", kThinCasters},
                           {"shadow_pixels", thin_pixels},
                           {"gap_pixels", gap_pixels},
                           {"reference_shadow_darkness_mean", thin_pixels > 0 ? ref_thin_shadow / static_cast<double>(thin_pixels) : 0.0},
                           {"reference_gap_visibility_mean", gap_pixels > 0 ? ref_gaps / static_cast<double>(gap_pixels) : 0.0},
                           {"crop_frame", crop_frame}};
    for (const Config& c : configs) {
      t["flicker"].push_back({{"configuration", c.name},
                              {"mean_abs_mean", mean_of(c.flicker_mean_abs)},
                              {"share_changed_mean", mean_of(c.flicker_share)},
                              {"mean_abs_per_frame", c.flicker_mean_abs},
                              {"resolution_changes", c.resolution_changes}});
      t["along_path"].push_back({{"configuration", c.name}, {"frame_ms", c.ms}, {"texels", c.texels}, {"resolution", c.resolution}});
    }
    // The thin casters' shadow and gaps a configuration keeps, relative to the reference's.
    auto shadow_kept = [&](const Config& c) { return c.thin_shadow / std::max(ref_thin_shadow, 1e-9); };
    auto gaps_kept = [&](const Config& c) { return gap_pixels > 0 ? c.gaps / std::max(ref_gaps, 1e-9) : 1.0; };
    auto measured = [&](const Config& c, nlohmann::json& j) {
      j["texels_rendered"] = spread(c.texels);
      j["texels_allocated"] = c.allocated;
      j["map_triangles"] = spread(c.map_triangles);
      j["ssim_vs_engine_min"] = *std::min_element(c.ssim_vs_engine.begin(), c.ssim_vs_engine.end());
      j["reference_error"] = reference_error_json(c.vs_reference);
      if (thin_pixels > 0) j["thin_casters"] = {{"shadow_kept", shadow_kept(c)}, {"gaps_kept", gaps_kept(c)}};
    };
    measured(cf, t["fixed"]);
    measured(ca, t["adaptive"]);
    t["adaptive"]["without_hysteresis"] = {{"resolution_changes", configs[n_timed].resolution_changes},
                                           {"texels_rendered", spread(configs[n_timed].texels)},
                                           {"reference_error", reference_error_json(configs[n_timed].vs_reference)}};
    t["engine_baseline"] = configs[engine].name;
    t["speedup_vs_engine_median"] = spread(configs[engine].ms).median / std::max(sa.median, 1e-9);
    for (std::size_t k = 2; k < n_timed; ++k) {
      nlohmann::json b = {{"name", configs[k].name},
                          {"settings", shadows::to_json(configs[k].settings)},
                          {"frame_ms", spread(configs[k].ms)},
                          {"passes", io::to_json(configs[k].timer->stats())}};
      measured(configs[k], b);
      t["baselines"].push_back(b);
    }
    report["techniques"].push_back(t);

    std::printf("%-6s %8.1f [%6.1f, %6.1f] %8.1f [%6.1f, %6.1f] %7.2fx %20s %8.4f %9.4f %9.4f\n", name.c_str(), sf.median, sf.p10,
                sf.p90, sa.median, sa.p10, sa.p90, speedup, (usual + "²").c_str(), min_ssim, worst_diff, worst_share);
    // Every configuration against the engine baseline and the reference, texels per frame (median).
    const double engine_median = spread(configs[engine].ms).median;
    std::printf("  %-24s %24s %7s %9s %9s %9s %8s %9s %8s %7s %7s\n", "configuration", "frame ms", "vs eng.", "Mtex drawn", "allocated",
                "Mtri maps", "SSIM eng", "RMSE ref", "SSIM ref", "thin", "gaps");
    for (std::size_t k = 0; k < n_timed; ++k) {
      const Config& c = configs[k];
      const Spread ms = spread(c.ms);
      const nlohmann::json err = reference_error_json(c.vs_reference);
      std::printf("  %-24s %8.1f [%6.1f, %6.1f] %6.2fx %10.2f %9.2f %9.3f %8.4f", c.name.c_str(), ms.median, ms.p10, ms.p90,
                  engine_median / std::max(ms.median, 1e-9), spread(c.texels).median / 1e6, c.allocated / 1e6,
                  spread(c.map_triangles).median / 1e6, *std::min_element(c.ssim_vs_engine.begin(), c.ssim_vs_engine.end()));
      if (!err.is_null()) std::printf(" %9.5f %8.4f", err["rmse_mean"].get<double>(), err["ssim_mean"].get<double>());
      if (thin_pixels > 0)
        std::printf(" %7.3f %7.3f", shadow_kept(c), gaps_kept(c));
      std::printf("\n");
    }
    if (t.contains("reference")) std::printf("  reference: %s\n", ref_description.c_str());
    if (t.contains("thin_casters"))
      std::printf("  thin casters (crane, wires): %lld shadow and %lld gap pixels over %d frames; thin = their shadow kept, gaps = "
                  "their gaps kept, relative to the reference\n",
                  static_cast<long long>(thin_pixels), static_cast<long long>(gap_pixels), ref_frames);
    if (!ca.pcss_clamped.empty())
      std::printf("  PCSS: %.1f %% of the filtered pixels held at the minimum penumbra (clamped; mean over the path, %.1f %% in its last "
                  "frame)\n",
                  100 * mean_of(ca.pcss_clamped), 100 * ca.pcss_clamped.back());
    if (plan.frames.size() > 1) {
      std::printf("  %-24s %16s %14s %12s\n", "flicker along the path", "mean |dV|", "share > 1/255", "res changes");
      for (const auto& f : t["flicker"])
        std::printf("  %-24s %16.5f %14.4f %12d\n", f["configuration"].get<std::string>().c_str(), f["mean_abs_mean"].get<double>(),
                    f["share_changed_mean"].get<double>(), f["resolution_changes"].get<int>());
    }
    std::fflush(stdout);
  }
  io::write_file_atomic(out.path() / "frames.csv", csv);
  io::write_file_atomic(out.path() / "report.json", json_input::dump(report, 2) + "\n");
  if (opt.plot)
    apps::run_python_script(opt.python, opt.plot_script, {(out.path() / "report.json").string(), out.path().string()}, "the chart");
  out.commit();
  std::printf("wrote %s/\n", opt.output.c_str());
  return 0;
}

#if PENUMBRA_DEMO_GUI
int run_windowed(const Options& opt, shadows::ShadowSettings settings) {
  scene::Scene scene = scene::load_scene(opt.scene);
  if (opt.light_size >= 0) scene.light.size = opt.light_size;
  gl::Glfw glfw;
  gl::Window window(
      {.title = "Penumbra demo - " + scene.name, .width = opt.width, .height = opt.height, .gl_errors_throw = gl::kDebugBuild});
  shadows::Renderer renderer;
  renderer.set_scene(scene);
  settings.adaptive.enabled = true;
  if (opt.auto_cascades) settings.map.cascades = 0;
  apps::CalibrationFollower follower;  // the panel's technique switch picks that technique's c
  gl::PassTimer timer(!window.info().software);
  bool show_map = true, show_cascades = false, animate = true;
  int frame = 0, path_i = 0;
  double fps = 0, last = now_ms();
  while (!window.should_close()) {
    glfw.wait_events(0);
    window.begin_frame();
    if (animate)
      renderer.scene().camera = scene.camera_path.empty()
                                    ? path_camera(scene.camera, path_i++ % (4 * opt.frames), 4 * opt.frames)
                                    : scene.camera_path.at(scene.camera, path_i++ % scene.camera_path.frames());
    int fb_w = 0, fb_h = 0;
    window.framebuffer_size(fb_w, fb_h);
    if (frame % 30 == 0) timer.clear();
    renderer.set_show_cascades(show_cascades);
    follower.update(opt.calibration, settings);
    const shadows::FrameInfo info = renderer.render(settings, std::max(fb_w, 1), std::max(fb_h, 1), &timer);
    renderer.present(0, fb_w, fb_h);
    const double t = now_ms();
    fps = 0.9 * fps + 0.1 * 1000.0 / std::max(t - last, 1e-3);
    last = t;

    ImGui::SetNextWindowPos({10, 10}, ImGuiCond_FirstUseEver);
    ImGui::SetNextWindowSize({460, 0}, ImGuiCond_FirstUseEver);
    ImGui::Begin("Penumbra demo");
    ImGui::PushItemWidth(200);
    ImGui::Text("%s | %s | %.1f fps", scene.name.c_str(), window.info().renderer.c_str(), fps);
    ImGui::Checkbox("camera path", &animate);
    ImGui::Checkbox("adaptive resolution", &settings.adaptive.enabled);
    ImGui::Text("%s", apps::calibration_line(opt.calibration, settings).c_str());
    gui::shadow_settings_panel(settings);
    gui::light_size_control(renderer.scene().light);
    ImGui::Separator();
    ImGui::Text("resolution (%s, %s storage, atlas %dx%d)", info.resolution_source.c_str(), info.storage.c_str(), info.atlas_width,
                info.atlas_height);
    for (std::size_t i = 0; i < info.cascades.size(); ++i) {
      const auto& c = info.cascades[i];
      ImGui::Text("  cascade %zu: %d^2 (rule %.0f), depth %.1f-%.1f, extent %.2f ws", i, c.resolution_texels, c.required_texels,
                  c.split_near_ws, c.split_far_ws, c.light.extent_ws);
    }
    if (info.pcss_requirement.valid)
      ImGui::Text("PCSS: %.1f %% of pixels at the min penumbra, %.1f %% above the max map", 100 * info.pcss_requirement.clamped_fraction,
                  100 * info.pcss_requirement.above_max_fraction);
    for (const auto& st : timer.stats()) ImGui::Text("%-16s %7.2f ms (%s)", st.pass.c_str(), st.median_ms, gl::to_string(st.method));
    ImGui::Checkbox("cascade overlay", &show_cascades);
    ImGui::Checkbox("show shadow map", &show_map);
    if (show_map && renderer.shadow_map_texture() && info.atlas_width > 0) {
      // Cascade 0's region of the atlas (flipped: GL's rows run bottom up).
      const auto& c = info.cascades.front();
      const float w = static_cast<float>(info.atlas_width), h = static_cast<float>(info.atlas_height);
      const float r = static_cast<float>(c.resolution_texels);
      ImGui::Image(reinterpret_cast<ImTextureID>(static_cast<std::intptr_t>(renderer.shadow_map_texture())), {200, 200},
                   {c.atlas_x / w, (c.atlas_y + r) / h}, {(c.atlas_x + r) / w, c.atlas_y / h});
    }
    ImGui::PopItemWidth();
    ImGui::End();
    window.end_frame();
    ++frame;
    if (!opt.screenshot.empty() && frame >= opt.screenshot_frames) {
      io::write_png(opt.screenshot, window.read_back());
      break;
    }
    window.swap();
  }
  return 0;
}
#endif

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Adaptive shadow-map resolution against a fixed resolution: frame time and image difference."};
  cli::describe_tool(app, "penumbra-demo", "adaptive.md");
  Options opt;
  bool headless = false;
  shadows::ShadowSettings base = demo_defaults();
  app.add_flag("--headless", headless, "run the comparison along the camera path without a window");
  app.add_option("--scene", opt.scene, "built-in scene name or scene file (.json)");
  apps::add_light_size_option(app, opt.light_size);
  app.add_option("--techniques", opt.techniques, "techniques to compare (comma separated)")->delimiter(',');
  app.add_option("--path", opt.path,
                 "scenes with a camera path: short (--frames frames, as stations of 3 consecutive frames spread over the path) "
                 "or full (every frame)")
      ->check(CLI::IsMember({"short", "full"}));
  app.add_option("--frames", opt.frames, "frames per technique: of the short path, or of the orbit of a scene without a camera path")
      ->check(CLI::Range(1, 100000));
  app.add_option("--width", opt.width, "image width in pixels")->check(CLI::Range(16, 16384));
  app.add_option("--height", opt.height, "image height in pixels")->check(CLI::Range(16, 16384));
  app.add_option("--fixed-resolution", base.map.resolution_texels, "resolution of the fixed comparison, texels per side")
      ->check(CLI::Range(1, 65536));
  apps::add_calibration_option(app, opt.calibration);
  app.add_flag("--ci-upper", opt.ci_upper, "use the upper bound of c's 95 % interval (more conservative)");
  app.add_option("-o,--output", opt.output, "output directory (replaced as a whole when the run succeeds)")
      ->check(cli::path_given());
  app.add_option("--python", opt.python, "Python with matplotlib that draws the chart");
  app.add_flag("!--no-plot", opt.plot, "skip the bar chart");
  app.add_flag("!--no-baselines", opt.baselines,
               "skip the engine baselines (one map of twice --fixed-resolution, four cascades of it) and the comparison with them");
  app.add_flag("!--no-reference", opt.reference,
               "skip the error against the reference (four cascades of 8192² with the same filter, or the area-light mean)");
  app.add_option("--reference-samples", opt.reference_samples, "area-light reference: point lights averaged (rounded up to a square)")
      ->check(CLI::Range(1, 4096));
  app.add_option("--screenshot", opt.screenshot, "windowed: write the window (with the panel) to this PNG, then exit");
  app.add_option("--screenshot-frames", opt.screenshot_frames, "windowed: frames before --screenshot")->check(CLI::Range(1, 100000));
  apps::add_settings_options(app, base);
  if (const auto status = cli::parse(app, argc, argv, "penumbra-demo")) return *status;
  opt.auto_cascades = app.count("--map.cascades") == 0;
  try {
    std::vector<shadows::Technique> compared;
    std::string listed;
    for (const auto& t : opt.techniques) {
      compared.push_back(shadows::technique_from_string(t));
      listed += (listed.empty() ? "" : ",") + t;
    }
    (void)apps::setting_stands_for(app, "--map.resolution_texels", "--fixed-resolution");
    if (headless) apps::refuse_unused_technique_options(app, compared, "--techniques " + listed);
    apps::apply_calibration(app, opt.calibration, base, opt.ci_upper);
    if (headless) return run_headless(opt, base);
#if PENUMBRA_DEMO_GUI
    return run_windowed(opt, base);
#else
    return cli::fail("penumbra-demo", "built without GUI support; use --headless", cli::kExitUsage);
#endif
  } catch (const std::exception& e) {
    return cli::fail("penumbra-demo", e);
  }
}
