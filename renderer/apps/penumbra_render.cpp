// penumbra-render: scene + technique + parameters + shadow-map resolution → lit image (PNG),
// visibility buffer (EXR) and report.json with per-pass times. Runs headless (EGL).
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <new>
#include <set>
#include <string>
#include <unistd.h>
#include <vector>

#include "gl/context.h"
#include "cli/main.h"
#include "io/atomic_file.h"
#include "json/json_input.h"
#include "gl/timer.h"
#include "io/image_io.h"
#include "io/report.h"
#include "io/staged_dir.h"
#include "scene/scene.h"
#include "shadows/frame_plan.h"
#include "shadows/frame_report.h"
#include "shadows/renderer.h"
#include "shadows/settings.h"
#include "shadows/technique.h"
#include "shadows/virtual_shadow_map.h"
#include "apps/virtual_debug.h"
#include "cli_options.h"

namespace fs = std::filesystem;
using namespace penumbra;

namespace {

struct Variant {
  std::string name;
  shadows::ShadowSettings settings;
};

std::string fmt_ms(double ms) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%9.2f", ms);
  return buf;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Render a scene with a shadow technique; writes lit.png, visibility.exr and report.json."};
  cli::describe_tool(app, "penumbra-render", "renderer.md");
  app.option_defaults()->always_capture_default();
  std::string scene_arg = "demo";
  std::string technique_arg = "pcf";
  std::vector<int> resolutions{2048};
  std::string output;
  int width = 1280, height = 720, frames = 5, warmup = 1;
  float light_size = -1;
  int path_frame = -1;
  bool virtual_debug = false;
  shadows::ShadowSettings base;
  apps::CalibrationOption calibration;

  app.add_option("--scene", scene_arg, "built-in scene name or scene file (.json)");
  std::vector<std::string> technique_choices(shadows::technique_names().begin(), shadows::technique_names().end());
  technique_choices.push_back("all");
  std::string technique_help;
  for (const auto& t : technique_choices) technique_help += (technique_help.empty() ? "" : ", ") + t;
  app.add_option("--technique", technique_arg, technique_help + " (all: every technique and PCF kernel)")
      ->check(CLI::IsMember(technique_choices));
  cli::add_list_option(app, "--resolution", resolutions, "shadow-map texels per side; a comma list renders each", cli::integers_in(1, 65536));
  app.add_option("--width", width, "image width in pixels")->check(CLI::Range(1, 16384));
  app.add_option("--height", height, "image height in pixels")->check(CLI::Range(1, 16384));
  app.add_option("--frames", frames, "timed frames per render (median reported)")->check(CLI::Range(1, 1000));
  app.add_option("--warmup", warmup, "untimed frames before timing")->check(CLI::Range(0, 100));
  apps::add_light_size_option(app, light_size);
  app.add_option("--path-frame", path_frame, "view from this frame of the scene's camera path instead of its camera")
      ->check(CLI::Range(0, 10'000'000));
  app.add_flag("--virtual-debug", virtual_debug,
               "also write the sun's virtual shadow map for this view: virtual-levels.png (the level each pixel samples, by the "
               "rule and by the footprint) and virtual-pool.png (the page pool: drawn for this view green, kept from the previous "
               "path frame blue); pcf or vsm with a world radius, or pcss, the pixel floor --map.virtual_min_texel_px");
  app.add_option("-o,--output", output, "output directory (replaced as a whole when the run succeeds)")
      ->required()
      ->check(cli::path_given());
  apps::add_calibration_option(app, calibration);
  apps::add_settings_options(app, base);

  if (const auto status = cli::parse(app, argc, argv, "penumbra-render")) return *status;

  std::string scene_size;  // "N objects (M distinct meshes)" once loaded: what an out-of-memory line names
  try {
    apps::apply_calibration(app, calibration, base);
    if (apps::setting_stands_for(app, "--map.resolution_texels", "--resolution")) resolutions = {base.map.resolution_texels};
    if (technique_arg != "all")
      apps::refuse_unused_technique_options(app, {shadows::technique_from_string(technique_arg)}, "--technique " + technique_arg);
    scene::Scene scene = scene::load_scene(scene_arg);
    {
      std::set<const scene::MeshData*> meshes;
      for (const scene::Object& o : scene.objects) meshes.insert(o.mesh.get());
      scene_size = std::to_string(scene.objects.size()) + " objects (" + std::to_string(meshes.size()) + " distinct meshes)";
    }
    apps::override_light_size(light_size, scene.light);
    if (virtual_debug && scene.light.type != scene::Light::Type::directional)
      throw cli::UsageError("--virtual-debug: the virtual shadow map is the sun's; scene " + scene.name + " has a spot light");
    scene::Camera previous_camera;
    const bool has_previous = path_frame > 0 && !scene.camera_path.empty();
    if (has_previous) previous_camera = scene.camera_path.at(scene.camera, path_frame - 1);
    if (path_frame >= 0) {
      if (scene.camera_path.empty()) throw std::runtime_error("--path-frame: scene '" + scene.name + "' has no camera path");
      if (path_frame >= scene.camera_path.frames())
        throw std::runtime_error("--path-frame: " + std::to_string(path_frame) + " is beyond the path's last frame " +
                                 std::to_string(scene.camera_path.frames() - 1));
      scene.camera = scene.camera_path.at(scene.camera, path_frame);
      scene = scene::posed_at(scene, path_frame);  // moving objects where they are at that frame
    }

    // One variant per technique; a technique with a variant setting (PCF's kernel) gets one per
    // choice under `all`, named "<technique>-<choice>" either way.
    std::vector<Variant> variants;
    auto add_variants = [&](shadows::Technique t, bool every_choice) {
      Variant v{std::string(shadows::to_string(t)), base};
      v.settings.technique = t;
      if (shadows::variant_choices(t).empty()) {
        variants.push_back(v);
        return;
      }
      for (const std::string& choice : every_choice ? shadows::variant_choices(t) : std::vector{shadows::variant_choice(v.settings)}) {
        Variant c = v;
        c.name += "-" + choice;
        shadows::set_variant_choice(c.settings, choice);
        variants.push_back(c);
      }
    };
    if (technique_arg == "all") {
      for (auto name : shadows::technique_names()) add_variants(shadows::technique_from_string(name), true);
    } else {
      add_variants(shadows::technique_from_string(technique_arg), false);
    }
    for (auto& v : variants) apps::apply_calibration_for(calibration, v.settings);  // each technique's own c
    const apps::VirtualMarking virtual_mark = apps::virtual_marking(variants.front().settings, scene.light);
    if (virtual_debug && !virtual_mark.problem.empty()) throw cli::UsageError("--virtual-debug: " + virtual_mark.problem);
    for (const auto& v : variants)  // before anything renders: the plan would refuse it at the first frame
      if (v.settings.map.virtual_pages != shadows::VirtualPages::off)
        if (const std::string why = shadows::virtual_pages_refusal(v.settings, scene); !why.empty())
          throw cli::UsageError("--map.virtual_pages: " + why);
    {
      std::vector<shadows::ShadowSettings> rendered;
      for (const auto& v : variants) rendered.push_back(v.settings);
      if (virtual_debug) {  // the debug views mark the sun's pages whatever the frame draws: they read its floor
        shadows::ShadowSettings pages = variants.front().settings;
        if (pages.map.virtual_pages == shadows::VirtualPages::off) pages.map.virtual_pages = shadows::VirtualPages::rule;
        rendered.push_back(pages);
      }
      apps::refuse_unread_settings(app, rendered, {{"--resolution", "map.resolution_texels"}});
    }

    gl::HeadlessContext context;
    const auto& ctx = context.info();
    for (int r : resolutions)
      if (r > ctx.max_texture_size)
        throw std::runtime_error("--resolution " + std::to_string(r) + " exceeds this device's GL_MAX_TEXTURE_SIZE " +
                                 std::to_string(ctx.max_texture_size));

    io::StagedDirectory out(output, "report.json");  // refuses a directory that is not ours
    const fs::path& staging = out.path();

    shadows::Renderer renderer;
    renderer.set_count_work(true);  // report.json's work: what each pass gave the GPU to do
    renderer.set_scene(scene);
    nlohmann::json summary;
    summary["device"] = nlohmann::json(ctx);
    summary["scene"] = scene.name;
    summary["image_px"] = {width, height};
    summary["frames"] = frames;
    // The c of the technique rendered (with several, each render's report holds its own).
    summary["calibration"] = apps::calibration_json(calibration, variants.size() == 1 ? variants.front().settings : base);
    summary["renders"] = nlohmann::json::array();
    std::vector<io::Image8> montage_images;
    std::vector<std::string> labels;

    std::cout << "scene " << scene.name << ", " << width << "x" << height << ", " << ctx.renderer << " ("
              << ctx.platform << "); times: median of " << frames << " frames, ms, "
              << (ctx.software ? "wall clock around glFinish (wall_finish)" : "GPU timer queries (gpu_timer)")
              << "\n";
    // The c of each technique the adaptive rule sizes, where it came from and what the fitter
    // flagged, before anything is rendered with it.
    std::vector<std::string> c_lines;
    for (const auto& v : variants)
      if (v.settings.adaptive.enabled)
        if (const std::string line = apps::calibration_line(calibration, v.settings);
            std::find(c_lines.begin(), c_lines.end(), line) == c_lines.end()) {
          c_lines.push_back(line);
          std::cout << line << "\n";
        }
    // screen: the G-buffer and post passes of the screen-space techniques; shading: the camera's
    // depth prepass (map.depth_prepass) and its shading.
    std::printf("%-12s %6s %10s %10s %10s %10s %10s\n", "technique", "res", "shadow_map", "vsm_blur", "screen", "shading", "total");
    const bool progress = ::isatty(STDERR_FILENO) != 0;  // a progress line only where it can be redrawn
    const int total_runs = static_cast<int>(variants.size() * resolutions.size());
    int run = 0;
    for (int res : resolutions) {
      for (auto& v : variants) {
        ++run;
        if (progress) {
          std::fprintf(stderr, "[%d/%d] %s at %d^2...\r", run, total_runs, v.name.c_str(), res);
          std::fflush(stderr);
        }
        v.settings.map.resolution_texels = res;
        gl::PassTimer timer(!ctx.software);
        // A frame whose page pool missed pages says so once per render (its pixels read a coarser level).
        std::string missing;
        const auto warn = [&](const shadows::FrameInfo& frame) {
          if (!frame.virtual_map || !missing.empty()) return;
          missing = shadows::missing_pages_warning(frame.virtual_map->pages, frame.virtual_map->pool_pages_per_side);
          if (!missing.empty()) std::fprintf(stderr, "penumbra-render: %s: %s\n", v.name.c_str(), missing.c_str());
        };
        for (int i = 0; i < warmup; ++i) warn(renderer.render(v.settings, width, height));
        shadows::FrameInfo info;
        for (int i = 0; i < frames; ++i) warn(info = renderer.render(v.settings, width, height, &timer));
        timer.poll(true);
        const auto stats = timer.stats();

        const std::string dir_name = resolutions.size() > 1 ? v.name + "-" + std::to_string(res) : v.name;
        const fs::path dir = staging / dir_name;
        fs::create_directories(dir);
        io::Image8 color = renderer.read_color();
        io::write_png(dir / "lit.png", color);
        io::write_exr(dir / "visibility.exr", renderer.read_visibility());
        nlohmann::json report = shadows::frame_report(info, v.settings, stats);
        report["scene"] = scene.name;
        report["device"] = nlohmann::json(ctx);
        report["calibration"] = apps::calibration_json(calibration, v.settings);
        io::write_file_atomic(dir / "report.json", json_input::dump(report, 2) + "\n");

        const gl::TimingMethod shown = ctx.software ? gl::TimingMethod::wall_finish : gl::TimingMethod::gpu_timer;
        double shadow_map = 0, vsm_blur = 0, screen = 0, shading = 0, total = 0;
        for (const auto& st : stats) {
          if (st.method != shown) continue;
          total += st.median_ms;
          if (st.pass == "shadow_map") shadow_map = st.median_ms;
          else if (st.pass.rfind("virtual_", 0) == 0) shadow_map += st.median_ms;  // the virtual map's steps (passes.cpp)
          else if (st.pass == "vsm_blur") vsm_blur = st.median_ms;
          else if (st.pass == "shading" || st.pass == "depth_prepass") shading += st.median_ms;
          else screen += st.median_ms;
        }
        const bool screen_space = shadows::technique_entry(v.settings.technique).screen_space();
        // The resolution used: the rule's with adaptive.enabled, one entry per cascade.
        std::string used;
        for (const auto& c : info.cascades) used += (used.empty() ? "" : "+") + std::to_string(c.resolution_texels);
        if (info.virtual_map) used = std::to_string(info.virtual_map->pages.requested) + "p";  // pages, not a map
        std::printf("%-12s %6s %s %s %s %s %s\n", v.name.c_str(), used.c_str(), fmt_ms(shadow_map).c_str(),
                    std::find(info.passes.begin(), info.passes.end(), "vsm_blur") != info.passes.end()
                        ? fmt_ms(vsm_blur).c_str()
                        : "        -",
                    screen_space ? fmt_ms(screen).c_str() : "        -", fmt_ms(shading).c_str(), fmt_ms(total).c_str());
        std::fflush(stdout);
        summary["renders"].push_back({{"name", dir_name}, {"technique", v.name}, {"resolution_texels", res},
                                      {"resolution_used_texels", info.resolution_texels}, {"cascades", info.cascades.size()},
                                      {"timing_method", gl::to_string(shown)}, {"total_ms", total},
                                      {"timings", report["timings"]}});
        if (resolutions.size() == 1 || res == resolutions.back()) {
          montage_images.push_back(std::move(color));
          labels.push_back(v.name);
        }
      }
    }
    if (progress) std::fprintf(stderr, "%*s\r", 60, "");
    if (virtual_debug) {
      const nlohmann::json v = apps::write_virtual_debug(scene, has_previous ? &previous_camera : nullptr, scene.camera, width, height,
                                                         virtual_mark, staging);
      summary["virtual_debug"] = v;
      std::printf("virtual shadow map: %d pages by the rule, %d by the footprint; %d drawn, %d kept from the previous frame "
                  "(virtual-levels.png, virtual-pool.png)\n",
                  v.at("pages_rule").get<int>(), v.at("pages_footprint").get<int>(), v.at("drawn").get<int>(), v.at("cached").get<int>());
    }
    if (montage_images.size() > 1) {
      io::write_png(staging / "montage.png", io::montage(montage_images, labels, 3, 640));
    }
    io::write_file_atomic(staging / "report.json", json_input::dump(summary, 2) + "\n");
    out.commit();
    std::cout << "wrote " << out.target().string() << "/\n";
    return 0;
  } catch (const std::bad_alloc&) {
    // Was "std::bad_alloc" after 35 s, naming nothing.
    return cli::fail("penumbra-render", "out of memory" + (scene_size.empty() ? std::string(" reading the scene")
                                                                              : " rendering the scene's " + scene_size) +
                                            "; nothing written (fewer or shared meshes, a smaller --resolution or image)");
  } catch (const std::exception& e) {
    return cli::fail("penumbra-render", e);
  }
}
