// penumbra-demo: adaptive shadow-map resolution against the engine's best at equal error.
//
//   --headless  for each technique, walks the scene's camera path (the outdoor town: --path short
//               or full; other scenes: an orbit) and renders every frame in each configuration
//               (apps/demo/configurations.h): the adaptive rule res = c / r_uv (rule-sized
//               cascades, count chosen), a fixed map (default 2048²), and the engine family (a
//               few single maps and cascades; --sweep: 1024²-8192² maps, 2-4 cascades of
//               1024²-4096²). The walk (apps/demo/measurement.h) measures per configuration
//               frame time, texels drawn and allocated, triangles, SSIM against the engine
//               baseline, error against a reference of the technique (metrics/ground_truth.h)
//               and flicker from frame to frame (metrics/temporal.h), and at the reference
//               frames the perceived difference of the lit frames (apps/demo/perceptual.h:
//               LDR-FLIP and the frame observer at the study display's pixels per degree). The
//               report (apps/demo/report.h) reads the adaptive rule against the engine family's
//               Pareto front at equal perceived difference (FLIP), then at equal error (RMSE)
//               (speedup and memory ratio with intervals), names the cheapest configuration the
//               observer cannot tell from the reference, then the single-map comparison and the
//               tables; writes report.json, frames.csv, side-by-side images, crops, FLIP montages
//               and the plots (scripts/plot_demo.py) into -o DIR.
//   windowed    the same renderer in a window with a panel: technique and filter, fitting,
//               adaptive on/off, c and its calibration file, the resolution in use per cascade,
//               shadow-map and cascade overlays, fps and per-pass times.
#include <epoxy/gl.h>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "adaptive/calibration.h"
#include "adaptive/resolution_rule.h"
#include "adaptive/virtual_pages.h"
#include "apps/cli_options.h"
#include "apps/demo/configurations.h"
#include "apps/demo/measurement.h"
#include "apps/demo/path.h"
#include "apps/demo/report.h"
#include "apps/run_python.h"
#include "apps/virtual_debug.h"
#include "cli/list_option.h"
#include "cli/main.h"
#include "cli/progress_bar.h"
#include "gl/context.h"
#include "gl/timer.h"
#include "io/atomic_file.h"
#include "io/image_io.h"
#include "io/report.h"
#include "io/safe_path.h"
#include "io/staged_dir.h"
#include "json/json_input.h"
#include "metrics/frame_observer.h"
#include "scene/scene.h"
#include "shard/shard.h"
#include "apps/display_geometry.h"
#include "shadows/frame_report.h"
#include "shadows/renderer.h"
#include "shadows/virtual_shadow_map.h"
#include "stats/summary.h"
#include "tool/tool.h"

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
// kernels (exact, deterministic: the two images differ only by the map's resolution), and the
// rule as a careful engine applies it: no texel finer than a pixel footprint at its cascade's
// near end (adaptive.min_texel_px; 0 gives the rule alone). The adaptive atlas is sized to each
// frame's maps (adaptive.storage = realloc), so that the memory compared with the engine's is what
// the rule asks for, not the maximum a sub-rectangle atlas keeps allocated.
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
  s.adaptive.storage = shadows::Storage::realloc;
  return s;
}

double now_ms() {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// Fixed | adaptive | |difference| × 10 (grey), side by side, each under a dark band with its
// label: what it is, its maps' resolution, the technique and the frame (io::montage draws the
// text where the image backend has a font; the minimal backend leaves the bands blank).
io::Image8 side_by_side(const io::Image8& a, const io::Image8& b, const std::vector<std::string>& labels) {
  // The montage draws 24 px text from row 30 of a tile: a narrow image is scaled up to 720 px so
  // that its label fits, and its band is 40 rows at that scale.
  const int tile_width = std::max(a.width, 720);
  const int band = (40 * a.width + tile_width - 1) / tile_width;
  const auto banded = [&](auto pixel) {
    io::Image8 out{a.width, a.height + band, 4, std::vector<std::uint8_t>(static_cast<std::size_t>(a.width) * (a.height + band) * 4, 32)};
    for (int y = 0; y < a.height; ++y)
      for (int x = 0; x < a.width; ++x)
        for (int c = 0; c < 4; ++c) out.at(x, band + y, c) = pixel(x, y, c);
    return out;
  };
  const auto diff = [&](int x, int y, int c) {
    int d = 0;
    for (int k = 0; k < 3; ++k) d = std::max(d, std::abs(int(a.at(x, y, k)) - int(b.at(x, y, k))));
    return c == 3 ? std::uint8_t{255} : static_cast<std::uint8_t>(std::min(255, d * 10));
  };
  const std::vector<io::Image8> tiles = {banded([&](int x, int y, int c) { return a.at(x, y, c); }),
                                         banded([&](int x, int y, int c) { return b.at(x, y, c); }), banded(diff)};
  return io::montage(tiles, labels, 3, tile_width);
}

// The side-by-side's labels: the fixed map, the adaptive maps at the frame shown, the difference.
// Sizes as "2048x2048" (OpenImageIO's text draws "²" as a full-size 2).
std::vector<std::string> side_by_side_labels(const demo::TechniqueRun& run, const demo::PathPlan& plan) {
  const demo::Series& adaptive = run.series[run.adaptive];
  const std::string at = run.technique + ", path frame " + std::to_string(plan.frames[run.shown_at].frame);
  const int fixed = run.series[run.fixed].config.settings.map.resolution_texels;
  const std::string sides = run.shown_at < adaptive.resolution.size() ? adaptive.resolution[run.shown_at] : "?";  // "928" or "1024+512"
  const auto cascades = std::count(sides.begin(), sides.end(), '+') + 1;
  const std::string maps =
      cascades == 1 ? "one " + sides + "x" + sides + " map" : std::to_string(cascades) + " cascades, " + sides + " a side,";
  return {"fixed: one " + std::to_string(fixed) + "x" + std::to_string(fixed) + " map (" + at + ")", "adaptive: " + maps + " by the rule",
          "|fixed - adaptive| x 10"};
}

struct Options {
  std::string scene = "outdoor";
  float light_size = -1;       // >= 0: overrides the scene light's size
  std::vector<std::string> techniques = {"pcf", "pcss"};
  std::string path = "short";  // scenes with a camera path: "short" or "full"
  int frames = 12;
  int width = 960, height = 540;
  int repeats = 1;             // renders per frame and configuration (the frame's time: their median)
  apps::CalibrationOption calibration;
  bool ci_upper = false;
  std::string output = "out/demo";
  std::string python = "/usr/bin/python3";
  std::string plot_script = tool::script_file("plot_demo.py").string();
  bool plot = true;
  bool baselines = true;       // the engine family (one map of twice the fixed size, cascades)
  bool sweep = false;          // the whole engine family instead of a few points
  bool auto_cascades = true;   // adaptive: as many cascades as the rule needs (unless --map.cascades is given)
  bool virtual_pages = true;   // the sun's virtual map beside the maps (a directional light; box PCF in world units)
  bool reference = true;       // error against a reference of the technique at the reference frames
  bool flip = true;            // and the perceptual difference of the lit frames (apps/demo/perceptual.h)
  std::string display = tool::data_file("studies/default.json").string();  // its viewing geometry
  // Area-light reference: shadow rays per pixel, ray-traced (256 against 1024 differ by RMSE
  // 0.005 on the street: AreaLightSlow.OutdoorRayTracedReference...); in a build without Embree,
  // point-light maps averaged (64: 64 against 256 differ by 0.015, AreaLightSlow.OutdoorReference...).
  int reference_samples = PENUMBRA_HAS_RAY_TRACING ? 256 : 64;
  std::string screenshot;      // windowed: write the window here after screenshot_frames frames, then exit
  int screenshot_frames = 10;
};

// The unit a shard of the headless run takes is a technique (docs/cluster.md). A technique's
// configurations walk the path in lockstep, and what the run says about them pairs them frame by
// frame: SSIM against the engine baseline, the fixed map against the adaptive one, the crops where
// they differ, the FLIP montage, the front at equal error read across their frame times. Split
// finer, a part would carry every series for the merge to redo that, over times measured in
// different processes. Techniques share nothing that depends on one of them (the walk keeps the
// scene, the surface probe and the thin casters' masks, which read no technique), so shard I of N
// walks the techniques of --techniques whose position is I modulo N, and its part carries what
// the run prints and writes for them.
constexpr std::string_view kPartKind = "penumbra-demo part";

struct Sharding {
  std::optional<shard::Shard> shard;
  std::string part;               // --part FILE
  std::vector<std::string> args;  // the settings: the command line less --shard and --part
};

// One technique's share of what the headless run prints and writes: what a shard's part carries
// and a merge puts back in the technique's place.
struct TechniqueOutput {
  std::size_t index = 0;  // in --techniques
  std::string name;
  nlohmann::json entry;  // report.json's techniques[] entry
  std::string csv;       // its frames.csv rows
  bool flip_available = false;  // its headline reads FLIP (the run's first line says "perceived difference" if any does)
  std::array<std::vector<std::string>, 3> headlines;  // per demo::ErrorMeasure: the adaptive rule's line, then the virtual maps'
  std::string unseen, calibration, single_map_row, tables;
  std::vector<std::pair<std::string, std::string>> images;  // file in -o DIR, PNG bytes (a shard's and a merge's; the run writes its own)
};

constexpr std::array<std::string_view, 3> kMeasureKeys = {"flip", "flip_ray_traced", "rmse"};  // demo::ErrorMeasure's order

// What the run prints and writes beside the techniques, the same in every shard of one command.
struct RunHead {
  nlohmann::json report;       // report.json less "techniques"
  std::string scene_line;      // "\ndemo at 64x36 on llvmpipe ...; engine family sweep; calibration ...\n"
  std::string settings_lines;  // adaptive:, frame time:, the single-map table's header
};

// A part carries PNG files as text.
constexpr std::string_view kBase64Digits = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
std::string base64(std::string_view bytes) {
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  for (std::size_t i = 0; i < bytes.size(); i += 3) {
    const std::size_t n = std::min<std::size_t>(3, bytes.size() - i);  // bytes in this group
    std::uint32_t v = 0;
    for (std::size_t k = 0; k < 3; ++k) v = (v << 8) | (k < n ? static_cast<unsigned char>(bytes[i + k]) : 0u);
    for (std::size_t k = 0; k < 4; ++k) out += k <= n ? kBase64Digits[(v >> (18 - 6 * k)) & 63] : '=';
  }
  return out;
}
// Throws std::runtime_error for text that is not base64.
std::string unbase64(std::string_view text) {
  if (text.size() % 4 != 0) throw std::runtime_error("not base64 (" + std::to_string(text.size()) + " characters, not a multiple of 4)");
  std::string out;
  out.reserve(text.size() / 4 * 3);
  for (std::size_t i = 0; i < text.size(); i += 4) {
    std::uint32_t v = 0;
    int pad = 0;
    for (std::size_t k = 0; k < 4; ++k) {
      const char c = text[i + k];
      const std::size_t d = kBase64Digits.find(c);
      if (c == '=' && i + 4 == text.size() && k >= 2 && (k == 3 || text[i + 3] == '=')) {
        ++pad;
      } else if (d == std::string_view::npos || pad > 0) {
        throw std::runtime_error("not base64 (character " + std::to_string(i + k) + ")");
      }
      v = (v << 6) | static_cast<std::uint32_t>(d == std::string_view::npos ? 0 : d);
    }
    out += static_cast<char>((v >> 16) & 255);
    if (pad < 2) out += static_cast<char>((v >> 8) & 255);
    if (pad < 1) out += static_cast<char>(v & 255);
  }
  return out;
}

// A PNG's bytes as io::write_png writes them (a merge writes these bytes: its images are the
// unsharded run's), by way of a scratch folder of this process's own.
class PngBytes {
 public:
  PngBytes() {
    std::string dir = (fs::temp_directory_path() / "penumbra-demo-part-XXXXXX").string();
    if (!::mkdtemp(dir.data())) throw std::runtime_error(dir + ": cannot create the images' scratch folder");
    dir_ = dir;
  }
  ~PngBytes() {
    std::error_code ignored;
    fs::remove_all(dir_, ignored);
  }
  PngBytes(const PngBytes&) = delete;
  PngBytes& operator=(const PngBytes&) = delete;
  std::string operator()(const io::Image8& image) const {
    const fs::path file = dir_ / "image.png";
    io::write_png(file, image);
    return io::read_file(file, std::size_t{1} << 30);
  }

 private:
  fs::path dir_;
};

nlohmann::json output_json(const TechniqueOutput& o) {
  nlohmann::json j = {{"index", o.index},       {"technique", o.name},        {"entry", o.entry},   {"csv", o.csv},
                      {"flip_available", o.flip_available}, {"unseen", o.unseen}, {"calibration", o.calibration},
                      {"single_map_row", o.single_map_row}, {"tables", o.tables}};
  for (std::size_t m = 0; m < kMeasureKeys.size(); ++m) j["headlines"][kMeasureKeys[m]] = o.headlines[m];
  j["images"] = nlohmann::json::array();
  for (const auto& [file, bytes] : o.images) j["images"].push_back({{"file", file}, {"png_base64", base64(bytes)}});
  return j;
}

// Throws std::runtime_error naming the field at fault.
TechniqueOutput output_of_json(const nlohmann::json& j) {
  TechniqueOutput o;
  const auto text = [&](const char* key) {
    if (!j.contains(key) || !j[key].is_string()) throw std::runtime_error(std::string(key) + ": missing or not text");
    return j[key].get<std::string>();
  };
  if (!j.contains("index") || !j["index"].is_number_unsigned()) throw std::runtime_error("index: missing or not a whole number");
  o.index = j["index"].get<std::size_t>();
  o.name = text("technique"), o.csv = text("csv"), o.unseen = text("unseen"), o.calibration = text("calibration");
  o.single_map_row = text("single_map_row"), o.tables = text("tables");
  if (!j.contains("entry") || !j["entry"].is_object()) throw std::runtime_error("entry: missing or not an object");
  o.entry = j["entry"];
  if (!j.contains("flip_available") || !j["flip_available"].is_boolean()) throw std::runtime_error("flip_available: missing or not true/false");
  o.flip_available = j["flip_available"].get<bool>();
  for (std::size_t m = 0; m < kMeasureKeys.size(); ++m) {
    const std::string key(kMeasureKeys[m]);
    if (!j.contains("headlines") || !j["headlines"].is_object() || !j["headlines"].contains(key) || !j["headlines"][key].is_array())
      throw std::runtime_error("headlines." + key + ": missing or not a list");
    for (const auto& line : j["headlines"][key]) {
      if (!line.is_string()) throw std::runtime_error("headlines." + key + ": not a list of lines");
      o.headlines[m].push_back(line.get<std::string>());
    }
  }
  if (!j.contains("images") || !j["images"].is_array()) throw std::runtime_error("images: missing or not a list");
  for (const auto& image : j["images"]) {
    if (!image.is_object() || !image.contains("file") || !image["file"].is_string() || !image.contains("png_base64") ||
        !image["png_base64"].is_string())
      throw std::runtime_error("images: an entry without file and png_base64");
    const std::string file = image["file"].get<std::string>();
    // The name goes into -o DIR: a plain file name of this technique's, nothing else.
    if (file.empty() || file.find('/') != std::string::npos || file.rfind(o.name + "-", 0) != 0 || !file.ends_with(".png"))
      throw std::runtime_error("images: '" + json_input::printable(file, 80) + "' is not one of " + o.name + "'s images");
    try {
      o.images.emplace_back(file, unbase64(image["png_base64"].get<std::string>()));
    } catch (const std::exception& e) {
      throw std::runtime_error("images: " + file + ": " + e.what());
    }
  }
  return o;
}

nlohmann::json head_json(const RunHead& h) {
  return {{"report", h.report}, {"scene_line", h.scene_line}, {"settings_lines", h.settings_lines}};
}

// The adoption question first (the adaptive rule against the engine's Pareto front at equal
// perceived difference, where it was measured, then at equal RMSE), the single-map comparison and
// the tables below it.
void print_results(const RunHead& head, const std::vector<TechniqueOutput>& techniques) {
  const bool perceived = std::any_of(techniques.begin(), techniques.end(), [](const TechniqueOutput& t) { return t.flip_available; });
  std::printf("penumbra-demo: adaptive against the engine's Pareto front at equal %s to the reference (engine at equal error / "
              "adaptive, per frame along the path: median [95 %% bootstrap interval]; > 1 favours adaptive)\n",
              perceived ? "perceived difference (LDR-FLIP mean of the lit frames)" : "error");
  for (const demo::ErrorMeasure m : {demo::ErrorMeasure::flip, demo::ErrorMeasure::flip_ray_traced, demo::ErrorMeasure::rmse}) {
    if (m == demo::ErrorMeasure::rmse && perceived) {
      std::printf("the frame observer (metrics/frame_observer.h) on the lit frames against the reference (PCSS: converged PCSS) at the "
                  "technique's criterion F, every reference frame:\n");
      for (const TechniqueOutput& t : techniques) std::printf("%s\n", t.unseen.c_str());
      std::printf("at equal error (visibility RMSE against the reference):\n");
    }
    for (const TechniqueOutput& t : techniques)
      for (const std::string& line : t.headlines[static_cast<std::size_t>(m)]) std::printf("%s\n", line.c_str());
  }
  std::fputs(head.scene_line.c_str(), stdout);
  for (const TechniqueOutput& t : techniques) std::printf("%s\n", t.calibration.c_str());
  std::fputs(head.settings_lines.c_str(), stdout);
  for (const TechniqueOutput& t : techniques) std::fputs(t.single_map_row.c_str(), stdout);
  for (const TechniqueOutput& t : techniques) {
    std::printf("\n");
    std::fputs(t.tables.c_str(), stdout);
  }
  std::fflush(stdout);
}

constexpr const char* kFramesCsvHeader = "technique,configuration,path_frame,frame_ms,texels,cascades,ssim_vs_engine,flicker_mean_abs\n";

// What the unsharded run and the merge print and write into -o DIR (staged in `out`): the results,
// the images a part carried, frames.csv, report.json and the plots.
int write_results(const Options& opt, const RunHead& head, const std::vector<TechniqueOutput>& techniques, io::StagedDirectory& out) {
  print_results(head, techniques);
  nlohmann::json report = head.report;
  std::string csv = kFramesCsvHeader;
  for (const TechniqueOutput& t : techniques) {
    report["techniques"].push_back(t.entry);
    csv += t.csv;
    for (const auto& [file, bytes] : t.images) io::write_file_atomic(out.path() / file, bytes);
  }
  io::write_file_atomic(out.path() / "frames.csv", csv);
  io::write_file_atomic(out.path() / "report.json", json_input::dump(report, 2) + "\n");
  // A plot that fails does not cost the measurements (minutes of them with --sweep): they are
  // kept, and the error says how to draw them again.
  std::string plot_error;
  if (opt.plot) {
    try {
      apps::run_python_script(opt.python, opt.plot_script, {(out.path() / "report.json").string(), out.path().string()}, "the chart");
    } catch (const std::exception& e) {
      plot_error = e.what();
    }
  }
  out.commit();
  std::printf("wrote %s/\n", opt.output.c_str());
  if (!plot_error.empty()) {
    std::fprintf(stderr, "penumbra-demo: %s; the measurements are in %s/ (draw them again: %s %s %s/report.json %s)\n",
                 plot_error.c_str(), opt.output.c_str(), opt.python.c_str(), opt.plot_script.c_str(), opt.output.c_str(),
                 opt.output.c_str());
    return 1;
  }
  return 0;
}

void add_crops(std::vector<std::pair<std::string, io::Image8>>& images, const std::string& file, const demo::Crops& crops) {
  if (crops.tiles.empty()) return;
  images.emplace_back(file, io::montage(crops.tiles, crops.labels, static_cast<int>(crops.tiles.size()),
                                        std::min(2 * crops.tiles.front().width, 480)));
}

// The main job: for each technique, its configurations walk the path (apps/demo/measurement.h);
// then the adoption question first (the adaptive rule against the engine's Pareto front at equal
// error), the single-map comparison and the tables below it (apps/demo/report.h). A shard walks
// its techniques only and writes them into its part instead.
int run_headless(const Options& opt, shadows::ShadowSettings base, const Sharding& sharding) {
  // Everything that can refuse the command comes before any output: the plotter, the output
  // directory, the scene and its path; then the first line of progress.
  const bool sharded = sharding.shard.has_value();
  if (opt.plot && !sharded) apps::check_python(opt.python, opt.plot_script, "the chart");  // a shard writes its part alone; the merge plots
  const bool flip = opt.flip && opt.reference;
  const double pixels_per_degree = flip ? apps::display_pixels_per_degree(opt.display, "penumbra-demo") : 0.0;  // --display's viewing geometry
  std::optional<io::StagedDirectory> out;
  if (sharded) io::check_output(sharding.part, io::OutputKind::file);
  else out.emplace(opt.output, "report.json");
  gl::HeadlessContext ctx;
  const double t_scene = now_ms();
  scene::Scene scene = scene::load_scene(opt.scene);
  apps::override_light_size(opt.light_size, scene.light);
  const demo::PathPlan plan = demo::plan_path(scene, opt.path, opt.frames);
  std::fprintf(stderr, "scene %s built in %.1f s\n", scene.name.c_str(), (now_ms() - t_scene) / 1000);
  const gl::TimingMethod method = ctx.info().software ? gl::TimingMethod::wall_finish : gl::TimingMethod::gpu_timer;
  const bool directional = scene.light.type == scene::Light::Type::directional;

  RunHead head;
  nlohmann::json& report = head.report;
  report["scene"] = scene.name;
  report["device"] = ctx.info();
  report["image_px"] = {opt.width, opt.height};
  report["light"] = {{"type", directional ? "directional" : "spot"}, {"size", scene.light.size}, {"size_unit", directional ? "deg" : "world"}};
  report["path"] = plan.kind;
  report["path_length"] = plan.length;
  report["path_frames"] = plan.frames.size();
  for (const demo::PathFrame& f : plan.frames) report["path_frame_index"].push_back(f.frame);
  report["frame_time_method"] = "wall_finish";
  report["frame_time_repeats"] = opt.repeats;
  report["pass_time_method"] = gl::to_string(method);
  report["engine_family"] = !opt.baselines ? "none" : opt.sweep ? "sweep" : "default";
  report["calibration"] = apps::calibration_json(opt.calibration, base);
  report["calibration"]["bound"] = opt.ci_upper ? "ci95_hi" : "c";
  if (flip)
    report["perceptual"] = {{"measure", "LDR-FLIP (metrics/flip.h) of the lit frames at the reference frames"},
                            {"display", opt.display},
                            {"pixels_per_degree", pixels_per_degree},
                            {"pixels_per_degree_formula", "2 d tan(0.5 deg) width_px / width_mm (metrics::pixels_per_degree), the frame shown "
                                                          "pixel for pixel"}};
  {
    char line[1024];
    std::snprintf(line, sizeof line, "\n%s at %dx%d on %s; %zu frames of a %d-frame %s path; engine family %s; calibration %s\n",
                  scene.name.c_str(), opt.width, opt.height, ctx.info().renderer.c_str(), plan.frames.size(), plan.length, plan.kind.c_str(),
                  report["engine_family"].get<std::string>().c_str(), opt.calibration.loaded.source.c_str());
    head.scene_line = line;
    const auto& ap = base.adaptive;
    std::snprintf(line, sizeof line,
                  "adaptive: res = c L / r per cascade, as many cascades as the rule needs; texels no finer than %s at a cascade's near "
                  "end (--adaptive.min_texel_px), no wider than %s (--adaptive.max_texel_ws)\n",
                  ap.min_texel_px > 0 ? (std::to_string(ap.min_texel_px).substr(0, 4) + " px").c_str() : "the rule's (off)",
                  ap.max_texel_ws > 0 ? (std::to_string(ap.max_texel_ws).substr(0, 5) + " ws").c_str() : "the rule's (off)");
    head.settings_lines = line;
    std::snprintf(line, sizeof line, "frame time: wall clock around glFinish, ms over the path (median [p10, p90])%s\n",
                  opt.repeats > 1 ? (", each frame the median of " + std::to_string(opt.repeats) + " renders").c_str() : "");
    head.settings_lines += line;
    std::snprintf(line, sizeof line, "\nsingle map: one fitted map of %d² against adaptive, each labelled by its error (RMSE against the reference)\n",
                  base.map.resolution_texels);
    head.settings_lines += line;
    std::snprintf(line, sizeof line, "%-6s %10s %24s %10s %24s %8s %20s %8s %9s %9s\n", "tech", "RMSE fixed", "fixed", "RMSE adapt", "adaptive",
                  "speedup", "adaptive cascades", "min SSIM", "max diff", ">1/255");
    head.settings_lines += line;
  }

  // The techniques this process walks: all of them, or its shard's.
  std::vector<std::size_t> walked;
  for (std::size_t i = 0; i < opt.techniques.size(); ++i)
    if (!sharded || sharding.shard->covers(i)) walked.push_back(i);
  demo::ConfigurationOptions config_options;
  config_options.family = !opt.baselines ? demo::Family::none : opt.sweep ? demo::Family::sweep : demo::Family::default_;
  config_options.auto_cascades = opt.auto_cascades;
  config_options.virtual_pages = opt.virtual_pages && directional;
  std::vector<std::vector<demo::Configuration>> per_technique;
  for (const std::size_t i : walked) {
    shadows::ShadowSettings fixed = base;
    fixed.technique = shadows::technique_from_string(opt.techniques[i]);
    apps::apply_calibration_for(opt.calibration, fixed);  // the technique's own c
    fixed.adaptive.enabled = false;
    per_technique.push_back(demo::configurations(fixed, config_options));
  }
  const int total = static_cast<int>(walked.size() * plan.frames.size());
  int done = 0;
  std::fprintf(stderr, "penumbra-demo: %zu techniques x %zu configurations x %zu frames%s\n", walked.size(), per_technique.front().size(),
               plan.frames.size(),
               sharded ? (" (shard " + sharding.shard->text() + " of " + std::to_string(opt.techniques.size()) + " techniques)").c_str() : "");
  ProgressBar progress("penumbra-demo", true, " frames");
  demo::WalkOptions walk_options;
  walk_options.width = opt.width, walk_options.height = opt.height;
  walk_options.repeats = opt.repeats;
  walk_options.reference = opt.reference;
  walk_options.reference_samples = opt.reference_samples;
  walk_options.perceptual = flip;
  walk_options.pixels_per_degree = flip ? pixels_per_degree : walk_options.pixels_per_degree;
  demo::Walk walk(scene, plan, walk_options, method);
  std::optional<PngBytes> png_bytes;  // a shard's images go into its part
  if (sharded) png_bytes.emplace();
  std::vector<TechniqueOutput> outputs;
  for (std::size_t w = 0; w < walked.size(); ++w) {
    const std::string& name = opt.techniques[walked[w]];
    // The frame observer's "visible": the technique's calibration entry's criterion F (the
    // published design's without an entry).
    const adaptive::CalibrationChoice choice = opt.calibration.choice(per_technique[w].front().settings);
    walk.set_criterion_f(choice.entry ? choice.entry->definition().criterion_f : metrics::kStudyCriterionF);
    demo::TechniqueRun run = walk.run(name, per_technique[w], progress, done, total);
    const demo::EqualErrors equal = demo::equal_errors(run);
    TechniqueOutput o;
    o.index = walked[w];
    o.name = name;
    o.entry = demo::technique_json(run, equal);
    const shadows::ShadowSettings& adapt = run.series[run.adaptive].config.settings;
    o.entry["settings_fixed"] = shadows::to_json(run.series[run.fixed].config.settings);
    o.entry["settings_adaptive"] = shadows::to_json(adapt);
    o.entry["calibration"] = apps::calibration_json(opt.calibration, adapt);
    o.entry["calibration"]["bound"] = opt.ci_upper ? "ci95_hi" : "c";
    o.csv = run.csv;
    o.flip_available = equal.flip.available;
    for (const demo::EqualError* eq : equal.shown()) {
      std::vector<std::string>& lines = o.headlines[static_cast<std::size_t>(eq->measure)];
      lines.push_back(demo::headline(run, *eq));
      for (const demo::VirtualReading& v : eq->virtual_maps) lines.push_back(demo::virtual_headline(run, v));
    }
    o.unseen = demo::unseen_line(run, demo::cheapest_unseen(run));
    o.calibration = apps::calibration_line(opt.calibration, adapt);
    o.single_map_row = demo::single_map_row(run);
    o.tables = demo::tables(run, equal);
    std::vector<std::pair<std::string, io::Image8>> images;
    images.emplace_back(name + "-fixed-vs-adaptive.png", side_by_side(run.shown_fixed, run.shown_adaptive, side_by_side_labels(run, walk.plan())));
    add_crops(images, name + "-crops.png", run.thin_crops);
    add_crops(images, name + "-crops-gain.png", run.gain_crops);
    if (!run.flip_tiles.empty())
      images.emplace_back(name + "-flip-montage.png",
                          io::montage(run.flip_tiles, run.flip_labels, demo::kFlipMontageColumns, demo::flip_montage_tile_width(opt.width)));
    for (const auto& [file, image] : images) {
      if (sharded) o.images.emplace_back(file, (*png_bytes)(image));
      else io::write_png(out->path() / file, image);
    }
    outputs.push_back(std::move(o));
    // The next technique's maps (up to 4 × 4096² each in a sweep) and images come after this one's
    // are gone: what is kept is the numbers and the text.
  }
  progress.clear();  // the tables follow on stdout
  if (!sharded) return write_results(opt, head, outputs, *out);

  // A shard: its results as the run prints them, then its part, whole or not at all.
  print_results(head, outputs);
  nlohmann::json payload = {{"device", report["device"]}, {"head", head_json(head)}, {"techniques", nlohmann::json::array()}};
  std::string names;
  for (const TechniqueOutput& o : outputs) {
    payload["techniques"].push_back(output_json(o));
    names += (names.empty() ? "" : ",") + o.name;
  }
  io::write_file_atomic(sharding.part, shard::part_text(kPartKind, tool::version_line("penumbra-demo"), *sharding.shard,
                                                        {{"args", sharding.args}}, payload));
  std::printf("wrote %s: shard %s, techniques %s of %zu\n", sharding.part.c_str(), sharding.shard->text().c_str(), names.c_str(),
              opt.techniques.size());
  return 0;
}

// penumbra-demo merge: the parts' techniques, checked (merge_main: the parts themselves; here what
// they carry), printed and written as the unsharded run prints and writes them.
int merge_headless(const Options& opt, const std::vector<shard::Part>& parts) {
  if (opt.plot) apps::check_python(opt.python, opt.plot_script, "the chart");
  const shard::Part& first = parts.front();
  const std::string first_file = json_input::printable(first.path.string(), 200);
  const auto head_of = [](const shard::Part& part) -> RunHead {
    const std::string file = json_input::printable(part.path.string(), 200);
    const nlohmann::json& h = part.payload.contains("head") ? part.payload["head"] : nlohmann::json();
    if (!h.is_object() || !h.contains("report") || !h["report"].is_object() || !h.contains("scene_line") || !h["scene_line"].is_string() ||
        !h.contains("settings_lines") || !h["settings_lines"].is_string())
      throw std::runtime_error(file + ": payload.head: missing or not the run's head (report, scene_line, settings_lines)");
    return {h["report"], h["scene_line"].get<std::string>(), h["settings_lines"].get<std::string>()};
  };
  const RunHead head = head_of(first);
  std::vector<std::optional<TechniqueOutput>> outputs(opt.techniques.size());
  for (const shard::Part& part : parts) {
    const std::string file = json_input::printable(part.path.string(), 200);
    // Frame times of two devices are no one measurement: the front at equal error reads them side by side.
    const nlohmann::json device = part.payload.value("device", nlohmann::json());
    if (device != first.payload.value("device", nlohmann::json()))
      throw std::runtime_error(file + ": measured on another device than " + first_file + " (" + json_input::printable(device.dump(), 120) +
                               "); frame times of two devices do not merge");
    // The same command on another machine can still see another scene file or calibration file.
    const RunHead h = head_of(part);
    if (h.report != head.report || h.scene_line != head.scene_line || h.settings_lines != head.settings_lines)
      throw std::runtime_error(file + ": its run's scene, path, calibration or display differ from " + first_file +
                               "'s (payload.head); the parts are not one run");
    const nlohmann::json& list = part.payload.contains("techniques") ? part.payload["techniques"] : nlohmann::json();
    if (!list.is_array()) throw std::runtime_error(file + ": payload.techniques: missing or not a list");
    for (std::size_t k = 0; k < list.size(); ++k) {
      TechniqueOutput o;
      try {
        o = output_of_json(list[k]);
      } catch (const std::exception& e) {
        throw std::runtime_error(file + ": payload.techniques[" + std::to_string(k) + "]." + e.what());
      }
      if (o.index >= opt.techniques.size() || !part.shard.covers(o.index) || opt.techniques[o.index] != o.name || outputs[o.index])
        throw std::runtime_error(file + ": payload.techniques[" + std::to_string(k) + "]: " + json_input::printable(o.name, 40) +
                                 " at position " + std::to_string(o.index) + " is not one of shard " + part.shard.text() +
                                 "'s techniques of --techniques");
      outputs[o.index] = std::move(o);
    }
    for (std::size_t i = part.shard.index; i < opt.techniques.size(); i += part.shard.count)
      if (!outputs[i])
        throw std::runtime_error(file + ": payload.techniques: " + opt.techniques[i] + " (shard " + part.shard.text() + "'s) missing");
  }
  std::vector<TechniqueOutput> techniques;
  for (auto& o : outputs) techniques.push_back(std::move(*o));
  io::StagedDirectory out(opt.output, "report.json");
  return write_results(opt, head, techniques, out);
}

// --pages: the pages of a virtual shadow map for the sun along the path. Each pixel's surface asks
// for the coarsest clipmap level its filter allows (the rule: texel <= max(r / c, pixel
// footprint)) or that its footprint alone allows (what engines' virtual shadow maps use), plus the
// pages its filter reaches, marked on the GPU as the renderer marks them (apps::VirtualDebug: PCSS
// in its two rounds, the searches' pages and then each pixel's penumbra's); the pages are counted
// per frame. Then they are drawn into a virtual shadow map's pool (shadows/virtual_shadow_map.h,
// 1024 slots: 64 MB), once per frame from nothing (the work of a frame without a cache) and once
// along the path with the cache (what a walking camera redraws), each timed with glFinish around it.
int run_pages(const Options& opt, shadows::ShadowSettings base) {
  io::StagedDirectory out(opt.output, "pages.json");
  gl::HeadlessContext ctx;
  scene::Scene scene = scene::load_scene(opt.scene);
  apps::override_light_size(opt.light_size, scene.light);
  if (scene.light.type != scene::Light::Type::directional)
    throw std::runtime_error("--pages: the virtual shadow map is the sun's; scene " + scene.name + " has a spot light");
  const demo::PathPlan plan = demo::plan_path(scene, opt.path, opt.frames);
  const scene::GpuMeshes meshes(scene.objects);
  shadows::VirtualMapView view;  // per frame: the maps' bounded region for its camera (shadows::sun_virtual_view)
  bool has_view = false;
  const int kPoolSide = shadows::ShadowMapParams{}.virtual_pool_pages;  // the renderer's default pool
  adaptive::VirtualMapLayout layout;
  const double kPageBytes = static_cast<double>(layout.page_texels) * layout.page_texels * 4;  // a page of 32-bit depth
  std::vector<io::Image8> level_views;  // levels.png
  std::vector<std::string> level_labels;
  nlohmann::json report;
  report["scene"] = scene.name;
  report["image_px"] = {opt.width, opt.height};
  report["pool_slots"] = kPoolSide * kPoolSide;
  report["timing"] = "wall clock around the update with glFinish";
  report["marking"] = "on the GPU, as the renderer marks (PCSS: the searches' pages, then each pixel's penumbra's)";
  report["layout"] = {{"levels", layout.levels}, {"texel0_ws", layout.texel0_ws}, {"page_texels", layout.page_texels},
                      {"pages_per_side", layout.pages_per_side}};
  std::printf("penumbra-demo --pages: %s at %dx%d, %zu frames; clipmap of %d levels, level 0 texel %g ws, pages of %d² texels, "
              "%d² pages per level\n",
              scene.name.c_str(), opt.width, opt.height, plan.frames.size(), layout.levels, layout.texel0_ws, layout.page_texels,
              layout.pages_per_side);
  std::printf("%-6s %6s %12s %12s %8s %12s %12s %16s %16s %14s\n", "tech", "frame", "pages rule", "footprint", "ratio", "MB rule",
              "MB footprint", "ms draw rule", "ms draw fp", "cached drawn");
  for (const std::string& name : opt.techniques) {
    shadows::ShadowSettings s = base;
    s.technique = shadows::technique_from_string(name);
    apps::apply_calibration_for(opt.calibration, s);
    const apps::VirtualMarking marking = apps::virtual_marking(s, scene.light);
    if (!marking.problem.empty()) throw std::runtime_error("--pages: technique " + name + ": " + marking.problem);
    nlohmann::json t = {{"technique", name}, {"c", marking.options.c_texels}, {"min_texel_px", marking.options.min_texel_px}};
    if (marking.pcss) t["min_penumbra_ws"] = marking.pcss->min_penumbra_ws;
    else t["radius_ws"] = marking.radius_ws;
    std::vector<double> ratios;
    apps::VirtualDebug marker(scene);  // the marking, with the pool its searches read (PCSS)
    // Drawn from nothing each frame (uncached), and along the path keeping pages (cached), per marking.
    shadows::VirtualShadowMap uncached(layout, kPoolSide), cached_rule(layout, kPoolSide), cached_footprint(layout, kPoolSide);
    scene::Scene posed = scene;  // the moving objects (scene::ObjectPath) where the frame drawn has them
    const auto timed_update = [&](shadows::VirtualShadowMap& map, const adaptive::MarkResult& marks, double& ms) {
      glFinish();
      const double t0 = now_ms();
      const shadows::VirtualMapStats st = map.update(marks.pages, view, posed, meshes);
      glFinish();
      ms = now_ms() - t0;
      return st;
    };
    const auto stats_json = [](const shadows::VirtualMapStats& st, double ms) {
      nlohmann::json j = shadows::virtual_pages_json(st);  // the key set of every report
      j["update_ms"] = ms;
      return j;
    };
    const auto marked_pixels = [](const adaptive::MarkResult& m) {
      std::int64_t n = m.unmarked;
      for (const std::int64_t k : m.pixels_per_level) n += k;
      return n;
    };
    for (std::size_t fi = 0; fi < plan.frames.size(); ++fi) {
      const demo::PathFrame& pf = plan.frames[fi];
      const scene::Camera camera = demo::camera_at(scene, plan, pf.frame);
      posed = scene::posed_at(scene, pf.frame);
      for (shadows::VirtualShadowMap* map : {&cached_rule, &cached_footprint}) map->invalidate_moved_casters(posed);  // the van's pages
      // The debug view (the first technique, each station's first frame): the level each pixel
      // samples, by the rule and by the footprint.
      const bool images = &name == &opt.techniques.front() && (fi == 0 || pf.frame != plan.frames[fi - 1].frame + 1);
      apps::VirtualDebug::View marked = marker.view(posed, camera, opt.width, opt.height, marking, images);
      if (images) {
        for (const auto& [levels, m] : {std::pair{&marked.rule_levels, "rule"}, std::pair{&marked.footprint_levels, "footprint"}}) {
          level_views.push_back(std::move(*levels));
          level_labels.push_back("frame " + std::to_string(pf.frame) + ", " + m);
        }
      }
      const adaptive::MarkResult& by_rule = marked.rule;
      const adaptive::MarkResult& by_footprint = marked.footprint;
      const double ratio = by_rule.pages.empty() ? 0.0 : static_cast<double>(by_footprint.pages.size()) / static_cast<double>(by_rule.pages.size());
      ratios.push_back(ratio);
      scene::Scene seen = posed;
      seen.camera = camera;
      view = shadows::sun_virtual_view(seen, static_cast<float>(opt.width) / static_cast<float>(opt.height), has_view ? &view : nullptr);
      has_view = true;
      double ms_rule = 0, ms_footprint = 0, ms_cached_rule = 0, ms_cached_footprint = 0;
      uncached.invalidate_all();
      const shadows::VirtualMapStats draw_rule = timed_update(uncached, by_rule, ms_rule);
      uncached.invalidate_all();
      const shadows::VirtualMapStats draw_footprint = timed_update(uncached, by_footprint, ms_footprint);
      const shadows::VirtualMapStats walk_rule = timed_update(cached_rule, by_rule, ms_cached_rule);
      const shadows::VirtualMapStats walk_footprint = timed_update(cached_footprint, by_footprint, ms_cached_footprint);
      std::printf("%-6s %6d %12zu %12zu %7.2fx %12.1f %12.1f %16.1f %16.1f %7d/%-6d\n", name.c_str(), pf.frame, by_rule.pages.size(),
                  by_footprint.pages.size(), ratio, static_cast<double>(by_rule.pages.size()) * kPageBytes / 1048576.0,
                  static_cast<double>(by_footprint.pages.size()) * kPageBytes / 1048576.0, ms_rule, ms_footprint, walk_rule.drawn,
                  walk_rule.requested);
      t["frames"].push_back({{"path_frame", pf.frame},
                             {"pixels", marked_pixels(by_rule)},  // that marked filter pages (PCSS: those with a blocker in front)
                             {"pages_rule", by_rule.pages.size()},
                             {"pages_footprint", by_footprint.pages.size()},
                             {"pages_per_level_rule", by_rule.pages_per_level()},
                             {"pages_per_level_footprint", by_footprint.pages_per_level()},
                             {"pixels_per_level_rule", by_rule.pixels_per_level},
                             {"pixels_per_level_footprint", by_footprint.pixels_per_level},
                             {"unmarked_rule", by_rule.unmarked},
                             {"unmarked_footprint", by_footprint.unmarked},
                             {"uncached_rule", stats_json(draw_rule, ms_rule)},
                             {"uncached_footprint", stats_json(draw_footprint, ms_footprint)},
                             {"cached_rule", stats_json(walk_rule, ms_cached_rule)},
                             {"cached_footprint", stats_json(walk_footprint, ms_cached_footprint)}});
    }
    const stats::Spread sr = stats::spread(ratios);
    std::printf("%-6s median footprint / rule pages %.2fx [%.2f, %.2f] over %zu frames\n", name.c_str(), sr.median, sr.min, sr.max,
                ratios.size());
    t["pages_ratio_footprint_over_rule"] = {{"median", sr.median}, {"min", sr.min}, {"max", sr.max}};
    report["techniques"].push_back(t);
  }
  level_views.push_back(apps::level_key(layout.levels, opt.width, std::max(1, opt.height / 4)));
  level_labels.push_back("key: levels 0-" + std::to_string(layout.levels - 1) + ", fine to coarse");
  io::write_png(out.path() / "levels.png", io::montage(level_views, level_labels, 2, std::min(opt.width, 480)));
  io::write_file_atomic(out.path() / "pages.json", json_input::dump(report, 2) + "\n");
  out.commit();
  std::printf("wrote %s/pages.json\n", opt.output.c_str());
  return 0;
}

#if PENUMBRA_DEMO_GUI
int run_windowed(const Options& opt, shadows::ShadowSettings settings) {
  scene::Scene scene = scene::load_scene(opt.scene);
  apps::override_light_size(opt.light_size, scene.light);
  gl::Glfw glfw;
  gl::Window window(
      {.title = "Penumbra demo - " + scene.name, .width = opt.width, .height = opt.height, .gl_errors_throw = gl::kDebugBuild});
  shadows::Renderer renderer;
  renderer.set_scene(scene);
  settings.adaptive.enabled = true;
  if (opt.auto_cascades) settings.map.cascades = 0;
  apps::CalibrationFollower follower;  // the panel's technique switch picks that technique's c
  gui::SettingsUndo undo;  // a panel change the view cannot draw is undone, and said in the panel
  gl::PassTimer timer(!window.info().software);
  bool show_map = true, show_cascades = false, animate = true;
  int frame = 0, path_i = 0;
  double fps = 0, last = now_ms();
  while (!window.should_close()) {
    glfw.wait_events(0);
    window.begin_frame();
    if (animate && scene.camera_path.empty()) {
      renderer.scene().camera = demo::orbit_camera(scene.camera, path_i++ % (4 * opt.frames), 4 * opt.frames);
    } else if (animate) {
      const int path_frame = path_i++ % scene.camera_path.frames();
      renderer.scene().camera = scene.camera_path.at(scene.camera, path_frame);
      scene::pose_objects(scene, path_frame, renderer.scene());  // the moving objects with it
    }
    int fb_w = 0, fb_h = 0;
    window.framebuffer_size(fb_w, fb_h);
    if (frame % 30 == 0) timer.clear();
    renderer.set_show_cascades(show_cascades);
    shadows::FrameInfo info;
    undo.render(settings, [&](shadows::ShadowSettings& s) {
      follower.update(opt.calibration, s);
      info = renderer.render(gui::drawable_settings(s, renderer.scene()), std::max(fb_w, 1), std::max(fb_h, 1), &timer);
    });
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
    undo.line();
    gui::virtual_pages_line(settings, renderer.scene(), info);
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

// The command line less --shard and --part: a part's settings (fingerprinted; the merge parses
// them again, with its own -o DIR).
std::vector<std::string> settings_args(const std::vector<std::string>& args) {
  return shard::without_options(args, {"--shard", "--part"});
}

// The command line `args` (argv less the tool's name); for a merge, the parts' own arguments and
// -o DIR, with `merged` the parts (checked by merge_main).
int run(const std::vector<std::string>& args, const std::vector<shard::Part>* merged) {
  shard::Argv argv("penumbra-demo", args);
  const char* const tool_name = merged ? "penumbra-demo merge" : "penumbra-demo";
  CLI::App app{"Adaptive shadow-map resolution against a fixed resolution: frame time and image difference."};
  cli::describe_tool(app, "penumbra-demo", "adaptive.md");
  Options opt;
  bool headless = false;
  bool pages = false;
  shadows::ShadowSettings base = demo_defaults();
  app.add_flag("--headless", headless, "run the comparison along the camera path without a window");
  app.add_option("--scene", opt.scene, "built-in scene name or scene file (.json)");
  apps::add_light_size_option(app, opt.light_size);
  cli::add_list_option(app, "--techniques", opt.techniques, "techniques to compare (comma separated)", apps::technique_items(false));
  app.add_option("--path", opt.path,
                 "scenes with a camera path: short (--frames frames, as stations of 3 consecutive frames spread over the path) "
                 "or full (every frame)")
      ->check(CLI::IsMember({"short", "full"}));
  app.add_option("--frames", opt.frames, "frames per technique: of the short path, or of the orbit of a scene without a camera path")
      ->check(CLI::Range(1, 100000));
  app.add_flag("--pages", pages,
               "headless: the pages a virtual shadow map of the sun marks along the path, by the rule and by the pixel footprint, "
               "marked on the GPU as the renderer marks them (PCSS: its searches' pages, then each pixel's penumbra's), drawn into its "
               "page pool from nothing and with its cache (shadows/virtual_shadow_map.h); writes pages.json");
  app.add_flag("--sweep", opt.sweep,
               "the whole engine family: single maps of 1024²-8192² and 2-4 cascades of 1024²-4096² (default: single maps of "
               "half, twice and four times --fixed-resolution, two cascades of once and twice it, four cascades of it)");
  app.add_option("--repeats", opt.repeats, "renders per frame and configuration; a frame's time is their median")
      ->check(CLI::Range(1, 100));
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
               "skip the engine family (and with it the equal-error comparison): adaptive and the fixed map only");
  app.add_flag("!--no-virtual", opt.virtual_pages,
               "headless: without the sun's virtual shadow map (virtual rule / footprint, drawn every frame, and the rule cached; "
               "box PCF in world units only)");
  app.add_flag("!--no-reference", opt.reference,
               "skip the error against the reference (four cascades of 8192² with the same filter, or the area-light mean)");
  app.add_flag("!--no-flip", opt.flip,
               "skip the perceptual difference (LDR-FLIP of the lit frames against the reference's; PCSS also against PCSS at "
               "converged resolution and taps)");
  app.add_option("--display", opt.display,
                 "study config whose display block (width_px, width_mm, viewing_distance_mm) gives FLIP's pixels per degree")
      ->check(cli::path_given());
  app.add_option("--reference-samples", opt.reference_samples,
                 "area-light reference: shadow rays per pixel (ray-traced) or point-light maps averaged (without Embree), rounded "
                 "up to a square")
      ->check(CLI::Range(1, 4096));
  app.add_option("--screenshot", opt.screenshot, "windowed: write the window (with the panel) to this PNG, then exit");
  app.add_option("--screenshot-frames", opt.screenshot_frames, "windowed: frames before --screenshot")->check(CLI::Range(1, 100000));
  std::string shard_text, part_out;
  app.add_option("--shard", shard_text,
                 "I/N: --headless walks only shard I of N (0 <= I < N) of the techniques, those whose position in --techniques is I "
                 "modulo N (a technique's configurations are compared frame by frame: it is not split), into --part instead of -o; "
                 "`penumbra-demo merge PARTS... -o DIR` prints and writes what the unsharded run does, but for the frame times and "
                 "what is read from them (docs/cluster.md)");
  app.add_option("--part", part_out,
                 "--shard: the part file to write, whole or not at all (the shard's techniques: report entries, frames.csv rows, "
                 "printed lines and images; the arguments, the device and the build's version)");
  apps::add_settings_options(app, base);
  if (const auto status = cli::parse(app, argv.argc(), argv.argv(), tool_name)) return *status;
  opt.auto_cascades = app.count("--map.cascades") == 0;
  try {
    Sharding sharding;
    if (!shard_text.empty()) {
      if (!headless || pages) throw cli::UsageError("--shard: only with --headless (a shard walks whole techniques of the comparison)");
      sharding.shard = shard::parse(shard_text);
      if (part_out.empty()) throw cli::UsageError("--shard: needs --part FILE, where the shard's techniques go");
      if (app.count("--output") > 0)
        throw cli::UsageError("--output: a shard writes a part (--part); `penumbra-demo merge PARTS... -o DIR` writes the directory");
      if (sharding.shard->count > opt.techniques.size())
        throw cli::UsageError("--shard: " + shard_text + ": N is above the " + std::to_string(opt.techniques.size()) +
                              " techniques of --techniques, the unit a shard walks (at most " + std::to_string(opt.techniques.size()) +
                              " shards)");
      sharding.part = part_out;
      sharding.args = settings_args(args);
    } else if (!part_out.empty()) {
      throw cli::UsageError("--part: only with --shard I/N");
    }
    std::vector<shadows::Technique> compared;
    std::string listed;
    for (const auto& t : opt.techniques) {
      compared.push_back(shadows::technique_from_string(t));
      listed += (listed.empty() ? "" : ",") + t;
    }
    (void)apps::setting_stands_for(app, "--map.resolution_texels", "--fixed-resolution");
    if (headless) apps::refuse_unused_technique_options(app, compared, "--techniques " + listed);
    if (merged) return merge_headless(opt, *merged);  // the parts carry what the calibration gave
    apps::apply_calibration(app, opt.calibration, base, opt.ci_upper);
    if (pages) return run_pages(opt, base);
    if (headless) return run_headless(opt, base, sharding);
#if PENUMBRA_DEMO_GUI
    return run_windowed(opt, base);
#else
    return cli::fail("penumbra-demo", "built without GUI support; use --headless", cli::kExitUsage);
#endif
  } catch (const std::exception& e) {
    return cli::fail(tool_name, e);
  }
}

// penumbra-demo merge PARTS... -o DIR: the parts, checked (shard::read_parts: none missing or
// twice, one command, one build), through run() with their own arguments.
int merge_main(int argc, char** argv) {
  CLI::App app{"Merge the part files of penumbra-demo --headless ... --shard I/N --part FILE: prints the tables and writes the "
               "directory the unsharded run writes (report.json, frames.csv, the images, the plots). The images are its bytes; "
               "every field and column equals the unsharded run's but the frame times and what is read from them: frame_ms, "
               "shadow_ms, the passes' *_ms, the references' and FLIP's times, the speedups, the fronts on time and shadow cost "
               "(front, front_ms, ratio, the * marks, on_front.time), the headlines and the observer's cheapest by time "
               "(docs/cluster.md)",
               "penumbra-demo merge"};
  cli::describe_tool(app, "penumbra-demo merge", "cluster.md");
  std::vector<std::string> paths;
  std::string out;
  app.add_option("parts", paths, "the part files, one per shard 0/N to N-1/N, any order")->required();
  app.add_option("-o,--output", out, "the output directory (as -o of the unsharded run)")->required()->check(cli::path_given());
  if (const auto status = cli::parse(app, argc - 1, argv + 1, "penumbra-demo merge")) return *status;
  std::vector<std::string> args;
  shard::Checked checked;
  try {
    checked = shard::read_parts({paths.begin(), paths.end()}, kPartKind, tool::version_line("penumbra-demo"));
    args = shard::stored_args(checked.settings, paths.front());
  } catch (const std::exception& e) {
    return cli::fail("penumbra-demo merge", e);
  }
  args.push_back("-o");
  args.push_back(out);
  return run(args, &checked.parts);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc >= 2 && std::string_view(argv[1]) == "merge") return merge_main(argc, argv);
  return run(std::vector<std::string>(argv + 1, argv + argc), nullptr);
}
