// penumbra-demo: adaptive shadow-map resolution against a fixed resolution.
//
//   --headless  for each technique, renders the scene along a fixed camera path twice, once at a
//               fixed resolution (default 2048²) and once with the adaptive rule res = c / r_uv,
//               and reports frame time (median and spread over the path), per-pass times, the
//               resolution used, and the image difference (max abs, SSIM, share of pixels off by
//               more than 1/255); beside them the engine baselines (one map of twice the fixed
//               size, four cascades of the fixed size) with texels drawn and allocated and SSIM
//               against the cascades. Writes report.json, frames.csv, side-by-side images and a
//               bar chart (scripts/plot_demo.py) into -o DIR; prints the tables.
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
#include <memory>
#include <string>
#include <vector>

#include <glm/gtc/constants.hpp>

#include "adaptive/resolution_rule.h"
#include "cli/main.h"
#include "io/atomic_file.h"
#include "json/json_input.h"
#include "apps/cli_options.h"
#include "apps/run_python.h"
#include "gl/context.h"
#include "gl/timer.h"
#include "io/image_io.h"
#include "io/report.h"
#include "io/staged_dir.h"
#include "metrics/image_error.h"
#include "metrics/surface_probe.h"
#include "metrics/temporal.h"
#include "scene/scene.h"
#include "shadows/renderer.h"

#if PENUMBRA_DEMO_GUI
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <imgui.h>

#include "gl/window.h"
#include "gui/settings_panel.h"
#endif

using namespace penumbra;
namespace fs = std::filesystem;

namespace {

// The demo's defaults: filters sized in world units (the rule needs a world-space radius), grid
// kernels (exact, deterministic: the two images differ only by the map's resolution).
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

struct Spread {
  double median = 0, p10 = 0, p90 = 0, min = 0, max = 0;
};
Spread spread(std::vector<double> v) {
  Spread s;
  if (v.empty()) return s;
  std::sort(v.begin(), v.end());
  auto at = [&](double q) { return v[static_cast<std::size_t>(std::lround(q * static_cast<double>(v.size() - 1)))]; };
  s.median = at(0.5), s.p10 = at(0.1), s.p90 = at(0.9), s.min = v.front(), s.max = v.back();
  return s;
}
nlohmann::json to_json(const Spread& s) {
  return {{"median", s.median}, {"p10", s.p10}, {"p90", s.p90}, {"min", s.min}, {"max", s.max}};
}

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

struct Options {
  std::string scene = "demo";
  float light_size = -1;       // >= 0: overrides the scene light's size
  std::vector<std::string> techniques = {"pcf", "pcss"};
  int frames = 16;
  int width = 1280, height = 720;
  apps::CalibrationOption calibration;
  bool ci_upper = false;
  std::string output = "out/demo";
  std::string python = "/usr/bin/python3";
  std::string plot_script = tool::script_file("plot_demo.py").string();
  bool plot = true;
  bool baselines = true;       // also the engine baselines: a single map of twice the fixed size, four cascades of it
  std::string screenshot;      // windowed: write the window here after screenshot_frames frames, then exit
  int screenshot_frames = 10;
};

int run_headless(const Options& opt, shadows::ShadowSettings base) {
  gl::HeadlessContext ctx;
  scene::Scene scene = scene::load_scene(opt.scene);
  if (opt.light_size >= 0) scene.light.size = opt.light_size;
  io::StagedDirectory out(opt.output, "report.json");
  const gl::TimingMethod method = ctx.info().software ? gl::TimingMethod::wall_finish : gl::TimingMethod::gpu_timer;

  nlohmann::json report;
  report["scene"] = scene.name;
  report["device"] = io::to_json(ctx.info());
  report["image_px"] = {opt.width, opt.height};
  report["light"] = {{"type", scene.light.type == scene::Light::Type::spot ? "spot" : "directional"},
                     {"size", scene.light.size},
                     {"size_unit", scene.light.type == scene::Light::Type::spot ? "world" : "deg"}};
  report["path_frames"] = opt.frames;
  report["frame_time_method"] = "wall_finish";
  report["pass_time_method"] = gl::to_string(method);
  report["calibration"] = apps::calibration_json(opt.calibration, base);
  report["calibration"]["bound"] = opt.ci_upper ? "ci95_hi" : "c";
  std::string csv = "technique,frame,fixed_ms,adaptive_ms,fixed_texels,adaptive_texels,cascades,ssim,max_abs,share_above_1_255\n";

  std::printf("penumbra-demo: %s at %dx%d on %s; %d path frames; calibration %s\n", scene.name.c_str(), opt.width, opt.height,
              ctx.info().renderer.c_str(), opt.frames, opt.calibration.loaded.source.c_str());
  for (const std::string& name : opt.techniques) {
    shadows::ShadowSettings s = base;
    s.technique = shadows::technique_from_string(name);
    apps::apply_calibration_for(opt.calibration, s);
    std::printf("c for %s = %.3g texels: %s\n", name.c_str(), s.adaptive.c, opt.calibration.source_of_c(s).c_str());
  }
  std::printf("frame time: wall clock around glFinish, ms over the path (median [p10, p90])\n");
  std::printf("%-6s %24s %24s %8s %14s %8s %9s %9s\n", "tech", "fixed", "adaptive", "speedup", "adaptive res", "min SSIM",
              "max diff", ">1/255");
  const int total = static_cast<int>(opt.techniques.size()) * opt.frames;
  int done = 0;
  for (const std::string& name : opt.techniques) {
    shadows::ShadowSettings fixed = base;
    fixed.technique = shadows::technique_from_string(name);
    apps::apply_calibration_for(opt.calibration, fixed);  // the technique's own c
    fixed.adaptive.enabled = false;
    shadows::ShadowSettings adapt = fixed;
    adapt.adaptive.enabled = true;

    shadows::Renderer rf, ra;
    rf.set_scene(scene);
    ra.set_scene(scene);
    gl::PassTimer timer_f(method == gl::TimingMethod::gpu_timer), timer_a(method == gl::TimingMethod::gpu_timer);
    // Warm-up (shader compilation, allocation) at the path's first camera; not timed.
    rf.scene().camera = ra.scene().camera = path_camera(scene.camera, 0, opt.frames);
    rf.render(fixed, opt.width, opt.height);
    ra.render(adapt, opt.width, opt.height);

    std::vector<double> ms_f, ms_a, ssim, max_abs, share, res_a;
    io::Image8 shown_f, shown_a;
    shadows::FrameInfo last_a;
    // The baselines engines ship, drawn along the same path: one map of twice the fixed size, and
    // the cascaded default (four cascades of the fixed size, practical split, stabilized, blended:
    // the map.* defaults). Each image is compared with the four cascades' (the engine baseline).
    struct Baseline {
      std::string name;
      shadows::ShadowSettings settings;
      std::unique_ptr<shadows::Renderer> renderer;
      std::vector<double> ms, texels, ssim_vs_engine;
      double allocated = 0;
    };
    std::vector<Baseline> baselines;
    if (opt.baselines) {
      shadows::ShadowSettings big = fixed, csm = fixed;
      big.map.resolution_texels = 2 * fixed.map.resolution_texels;
      big.map.cascades = 1;
      csm.map.cascades = 4;
      baselines.push_back({"fixed-" + std::to_string(big.map.resolution_texels), big, std::make_unique<shadows::Renderer>(), {}, {}, {}, 0});
      baselines.push_back({"4x" + std::to_string(csm.map.resolution_texels) + "-cascades", csm, std::make_unique<shadows::Renderer>(), {}, {}, {}, 0});
      for (auto& b : baselines) {
        b.renderer->set_scene(scene);
        b.renderer->scene().camera = path_camera(scene.camera, 0, opt.frames);
        b.renderer->render(b.settings, opt.width, opt.height);  // warm-up, not timed
      }
    }
    std::vector<double> texels_f, texels_a, ssim_f_engine, ssim_a_engine;
    auto texels_of = [](const shadows::FrameInfo& info) {
      double t = 0;
      for (const auto& c : info.cascades) t += static_cast<double>(c.resolution_texels) * c.resolution_texels;
      return t;
    };
    // Flicker along the path (metrics/temporal.h): each configuration's visibility of frame t
    // against frame t-1 at the pixels whose surface point stayed in view, and the path's floor,
    // measured with one unfitted map of the fixed size (fixed in the world, so whatever it
    // measures is the reprojection's own).
    struct Temporal {
      std::string name;
      io::ImageF previous;
      std::vector<double> mean_abs, share_changed;
      std::string resolution;  // the last frame's (cascade_resolutions)
      int resolution_changes = 0;
    };
    metrics::SurfaceProbe probe(scene);
    io::ImageF surface_previous;
    glm::mat4 view_projection_previous(1);
    std::vector<Temporal> temporal;
    auto track = [&](std::size_t k, const std::string& config, const shadows::Renderer& r, const shadows::FrameInfo& info,
                     const metrics::FrameSample& current) {
      if (temporal.size() <= k) temporal.push_back({config, {}, {}, {}, {}, 0});
      Temporal& tm = temporal[k];
      io::ImageF vis = r.read_visibility();
      const std::string res = cascade_resolutions(info);
      if (!tm.resolution.empty() && tm.resolution != res) ++tm.resolution_changes;
      tm.resolution = res;
      if (!tm.previous.pixels.empty()) {
        const metrics::Flicker fl = metrics::flicker({&tm.previous, &surface_previous, view_projection_previous},
                                                     {&vis, current.surface, current.view_projection});
        tm.mean_abs.push_back(fl.mean_abs);
        tm.share_changed.push_back(fl.share_changed);
      }
      tm.previous = std::move(vis);
    };
    shadows::ShadowSettings world_fixed = fixed;
    world_fixed.map.fit = false;
    world_fixed.map.cascades = 1;
    shadows::Renderer floor_renderer;
    floor_renderer.set_scene(scene);
    for (int i = 0; i < opt.frames; ++i) {
      std::fprintf(stderr, "\r[%d/%d] %s frame %d/%d ", ++done, total, name.c_str(), i + 1, opt.frames);
      std::fflush(stderr);
      rf.scene().camera = ra.scene().camera = path_camera(scene.camera, i, opt.frames);
      const Timed f = timed_render(rf, fixed, opt.width, opt.height, timer_f);
      const Timed a = timed_render(ra, adapt, opt.width, opt.height, timer_a);
      const io::Image8 img_f = rf.read_color(), img_a = ra.read_color();
      const metrics::ImageError e = metrics::compare(img_f, img_a);
      texels_f.push_back(texels_of(f.info)), texels_a.push_back(texels_of(a.info));
      const scene::Camera camera = rf.scene().camera;
      io::ImageF surface = probe.render(camera, opt.width, opt.height);
      const glm::mat4 view_projection = metrics::camera_view_projection(camera, opt.width, opt.height);
      const metrics::FrameSample current{nullptr, &surface, view_projection};
      track(0, "adaptive", ra, a.info, current);
      track(1, "fixed-" + std::to_string(fixed.map.resolution_texels), rf, f.info, current);
      floor_renderer.scene().camera = camera;
      track(2, "floor (world-fixed map)", floor_renderer, floor_renderer.render(world_fixed, opt.width, opt.height), current);
      if (!baselines.empty()) {
        gl::PassTimer untimed(false);
        std::vector<io::Image8> images;
        for (auto& b : baselines) {
          b.renderer->scene().camera = rf.scene().camera;
          const Timed t = timed_render(*b.renderer, b.settings, opt.width, opt.height, untimed);
          b.ms.push_back(t.ms);
          b.texels.push_back(texels_of(t.info));
          b.allocated = static_cast<double>(t.info.atlas_width) * t.info.atlas_height;
          images.push_back(b.renderer->read_color());
          track(3 + images.size() - 1, b.name, *b.renderer, t.info, current);
        }
        const io::Image8& engine = images.back();
        for (std::size_t k = 0; k < baselines.size(); ++k) baselines[k].ssim_vs_engine.push_back(metrics::compare(engine, images[k]).ssim);
        ssim_f_engine.push_back(metrics::compare(engine, img_f).ssim);
        ssim_a_engine.push_back(metrics::compare(engine, img_a).ssim);
      }
      ms_f.push_back(f.ms), ms_a.push_back(a.ms);
      ssim.push_back(e.ssim), max_abs.push_back(e.max_abs), share.push_back(e.share_above_threshold);
      res_a.push_back(a.info.resolution_texels);
      const std::string cascades = cascade_resolutions(a.info);
      char row[256];
      std::snprintf(row, sizeof row, "%s,%d,%.4f,%.4f,%d,%d,%s,%.6f,%.6f,%.6f\n", name.c_str(), i, f.ms, a.ms,
                    f.info.resolution_texels, a.info.resolution_texels, cascades.c_str(), e.ssim, e.max_abs, e.share_above_threshold);
      csv += row;
      if (i == opt.frames / 2) shown_f = img_f, shown_a = img_a;
      last_a = a.info;
      surface_previous = std::move(surface);
      view_projection_previous = view_projection;
    }
    std::fprintf(stderr, "\r%60s\r", "");
    timer_f.poll(true);
    timer_a.poll(true);
    io::write_png(out.path() / (name + "-fixed-vs-adaptive.png"), side_by_side(shown_f, shown_a));

    const Spread sf = spread(ms_f), sa = spread(ms_a), sr = spread(res_a);
    const double speedup = sf.median / std::max(sa.median, 1e-9);
    const double min_ssim = *std::min_element(ssim.begin(), ssim.end());
    const double worst_diff = *std::max_element(max_abs.begin(), max_abs.end());
    const double worst_share = *std::max_element(share.begin(), share.end());
    double mean_ssim = 0;
    for (double v : ssim) mean_ssim += v / static_cast<double>(ssim.size());
    nlohmann::json t;
    t["technique"] = name;
    t["settings_fixed"] = shadows::to_json(fixed);
    t["settings_adaptive"] = shadows::to_json(adapt);
    t["calibration"] = apps::calibration_json(opt.calibration, adapt);
    t["calibration"]["bound"] = opt.ci_upper ? "ci95_hi" : "c";
    t["fixed"] = {{"resolution_texels", fixed.map.resolution_texels}, {"frame_ms", to_json(sf)}, {"passes", io::to_json(timer_f.stats())}};
    t["adaptive"] = {{"resolution_texels", to_json(sr)},
                     {"storage", last_a.storage},
                     {"resolution_source", last_a.resolution_source},
                     {"frame_ms", to_json(sa)},
                     {"passes", io::to_json(timer_a.stats())}};
    if (last_a.pcss_requirement.valid)
      t["adaptive"]["pcss_requirement"] = {{"clamped_fraction", last_a.pcss_requirement.clamped_fraction},
                                           {"above_max_fraction", last_a.pcss_requirement.above_max_fraction}};
    t["speedup_median"] = speedup;
    t["image"] = {{"ssim_min", min_ssim}, {"ssim_mean", mean_ssim}, {"max_abs_max", worst_diff}, {"share_above_1_255_max", worst_share}};
    for (const Temporal& tm : temporal) {
      double mean = 0, changed = 0;
      for (double v : tm.mean_abs) mean += v / static_cast<double>(tm.mean_abs.size());
      for (double v : tm.share_changed) changed += v / static_cast<double>(tm.share_changed.size());
      t["flicker"].push_back({{"configuration", tm.name},
                              {"mean_abs_mean", tm.mean_abs.empty() ? 0.0 : mean},
                              {"share_changed_mean", tm.share_changed.empty() ? 0.0 : changed},
                              {"mean_abs_per_frame", tm.mean_abs},
                              {"resolution_changes", tm.resolution_changes}});
    }
    t["fixed"]["texels_rendered"] = to_json(spread(texels_f));
    t["adaptive"]["texels_rendered"] = to_json(spread(texels_a));
    if (!baselines.empty()) {
      const Baseline& engine = baselines.back();
      const double engine_median = spread(engine.ms).median;
      t["engine_baseline"] = engine.name;
      t["speedup_vs_engine_median"] = engine_median / std::max(sa.median, 1e-9);
      t["fixed"]["ssim_vs_engine_min"] = *std::min_element(ssim_f_engine.begin(), ssim_f_engine.end());
      t["adaptive"]["ssim_vs_engine_min"] = *std::min_element(ssim_a_engine.begin(), ssim_a_engine.end());
      for (const auto& b : baselines)
        t["baselines"].push_back({{"name", b.name},
                                  {"settings", shadows::to_json(b.settings)},
                                  {"frame_ms", to_json(spread(b.ms))},
                                  {"texels_rendered", to_json(spread(b.texels))},
                                  {"texels_allocated", b.allocated},
                                  {"ssim_vs_engine_min", *std::min_element(b.ssim_vs_engine.begin(), b.ssim_vs_engine.end())}});
    }
    report["techniques"].push_back(t);

    char range[64];
    std::snprintf(range, sizeof range, "%.0f..%.0f", sr.min, sr.max);
    std::printf("%-6s %8.1f [%6.1f, %6.1f] %8.1f [%6.1f, %6.1f] %7.2fx %14s %8.4f %9.4f %9.4f\n", name.c_str(), sf.median, sf.p10,
                sf.p90, sa.median, sa.p10, sa.p90, speedup, range, min_ssim, worst_diff, worst_share);
    if (!baselines.empty()) {
      // Every configuration against the engine baseline (the last row), texels per frame (median).
      const double engine_median = spread(baselines.back().ms).median;
      auto row = [&](const std::string& config, const Spread& ms, double texels, double allocated, double ssim_engine) {
        std::printf("  %-22s %8.1f [%6.1f, %6.1f] %6.2fx %12.2f %12.2f %10.4f\n", config.c_str(), ms.median, ms.p10, ms.p90,
                    engine_median / std::max(ms.median, 1e-9), texels / 1e6, allocated / 1e6, ssim_engine);
      };
      std::printf("  %-22s %24s %7s %12s %12s %10s\n", "configuration", "frame ms", "vs eng.", "Mtexels drawn", "allocated",
                  "SSIM vs eng.");
      row("adaptive", sa, spread(texels_a).median, static_cast<double>(last_a.atlas_width) * last_a.atlas_height,
          t["adaptive"]["ssim_vs_engine_min"].get<double>());
      row("fixed-" + std::to_string(fixed.map.resolution_texels), sf, spread(texels_f).median,
          static_cast<double>(fixed.map.resolution_texels) * fixed.map.resolution_texels, t["fixed"]["ssim_vs_engine_min"].get<double>());
      for (const auto& b : baselines)
        row(b.name, spread(b.ms), spread(b.texels).median, b.allocated,
            *std::min_element(b.ssim_vs_engine.begin(), b.ssim_vs_engine.end()));
    }
    if (opt.frames > 1) {
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
  gl::WindowContext window(opt.width, opt.height, "Penumbra demo - " + scene.name);
  shadows::Renderer renderer;
  renderer.set_scene(scene);
  settings.adaptive.enabled = true;
  apps::CalibrationFollower follower;  // the panel's technique switch picks that technique's c
  gl::PassTimer timer(!window.info().software);
  bool show_map = true, show_cascades = false, animate = true;
  int frame = 0, path_i = 0;
  double fps = 0, last = now_ms();
  while (!window.should_close()) {
    window.begin_frame();
    if (animate) renderer.scene().camera = path_camera(scene.camera, path_i++ % (4 * opt.frames), 4 * opt.frames);
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
    ImGui::Text("c = %.3f texels: %s", settings.adaptive.c, opt.calibration.source_of_c(settings).c_str());
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
    window.render_ui();
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
  app.add_option("--frames", opt.frames, "camera-path frames per technique")->check(CLI::Range(1, 100000));
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
  app.add_option("--screenshot", opt.screenshot, "windowed: write the window (with the panel) to this PNG, then exit");
  app.add_option("--screenshot-frames", opt.screenshot_frames, "windowed: frames before --screenshot")->check(CLI::Range(1, 100000));
  apps::add_settings_options(app, base);
  if (const auto status = cli::parse(app, argc, argv, "penumbra-demo")) return *status;
  try {
    for (const auto& t : opt.techniques) shadows::technique_from_string(t);
    apps::apply_calibration(app, opt.calibration, base, opt.ci_upper);
    if (headless) return run_headless(opt, base);
#if PENUMBRA_DEMO_GUI
    return run_windowed(opt, base);
#else
    return cli::fail("penumbra-demo", "built without GUI support; use --headless", cli::kExitUsage);
#endif
  } catch (const std::exception& e) {
    return cli::fail("penumbra-demo", e.what());
  }
}
