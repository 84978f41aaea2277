// penumbra-bench: shadow error against frame time. For every scene, technique of the settings
// table, filter radius and shadow-map resolution it renders K timed frames and compares the
// visibility with a ground truth (renderer/metrics/ground_truth.h): the area-light average for
// techniques that stand for an area light (PCSS), the same filter on an 8192² map otherwise.
// Beside the fixed resolutions, each variant gets an adaptive row (the rule sizes the map) and,
// under a sun for the filters that read pages (box PCF and VSM with a world radius, PCSS with a
// box filter), two rows of the sun's virtual shadow map, its pages marked by the rule and by the
// footprint and drawn every frame.
// Writes DIR/bench.csv (one row per configuration, `pareto` marks the error/time front among
// the rows measured against the same reference), DIR/report.json, and one plot per scene
// (DIR/pareto-<scene>.png/.svg, drawn by scripts/plot_bench.py). Progress goes to stderr.
// The rows are independent: --shard I/N --part FILE measures every N-th of them (shard/shard.h),
// on any machine, and `penumbra-bench merge PARTS... -o DIR` writes the DIR the unsharded run
// writes. Frame times are measurements, so what a merge reproduces byte for byte is every other
// column; the Pareto marks, which read the times, are drawn again over the merged rows
// (docs/cluster.md).
#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "cli_options.h"
#include "cli/main.h"
#include "io/atomic_file.h"
#include "json/json_input.h"
#include "run_python.h"
#include "gl/context.h"
#include "gl/objects.h"
#include "gl/timer.h"
#include "io/image_io.h"
#include "io/report.h"
#include "io/safe_path.h"
#include "io/staged_dir.h"
#include "metrics/ground_truth.h"
#include "metrics/image_error.h"
#include "scene/scene.h"
#include "shadows/frame_plan.h"
#include "shadows/frame_report.h"
#include "shadows/renderer.h"
#include "stats/summary.h"
#include "shadows/settings.h"
#include "shadows/technique.h"
#include "shadows/virtual_shadow_map.h"
#include "shard/shard.h"
#include "tool/tool.h"

namespace fs = std::filesystem;
using namespace penumbra;

namespace {

struct Options {
  std::vector<std::string> scenes = {"demo", "fence", "tilted", "two-planes"};
  std::vector<std::string> techniques;  // empty: every technique of the settings table
  std::vector<int> resolutions = {128, 256, 512, 1024, 2048, 4096};
  std::vector<double> radii_ws = {0.05};  // one radius keeps the default run under ~10 min on llvmpipe
  int width = 640, height = 360, frames = 5, warmup = 1;
  metrics::ReferenceOptions reference;
  shadows::ShadowSettings base;
  apps::CalibrationOption calibration;
  bool adaptive = true;  // one adaptive row per variant the rule applies to
  bool virtual_map = true;  // virtual map rows (rule, footprint) per variant that reads pages, under a sun
  bool plot = true;
  std::string python = "/usr/bin/python3";
  std::string plot_script = tool::script_file("plot_bench.py").string();
  std::string output;
};

// One configuration family: a technique, and for fixed-radius filters one world-space radius.
// Every resolution of a variant is measured against the variant's one reference.
struct Variant {
  std::string technique;
  std::string label;        // "pcf r=0.05", "pcss"
  double radius_ws = NAN;   // NaN: the technique has no radius the bench sweeps
  shadows::ShadowSettings settings;
};

struct FrameTimes {
  std::vector<double> ms;
  gl::TimingMethod method = gl::TimingMethod::wall_finish;
  double median() const { return stats::median(ms); }
  double min() const { return *std::min_element(ms.begin(), ms.end()); }
  double max() const { return *std::max_element(ms.begin(), ms.end()); }
};

struct Row {
  std::size_t item = 0;  // the row's number in the grid's loop order (scene, variant, row of the variant): its shard
  std::string scene, technique, variant;
  double radius_ws = NAN;
  int resolution_texels = 0;  // 0 for a virtual map's row: it has pages, not one resolution
  bool adaptive = false;
  std::string virtual_pages;  // a virtual map's row: how its pages were marked (rule, footprint); else empty
  int pages_resident = 0;     // a virtual map's pages in the pool after the frame
  double memory_texels = 0;   // shadow memory in 4-byte texels: the atlas, or the resident pages and the page tables
  FrameTimes times;
  double floor_ms = 0;
  std::string reference_kind;  // the reference's kind, size and samples (a merge has the numbers, not the images)
  int reference_resolution_texels = 0, reference_samples = 0;
  metrics::ImageError error;
  bool pareto = false;
  bool pareto_spread = false;
  float s_xy = 1;
  float filter_radius_texels = 0;
  std::string resolution_source = "fixed";  // FrameInfo::resolution_source: fixed, rule, pcss_per_pixel, ...
  double required_texels = NAN;             // adaptive: the rule's requirement before clamping
  int cascades = 1;
  std::string settings;
  float c = 0;         // adaptive.c of the row's settings
  std::string c_from;  // where it came from (calibration.json entry, fallback or --adaptive.c)
  nlohmann::json work;  // the last timed frame's, per pass (what a GPU pays for): shadows::work_json
};

// Sets a fixed-radius filter's radius in world units, so that the filter is the same footprint
// at every resolution and at the reference's. False for techniques without such a radius.
bool set_radius_ws(shadows::ShadowSettings& s, double radius_ws) {
  const shadows::TechniqueEntry& entry = shadows::technique_entry(s.technique);
  if (!entry.set_filter_radius) return false;
  entry.set_filter_radius(s, {static_cast<float>(radius_ws), shadows::RadiusUnit::world});
  return true;
}

std::string format_radius(double r) {
  std::ostringstream o;
  o << r;
  return o.str();
}

std::vector<Variant> make_variants(const Options& opt) {
  std::vector<Variant> out;
  const auto names = opt.techniques.empty() ? std::vector<std::string>(shadows::technique_names().begin(), shadows::technique_names().end())
                                            : opt.techniques;
  for (const auto& name : names) {
    shadows::ShadowSettings s = opt.base;
    s.technique = shadows::technique_from_string(name);
    s.adaptive.enabled = false;  // fixed rows; the adaptive row of a variant switches it on
    apps::apply_calibration_for(opt.calibration, s);  // the technique's own c (calibration.json entry)
    shadows::ShadowSettings probe = s;
    if (set_radius_ws(probe, 1)) {
      for (double r : opt.radii_ws) {
        Variant v{name, name + " r=" + format_radius(r), r, s};
        set_radius_ws(v.settings, r);
        out.push_back(v);
      }
    } else {
      out.push_back({name, name, NAN, s});
    }
  }
  return out;
}

// Whether the adaptive rule has a filter size to work from (TechniqueEntry::filter_radius or
// rule_radius_ws): the swept radius of a fixed-radius filter, PCSS's penumbra. For the others
// (hard, screen-space) it would only ever pick adaptive.max_texels, a row that repeats a fixed one.
bool has_rule_radius(const Variant& v) {
  return !std::isnan(v.radius_ws) || shadows::technique_entry(v.settings.technique).rule_radius_ws != nullptr;
}

// Whether the variant's filter reads the sun's virtual shadow map in `scene` (shadows/frame_plan.h).
bool reads_pages(const Variant& v, const scene::Scene& scene) { return shadows::virtual_pages_refusal(v.settings, scene).empty(); }

// K frames after `warmup` untimed ones (which absorb allocation and shader compilation). Each
// frame is bracketed by glFinish and timed with the wall clock; on a GPU a GL_TIME_ELAPSED query
// around the frame is read back at once (a stall between frames costs the bench nothing).
FrameTimes time_frames(shadows::Renderer& r, const shadows::ShadowSettings& s, int width, int height, int warmup, int frames,
                       bool gpu, shadows::FrameInfo& info) {
  for (int i = 0; i < warmup; ++i) r.render(s, width, height);
  FrameTimes t;
  t.method = gpu ? gl::TimingMethod::gpu_timer : gl::TimingMethod::wall_finish;
  std::optional<gl::Query> query;
  if (gpu) query.emplace(GL_TIME_ELAPSED);
  for (int i = 0; i < frames; ++i) {
    glFinish();
    const auto t0 = std::chrono::steady_clock::now();
    if (gpu) glBeginQuery(GL_TIME_ELAPSED, query->id());
    info = r.render(s, width, height);
    if (gpu) glEndQuery(GL_TIME_ELAPSED);
    glFinish();
    const auto t1 = std::chrono::steady_clock::now();
    if (gpu) {
      GLuint64 ns = 0;
      glGetQueryObjectui64v(query->id(), GL_QUERY_RESULT, &ns);
      t.ms.push_back(static_cast<double>(ns) * 1e-6);
    } else {
      t.ms.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
    }
  }
  return t;
}

// Marks, within each (scene, variant) group, the rows no other row beats in both frame time and
// error (mean absolute visibility error): lower or equal in both and lower in one. `pareto` compares
// median frame times; `pareto_spread` reads frame times whose [min, max] ranges overlap as a tie
// (another row beats this one if it is no less accurate and not slower beyond the spread, and
// either more accurate or faster beyond it: its slowest frame faster than this row's fastest).
void mark_pareto(std::vector<Row>& rows) {
  for (auto& a : rows) {
    a.pareto = a.pareto_spread = true;
    for (const auto& b : rows) {
      if (&a == &b || a.scene != b.scene || a.variant != b.variant) continue;
      const double am = a.times.median(), bm = b.times.median();
      const double ae = a.error.mean_abs, be = b.error.mean_abs;
      if (bm <= am && be <= ae && (bm < am || be < ae)) a.pareto = false;
      const bool b_faster = b.times.max() < a.times.min(), b_slower = b.times.min() > a.times.max();
      if (be <= ae && !b_slower && (be < ae || b_faster)) a.pareto_spread = false;
    }
  }
}

std::string csv_number(double v) {
  if (std::isnan(v)) return "";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

const char* kCsvHeader =
    "scene,technique,variant,filter_radius_ws,resolution_texels,adaptive,width_px,height_px,frames,timing_method,"
    "frame_ms_median,frame_ms_min,frame_ms_max,floor_ms,reference_kind,reference_resolution_texels,reference_samples,"
    "mean_abs,rmse,max_abs,ssim,psnr_db,share_above_1_255,pareto,pareto_spread,s_xy,filter_radius_texels,resolution_source,required_texels,"
    "cascades,virtual_pages,pages_resident,memory_texels,settings";

std::string csv_row(const Row& r, const Options& opt) {
  std::ostringstream o;
  o << r.scene << ',' << r.technique << ',' << r.variant << ',' << csv_number(r.radius_ws) << ',' << r.resolution_texels << ','
    << (r.adaptive ? 1 : 0) << ',' << opt.width << ',' << opt.height << ',' << r.times.ms.size() << ','
    << gl::to_string(r.times.method) << ',' << csv_number(r.times.median()) << ',' << csv_number(r.times.min()) << ','
    << csv_number(r.times.max()) << ',' << csv_number(r.floor_ms) << ',' << r.reference_kind << ','
    << r.reference_resolution_texels << ',' << r.reference_samples << ',' << csv_number(r.error.mean_abs) << ','
    << csv_number(r.error.rmse) << ',' << csv_number(r.error.max_abs) << ',' << csv_number(r.error.ssim) << ','
    << csv_number(r.error.psnr_db) << ',' << csv_number(r.error.share_above_threshold) << ',' << (r.pareto ? 1 : 0) << ','
    << (r.pareto_spread ? 1 : 0) << ','
    << csv_number(r.s_xy) << ',' << csv_number(r.filter_radius_texels) << ',' << r.resolution_source << ','
    << csv_number(r.required_texels) << ',' << r.cascades << ',' << r.virtual_pages << ',' << r.pages_resident << ','
    << csv_number(r.memory_texels) << ",\"" << r.settings << "\"";
  return o.str();
}

nlohmann::json row_json(const Row& r) {
  nlohmann::json j = {{"scene", r.scene},
                      {"technique", r.technique},
                      {"variant", r.variant},
                      {"filter_radius_ws", std::isnan(r.radius_ws) ? nlohmann::json(nullptr) : nlohmann::json(r.radius_ws)},
                      {"resolution_texels", r.resolution_texels},
                      {"adaptive", r.adaptive},
                      {"timing_method", gl::to_string(r.times.method)},
                      {"frame_ms", r.times.ms},
                      {"frame_ms_median", r.times.median()},
                      {"floor_ms", r.floor_ms},
                      {"reference_kind", r.reference_kind},
                      {"error", metrics::to_json(r.error)},
                      {"pareto", r.pareto},
                      {"pareto_spread", r.pareto_spread},
                      {"s_xy", r.s_xy},
                      {"resolution_source", r.resolution_source},
                      {"required_texels", std::isfinite(r.required_texels) ? nlohmann::json(r.required_texels) : nlohmann::json(nullptr)},
                      {"cascades", r.cascades},
                      {"virtual_pages", r.virtual_pages.empty() ? nlohmann::json(nullptr) : nlohmann::json(r.virtual_pages)},
                      {"pages_resident", r.pages_resident},
                      {"memory_texels", r.memory_texels},
                      {"c", r.c},
                      {"c_from", r.c_from},
                      {"settings", r.settings}};
  j["work"] = r.work;
  return j;
}

// A part's numbers: JSON has no NaN or infinity (an unset radius, the PSNR of an exact match).
nlohmann::json part_number(double v) {
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  return v;
}
double number_of_part(const nlohmann::json& j) {
  if (j.is_number()) return j.get<double>();
  const std::string text = j.get<std::string>();  // throws for anything else: the caller names the part
  if (text == "nan") return NAN;
  if (text == "inf" || text == "-inf") return text == "inf" ? INFINITY : -INFINITY;
  throw std::runtime_error("'" + json_input::printable(text, 20) + "' is not a number");
}

// Everything a row of bench.csv and report.json reads, for a part file. JSON numbers round-trip
// doubles exactly, and the floats are doubles on the way, so a merged row prints as the measured one.
nlohmann::json row_part(const Row& r) {
  const metrics::ImageError& e = r.error;
  return {{"item", r.item}, {"scene", r.scene}, {"technique", r.technique}, {"variant", r.variant},
          {"radius_ws", part_number(r.radius_ws)}, {"resolution_texels", r.resolution_texels}, {"adaptive", r.adaptive},
          {"virtual_pages", r.virtual_pages}, {"pages_resident", r.pages_resident}, {"memory_texels", part_number(r.memory_texels)},
          {"frame_ms", r.times.ms}, {"timing_method", gl::to_string(r.times.method)}, {"floor_ms", part_number(r.floor_ms)},
          {"reference_kind", r.reference_kind}, {"reference_resolution_texels", r.reference_resolution_texels},
          {"reference_samples", r.reference_samples},
          {"error", {{"pixels", e.pixels}, {"channels", e.channels}, {"max_abs", part_number(e.max_abs)}, {"mean_abs", part_number(e.mean_abs)},
                     {"rmse", part_number(e.rmse)}, {"psnr_db", part_number(e.psnr_db)}, {"ssim", part_number(e.ssim)},
                     {"threshold", part_number(e.threshold)}, {"share_above_threshold", part_number(e.share_above_threshold)}}},
          {"s_xy", r.s_xy}, {"filter_radius_texels", r.filter_radius_texels}, {"resolution_source", r.resolution_source},
          {"required_texels", part_number(r.required_texels)}, {"cascades", r.cascades}, {"settings", r.settings}, {"c", r.c},
          {"c_from", r.c_from}, {"work", r.work}};
}

// The row a part recorded; throws naming the part's file and the row for a field that is missing
// or of the wrong type.
Row row_of_part(const nlohmann::json& j, const std::string& file) {
  try {
    Row r;
    r.item = j.at("item").get<std::size_t>();
    r.scene = j.at("scene").get<std::string>();
    r.technique = j.at("technique").get<std::string>();
    r.variant = j.at("variant").get<std::string>();
    r.radius_ws = number_of_part(j.at("radius_ws"));
    r.resolution_texels = j.at("resolution_texels").get<int>();
    r.adaptive = j.at("adaptive").get<bool>();
    r.virtual_pages = j.at("virtual_pages").get<std::string>();
    r.pages_resident = j.at("pages_resident").get<int>();
    r.memory_texels = number_of_part(j.at("memory_texels"));
    r.times.ms = j.at("frame_ms").get<std::vector<double>>();
    if (r.times.ms.empty()) throw std::runtime_error("frame_ms: no frames");
    const std::string method = j.at("timing_method").get<std::string>();
    if (method == gl::to_string(gl::TimingMethod::gpu_timer)) r.times.method = gl::TimingMethod::gpu_timer;
    else if (method == gl::to_string(gl::TimingMethod::wall_finish)) r.times.method = gl::TimingMethod::wall_finish;
    else throw std::runtime_error("timing_method: '" + json_input::printable(method, 40) + "'");
    r.floor_ms = number_of_part(j.at("floor_ms"));
    r.reference_kind = j.at("reference_kind").get<std::string>();
    r.reference_resolution_texels = j.at("reference_resolution_texels").get<int>();
    r.reference_samples = j.at("reference_samples").get<int>();
    const nlohmann::json& e = j.at("error");
    r.error.pixels = e.at("pixels").get<std::int64_t>();
    r.error.channels = e.at("channels").get<int>();
    r.error.max_abs = number_of_part(e.at("max_abs"));
    r.error.mean_abs = number_of_part(e.at("mean_abs"));
    r.error.rmse = number_of_part(e.at("rmse"));
    r.error.psnr_db = number_of_part(e.at("psnr_db"));
    r.error.ssim = number_of_part(e.at("ssim"));
    r.error.threshold = number_of_part(e.at("threshold"));
    r.error.share_above_threshold = number_of_part(e.at("share_above_threshold"));
    r.s_xy = j.at("s_xy").get<float>();
    r.filter_radius_texels = j.at("filter_radius_texels").get<float>();
    r.resolution_source = j.at("resolution_source").get<std::string>();
    r.required_texels = number_of_part(j.at("required_texels"));
    r.cascades = j.at("cascades").get<int>();
    r.settings = j.at("settings").get<std::string>();
    r.c = j.at("c").get<float>();
    r.c_from = j.at("c_from").get<std::string>();
    r.work = j.at("work");
    return r;
  } catch (const std::exception& e) {
    throw std::runtime_error(file + ": payload.rows: row " + (j.is_object() && j.contains("item") ? j["item"].dump() : std::string("?")) +
                             ": " + json_input::printable(e.what(), 160));
  }
}

// The options that say where the output goes and which shard runs, not what is measured: left out
// of a part's settings and of the recorded command, which ends with the -o DIR the merge writes.
std::vector<std::string> settings_args(const std::vector<std::string>& args) {
  return shard::without_options(args, {"--shard", "--part", "--output", "-o"});
}

constexpr std::string_view kPartKind = "penumbra-bench part";

// A merge's parts, checked by shard::read_parts: the rows, the references and the device come
// from them instead of from rendering.
struct Merged {
  std::vector<shard::Part> parts;
};

std::string join(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : ",") + x;
  return s;
}

int run(const std::vector<std::string>& args, const Merged* merged);

// penumbra-bench merge PARTS... -o DIR: the parts' rows, checked, through the same Pareto marks,
// CSV, report and plots as the unsharded run (run() with the parts' own arguments).
int merge_main(int argc, char** argv) {
  CLI::App app{"Merge the part files of penumbra-bench --shard I/N --part FILE into the directory the unsharded run writes "
               "(bench.csv, report.json, plots). Every column but the frame times, and the Pareto marks drawn from them, "
               "equals the unsharded run's: times are measurements and differ run to run (docs/cluster.md)",
               "penumbra-bench merge"};
  cli::describe_tool(app, "penumbra-bench merge", "cluster.md");
  std::vector<std::string> paths;
  std::string out;
  app.add_option("parts", paths, "the part files, one per shard 0/N to N-1/N, any order")->required();
  app.add_option("-o,--output", out, "the output directory (as -o of the unsharded run)")->required()->check(cli::path_given());
  if (const auto status = cli::parse(app, argc - 1, argv + 1, "penumbra-bench merge")) return *status;
  Merged merged;
  std::vector<std::string> args;
  try {
    shard::Checked checked = shard::read_parts({paths.begin(), paths.end()}, kPartKind, tool::version_line("penumbra-bench"));
    args = shard::stored_args(checked.settings, paths.front());
    // Frame times from two devices are not one measurement: the Pareto marks would compare them.
    const std::string first = json_input::printable(checked.parts.front().path.string(), 200);
    const nlohmann::json device = checked.parts.front().payload.value("device", nlohmann::json());
    for (const shard::Part& part : checked.parts)
      if (part.payload.value("device", nlohmann::json()) != device)
        throw std::runtime_error(json_input::printable(part.path.string(), 200) + ": measured on another device than " + first + " (" +
                                 json_input::printable(part.payload.value("device", nlohmann::json()).dump(), 120) +
                                 "); frame times of two devices do not merge");
    merged.parts = std::move(checked.parts);
  } catch (const std::exception& e) {
    return cli::fail("penumbra-bench merge", e);
  }
  args.push_back("-o");
  args.push_back(out);
  return run(args, &merged);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc >= 2 && std::string_view(argv[1]) == "merge") return merge_main(argc, argv);
  return run(std::vector<std::string>(argv + 1, argv + argc), nullptr);
}

namespace {

int run(const std::vector<std::string>& args, const Merged* merged) {
  shard::Argv argv("penumbra-bench", args);
  const char* const tool_name = merged ? "penumbra-bench merge" : "penumbra-bench";
  CLI::App app{"Shadow error against frame time: every technique x resolution (x filter radius) against a ground truth; "
               "writes bench.csv, report.json and a Pareto plot per scene."};
  cli::describe_tool(app, "penumbra-bench", "bench.md");
  app.option_defaults()->always_capture_default();
  Options opt;
  std::vector<std::string> techniques_arg{"all"};
  bool quick = false, no_plot = false;
  cli::add_list_option(app, "--scenes", opt.scenes, "built-in scene names or scene files (.json), comma-separated",
                       apps::scene_items());
  cli::add_list_option(app, "--techniques", techniques_arg, "techniques of the settings table, comma-separated, or all",
                       apps::technique_items(true));
  cli::add_list_option(app, "--resolutions", opt.resolutions, "shadow-map texels per side, comma-separated", cli::integers_in(1, 65536));
  std::vector<std::string> fixed_radius;  // the techniques --radii applies to, from the registry
  for (const auto name : shadows::technique_names())
    if (shadows::technique_entry(shadows::technique_from_string(name)).radius == shadows::RadiusReading::fixed_filter)
      fixed_radius.emplace_back(name);
  cli::add_list_option(app, "--radii", opt.radii_ws,
                       "filter radii of the fixed-radius filters (" + join(fixed_radius) + "), world units, comma-separated",
                       cli::numbers_in(1e-6, 1e6));
  app.add_option("--width", opt.width, "image width in pixels")->check(CLI::Range(1, 16384));
  app.add_option("--height", opt.height, "image height in pixels")->check(CLI::Range(1, 16384));
  app.add_option("--frames", opt.frames, "timed frames per configuration (median and min/max reported)")->check(CLI::Range(1, 1000));
  app.add_option("--warmup", opt.warmup, "untimed frames before timing")->check(CLI::Range(0, 100));
  app.add_option("--area-samples", opt.reference.area_samples, "point-light samples of the area-light reference (rounded up to a square)")
      ->check(CLI::Range(1, 4096));
  app.add_option("--area-resolution", opt.reference.area_resolution_texels, "texels per side of each area-light sample's hard map")
      ->check(CLI::Range(16, 65536));
  app.add_option("--reference-resolution", opt.reference.filter_resolution_texels,
                 "texels per side of the same-filter reference (clamped to GL_MAX_TEXTURE_SIZE, with a note)")
      ->check(CLI::Range(16, 65536));
  app.add_flag("--quick", quick,
               "a few-minute run: scenes demo,two-planes, resolutions 256,1024,4096, radius 0.05, 320x180, 3 frames, "
               "16 area samples (options given explicitly still win)");
  std::string timing = "auto";
  app.add_option("--timing", timing,
                 "frame timing: auto (GL timer queries on a GPU, wall clock around glFinish on software GL) or "
                 "wall_finish (the wall clock on every device, e.g. to set a GPU's wall time beside its gpu_timer run)")
      ->check(CLI::IsMember({"auto", "wall_finish"}));
  bool no_adaptive = false;
  app.add_flag("--no-adaptive", no_adaptive, "skip the adaptive rows (one per fixed-filter radius and for PCSS; --adaptive.* sets the rule)");
  bool no_virtual = false;
  app.add_flag("--no-virtual", no_virtual,
               "skip the virtual shadow map rows (pages marked by the rule and by the footprint, drawn every frame), which a scene "
               "lit by the sun gets for vsm, box pcf (--pcf.kernel grid) and pcss with --pcss.kernel grid");
  app.add_flag("--no-plot", no_plot, "skip the plots (no Python needed)");
  app.add_option("--python", opt.python, "Python with matplotlib that draws the plots");
  app.add_option("--plot-script", opt.plot_script, "the plotting script");
  app.add_option("-o,--output", opt.output, "output directory (replaced as a whole when the run succeeds)")->check(cli::path_given());
  std::string shard_text, part_out;
  app.add_option("--shard", shard_text,
                 "I/N: measure only shard I of N (0 <= I < N) of the rows, every row whose number in the loop order (scene, "
                 "variant, row of the variant) is I modulo N, into --part instead of -o; `penumbra-bench merge PARTS... -o DIR` "
                 "writes what the unsharded run writes, frame times apart (measurements differ run to run; docs/cluster.md)");
  app.add_option("--part", part_out, "--shard: the part file to write (the shard's rows, its settings, the device and the build's version)");
  apps::add_calibration_option(app, opt.calibration);
  apps::add_settings_options(app, opt.base);

  try {
    app.parse(argv.argc(), argv.argv());
    if (quick) {
      auto preset = [&](const char* option, auto& target, auto value) {
        if (app.count(option) == 0) target = value;
      };
      preset("--scenes", opt.scenes, std::vector<std::string>{"demo", "two-planes"});
      preset("--resolutions", opt.resolutions, std::vector<int>{256, 1024, 4096});
      preset("--radii", opt.radii_ws, std::vector<double>{0.05});
      preset("--width", opt.width, 320);
      preset("--height", opt.height, 180);
      preset("--frames", opt.frames, 3);
      preset("--area-samples", opt.reference.area_samples, 16);
    }
    opt.plot = !no_plot;
    opt.adaptive = !no_adaptive;
    opt.virtual_map = !no_virtual;
    const bool all_techniques = techniques_arg == std::vector<std::string>{"all"};
    if (!all_techniques) {
      opt.techniques = techniques_arg;
      for (const auto& t : opt.techniques) {
        try {
          shadows::technique_from_string(t);
        } catch (const std::invalid_argument& e) {
          throw CLI::ValidationError("--techniques", e.what());
        }
      }
    }
    if (apps::setting_stands_for(app, "--map.resolution_texels", "--resolutions")) opt.resolutions = {opt.base.map.resolution_texels};
    if (!all_techniques) {
      std::vector<shadows::Technique> rendered;
      for (const auto& t : opt.techniques) rendered.push_back(shadows::technique_from_string(t));
      apps::refuse_unused_technique_options(app, rendered, "--techniques " + join(opt.techniques));
    }
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);  // --help, --version
    return cli::fail(tool_name, e.what(), cli::kExitUsage);
  }
  std::optional<shard::Shard> sharded;
  try {
    if (!shard_text.empty()) {
      sharded = shard::parse(shard_text);
      if (part_out.empty()) throw cli::UsageError("--shard: needs --part FILE, where the shard's rows go");
      if (!opt.output.empty())
        throw cli::UsageError("--output: a shard writes a part (--part); `penumbra-bench merge PARTS... -o DIR` writes the directory");
      io::check_output(part_out, io::OutputKind::file);
    } else if (!part_out.empty()) {
      throw cli::UsageError("--part: only with --shard I/N");
    } else if (opt.output.empty()) {
      throw cli::UsageError("--output is required (or --shard I/N --part FILE)");
    }
  } catch (const std::exception& e) {
    return cli::fail(tool_name, e);
  }

  try {
    const auto started = std::chrono::steady_clock::now();
    auto elapsed_s = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count(); };
    // Calibration and scenes first: a bad file or name is refused before any GL work.
    apps::apply_calibration(app, opt.calibration, opt.base);
    std::vector<scene::Scene> scenes;
    for (const auto& name : opt.scenes) scenes.push_back(scene::load_scene(name));
    const bool plots = opt.plot && !sharded;  // a shard writes its part alone; the merge plots
    if (plots) apps::check_python(opt.python, opt.plot_script, "the plots");

    // The device: this one, or for a merge the one the parts were measured on (merge_main
    // checked that they share it).
    std::optional<gl::HeadlessContext> context;
    nlohmann::json device;
    bool gpu = false;
    std::string renderer_name;
    if (!merged) {
      context.emplace();
      const gl::ContextInfo& ctx = context->info();
      for (int r : opt.resolutions)
        if (r > ctx.max_texture_size)
          throw std::runtime_error("--resolutions " + std::to_string(r) + " exceeds this device's GL_MAX_TEXTURE_SIZE " +
                                   std::to_string(ctx.max_texture_size));
      device = ctx;
      gpu = !ctx.software && timing == "auto";
      renderer_name = ctx.renderer;
    } else {
      const nlohmann::json& payload = merged->parts.front().payload;
      device = payload.value("device", nlohmann::json());
      gpu = payload.value("timing_method", "") == std::string("gpu_timer");
      renderer_name = device.is_object() ? device.value("renderer", "") : "";
    }

    const std::vector<Variant> variants = make_variants(opt);
    {
      // The c each technique's adaptive rows use, where it came from and what the fitter flagged.
      std::vector<std::string> c_lines;
      for (const Variant& v : variants)
        if (const std::string line = apps::calibration_line(opt.calibration, v.settings);
            std::find(c_lines.begin(), c_lines.end(), line) == c_lines.end()) {
          c_lines.push_back(line);
          std::printf("%s\n", line.c_str());
        }
    }
    int adaptive_variants = 0, virtual_rows = 0;
    for (const auto& v : variants) adaptive_variants += opt.adaptive && has_rule_radius(v);
    for (const auto& scene : scenes)
      for (const auto& v : variants) virtual_rows += opt.virtual_map && reads_pages(v, scene) ? 2 : 0;
    const int total_rows =
        static_cast<int>(scenes.size() * (variants.size() * opt.resolutions.size() + static_cast<std::size_t>(adaptive_variants))) +
        virtual_rows;
    const auto row_count = static_cast<std::size_t>(total_rows);
    // The rows each shard's part owes, by number; the merge takes each from the one part that covers it.
    auto rows_of_shard = [&](const shard::Shard& sh) { return row_count / sh.count + (sh.index < row_count % sh.count ? 1 : 0); };
    std::vector<const nlohmann::json*> merged_rows(merged ? row_count : 0, nullptr);
    std::vector<std::string> merged_row_file(merged_rows.size());
    if (merged) {
      for (const shard::Part& part : merged->parts) {
        const std::string file = json_input::printable(part.path.string(), 200);
        static const nlohmann::json none;  // (both branches lvalues: the rows are pointed into, not copied)
        const nlohmann::json& part_rows = part.payload.contains("rows") ? part.payload["rows"] : none;
        if (part.payload.value("items", nlohmann::json()) != nlohmann::json(row_count) || !part_rows.is_array() ||
            !part.payload.contains("scenes") || !part.payload["scenes"].is_array() || part.payload["scenes"].size() != scenes.size())
          throw std::runtime_error(file + ": payload: not a part of this grid of " + std::to_string(row_count) + " rows");
        if (part_rows.size() != rows_of_shard(part.shard))
          throw std::runtime_error(file + ": payload.rows: " + std::to_string(part_rows.size()) + " rows, shard " + part.shard.text() +
                                   " of " + std::to_string(row_count) + " rows has " + std::to_string(rows_of_shard(part.shard)));
        for (const nlohmann::json& row : part_rows) {
          const nlohmann::json item = row.is_object() ? row.value("item", nlohmann::json()) : nlohmann::json();
          if (!item.is_number_unsigned() || item.get<std::size_t>() >= row_count || !part.shard.covers(item.get<std::size_t>()) ||
              merged_rows[item.get<std::size_t>()])
            throw std::runtime_error(file + ": payload.rows: row " + item.dump() + " is not one of shard " + part.shard.text() + "'s");
          merged_rows[item.get<std::size_t>()] = &row;
          merged_row_file[item.get<std::size_t>()] = file;
        }
      }
    }
    std::optional<io::StagedDirectory> out;
    if (!sharded) out.emplace(opt.output, "report.json");
    std::fprintf(stderr,
                 "%s: %zu scenes x (%zu variants x %zu resolutions + %d adaptive) + %d virtual = %d rows at %dx%d, "
                 "%d frames each, on %s (%s)%s\n",
                 tool_name, scenes.size(), variants.size(), opt.resolutions.size(), adaptive_variants, virtual_rows, total_rows, opt.width,
                 opt.height, opt.frames, renderer_name.c_str(), gpu ? "gpu_timer" : "wall_finish",
                 sharded ? (", shard " + sharded->text() + ": " + std::to_string(rows_of_shard(*sharded)) + " of them").c_str()
                         : merged ? (", merged from " + std::to_string(merged->parts.size()) + " parts").c_str() : "");

    std::vector<Row> rows;
    std::vector<std::unique_ptr<metrics::Reference>> references;
    nlohmann::json scene_reports = nlohmann::json::array();
    std::optional<shadows::Renderer> renderer;  // a merge renders nothing
    if (!merged) {
      renderer.emplace();
      renderer->set_count_work(true);  // each row's work per pass (report.json)
    }
    int done = 0;
    std::size_t item = 0;  // the next row's number in the loop order: its shard
    for (std::size_t scene_index = 0; scene_index < scenes.size(); ++scene_index) {
      const scene::Scene& scene = scenes[scene_index];
      shadows::FrameInfo info;
      FrameTimes floor;
      nlohmann::json scene_report;
      if (merged) {  // the floor as shard 0 measured it (every shard measures every scene's); the references below
        scene_report = merged->parts.front().payload["scenes"][scene_index];
        if (!scene_report.is_object() || scene_report.value("scene", "") != scene.name)
          throw std::runtime_error(json_input::printable(merged->parts.front().path.string(), 200) + ": payload.scenes: not " + scene.name);
        scene_report["references"] = nlohmann::json::array();
      } else {
        renderer->set_scene(scene);
        floor = time_frames(*renderer, shadows::unshadowed_floor(opt.base), opt.width, opt.height, opt.warmup, opt.frames, gpu, info);
        std::fprintf(stderr, "[%6.1f s] %s: unshadowed floor %.2f ms\n", elapsed_s(), scene.name.c_str(), floor.median());
        scene_report = {{"scene", scene.name},
                        {"floor_ms", {{"median", floor.median()}, {"min", floor.min()}, {"max", floor.max()}}},
                        {"floor_method", "hard shadows from a 1x1 unfitted map (one lookup per pixel)"},
                        {"references", nlohmann::json::array()}};
      }
      std::map<std::string, const metrics::Reference*> area_reference;  // one per scene: it does not depend on the technique
      std::set<std::string> merged_references;                          // the reference keys a merge has listed
      for (std::size_t variant_index = 0; variant_index < variants.size(); ++variant_index) {
        const Variant& v = variants[variant_index];
        const bool area = metrics::reference_kind(v.technique) == metrics::ReferenceKind::area_light;
        // The reference's key in a part: the variant that made it, or "area" for the scene's one
        // area-light reference (made by whichever area-light variant a shard measures first).
        const std::string reference_key = area ? "area" : std::to_string(variant_index);
        const std::size_t variant_rows = opt.resolutions.size() + (opt.adaptive && has_rule_radius(v) ? 1 : 0) +
                                         (opt.virtual_map && reads_pages(v, scene) ? 2 : 0);
        if (sharded) {  // a variant none of whose rows is this shard's costs no reference
          bool any = false;
          for (std::size_t k = item; k < item + variant_rows; ++k) any = any || sharded->covers(k);
          if (!any) {
            item += variant_rows;
            continue;
          }
        }
        if (merged) {
          if (merged_references.insert(reference_key).second) {
            nlohmann::json entry;
            for (const shard::Part& part : merged->parts)  // the lowest shard that made it
              for (const nlohmann::json& e : part.payload["scenes"][scene_index].value("references", nlohmann::json::array()))
                if (entry.is_null() && e.is_object() && e.value("key", "") == reference_key) entry = e;
            if (entry.is_null())
              throw std::runtime_error("no part has " + scene.name + "'s reference for " + v.label + " (" +
                                       json_input::printable(merged->parts.front().path.string(), 200) + ", ...)");
            entry.erase("key");
            scene_report["references"].push_back(entry);
          }
          for (std::size_t k = 0; k < variant_rows; ++k, ++item) {
            Row row = row_of_part(*merged_rows[item], merged_row_file[item]);
            if (row.scene != scene.name || row.variant != v.label)
              throw std::runtime_error(merged_row_file[item] + ": payload.rows: row " + std::to_string(item) + " is " + row.scene + ", " +
                                       row.variant + ", not " + scene.name + ", " + v.label);
            rows.push_back(std::move(row));
          }
          continue;
        }
        const metrics::Reference* ref = nullptr;
        if (area && area_reference.count(scene.name)) {
          ref = area_reference[scene.name];
        } else {
          std::fprintf(stderr, "[%6.1f s] %s: reference for %s (%s)...\n", elapsed_s(), scene.name.c_str(), v.label.c_str(),
                       area ? "area-light average" : "same filter, high resolution");
          references.push_back(std::make_unique<metrics::Reference>(
              metrics::make_reference(*renderer, v.settings, opt.width, opt.height, opt.reference)));
          ref = references.back().get();
          if (area) area_reference[scene.name] = ref;
          if (!ref->note.empty()) std::fprintf(stderr, "  note: %s\n", ref->note.c_str());
          scene_report["references"].push_back({{"for", area ? "every area-light technique" : v.label},
                                                {"kind", metrics::to_string(ref->kind)},
                                                {"resolution_texels", ref->resolution_texels},
                                                {"samples", ref->samples},
                                                {"description", ref->description},
                                                {"note", ref->note},
                                                {"render_ms", ref->render_ms}});
          if (sharded) scene_report["references"].back()["key"] = reference_key;
        }
        // The next row of the variant, measured when it is this shard's (always, unsharded).
        auto measure = [&](const shadows::ShadowSettings& s, int warmup) {
          const std::size_t number = item++;
          if (sharded && !sharded->covers(number)) return;
          Row row{number, scene.name, v.technique, v.label, v.radius_ws, s.map.resolution_texels};
          row.times = time_frames(*renderer, s, opt.width, opt.height, warmup, opt.frames, gpu, info);
          row.floor_ms = floor.median();
          row.reference_kind = metrics::to_string(ref->kind);
          row.reference_resolution_texels = ref->resolution_texels;
          row.reference_samples = ref->samples;
          row.error = metrics::compare(ref->visibility, renderer->read_visibility());
          row.s_xy = info.light.s_xy;
          row.filter_radius_texels = info.filter_radius_texels;
          row.resolution_texels = info.resolution_texels;
          row.adaptive = info.adaptive;
          row.resolution_source = info.resolution_source;
          row.cascades = static_cast<int>(info.cascades.size());
          if (info.adaptive && !info.cascades.empty()) row.required_texels = info.cascades.front().required_texels;
          row.memory_texels = shadows::shadow_memory_texels(info);
          row.work = shadows::work_json(info.work);
          // What the shading's shadow lookups read per pixel shown (a counting draw of the last
          // timed frame, untimed; docs/gpu.md's cost model reads it).
          const shadows::ShadowReads reads = renderer->count_shading_reads();
          row.work["shading_reads"] = {{"pixels", reads.pixels},
                                       {"instructions_per_pixel", reads.per_pixel(reads.instructions)},
                                       {"texels_per_pixel", reads.per_pixel(reads.texels)},
                                       {"bytes_per_pixel", reads.per_pixel(reads.bytes)}};
          if (info.virtual_map) {
            // A pool that missed pages shades their pixels from a coarser level: that speed is not
            // the configuration's, and the row is refused rather than reported.
            if (const std::string w = shadows::missing_pages_warning(info.virtual_map->pages, info.virtual_map->pool_pages_per_side);
                !w.empty())
              throw std::runtime_error(scene.name + ", " + v.label + ", " + info.resolution_source + ": not timed: " + w.substr(w.find(": ") + 2));
            row.virtual_pages = info.resolution_source.substr(info.resolution_source.find('_') + 1);  // virtual_rule: rule
            row.resolution_texels = 0;
            row.cascades = 0;
            row.pages_resident = info.virtual_map->pages.resident;
          }
          row.settings = shadows::describe(s);
          row.c = s.adaptive.c;
          row.c_from = opt.calibration.source_of_c(s);
          ++done;
          const int of = sharded ? static_cast<int>(rows_of_shard(*sharded)) : total_rows;
          const std::string size = row.virtual_pages.empty() ? (row.adaptive ? "adaptive " : "") + std::to_string(row.resolution_texels) + "^2"
                                                             : "virtual " + row.virtual_pages + " " + std::to_string(row.pages_resident) + "p";
          std::fprintf(stderr, "[%6.1f s] %d/%d %s %s %s: %.2f ms, mean abs %.5f, max %.3f, SSIM %.4f\n", elapsed_s(), done,
                       of, scene.name.c_str(), v.label.c_str(), size.c_str(), row.times.median(), row.error.mean_abs,
                       row.error.max_abs, row.error.ssim);
          rows.push_back(std::move(row));
        };
        for (int res : opt.resolutions) {
          shadows::ShadowSettings s = v.settings;
          s.map.resolution_texels = res;
          measure(s, opt.warmup);
        }
        if (opt.adaptive && has_rule_radius(v)) {
          // The rule's resolution for this filter, in steady state: a fresh controller grows at
          // once, and a PCSS per-pixel requirement (measured one frame late) may then shrink it
          // after adaptive.shrink_delay_frames frames; the warmup covers both.
          shadows::ShadowSettings s = v.settings;
          s.adaptive.enabled = true;
          renderer->reset_adaptive();
          measure(s, std::max(opt.warmup, s.adaptive.shrink_delay_frames + 2));
        }
        if (opt.virtual_map && reads_pages(v, scene))
          for (const shadows::VirtualPages marking : {shadows::VirtualPages::rule, shadows::VirtualPages::footprint}) {
            // Every page drawn each frame: the work of a frame whose view is new (a cache would
            // draw nothing in a still view).
            shadows::ShadowSettings s = v.settings;
            s.map.virtual_pages = marking;
            s.map.virtual_cache = false;
            measure(s, opt.warmup);
          }
      }
      scene_reports.push_back(scene_report);
    }
    if (sharded) {  // the settings are the arguments themselves: the merge parses them again
      nlohmann::json part_rows = nlohmann::json::array();
      for (const Row& r : rows) part_rows.push_back(row_part(r));
      const nlohmann::json payload = {{"items", row_count},        {"device", device}, {"timing_method", gpu ? "gpu_timer" : "wall_finish"},
                                      {"scenes", scene_reports}, {"rows", part_rows}, {"elapsed_s", elapsed_s()}};
      io::write_file_atomic(part_out, shard::part_text(kPartKind, tool::version_line("penumbra-bench"), *sharded,
                                                       {{"args", settings_args(args)}}, payload));
      std::printf("wrote %s: shard %s, %zu of %d rows\n", part_out.c_str(), sharded->text().c_str(), rows.size(), total_rows);
      return 0;
    }
    mark_pareto(rows);
    int adaptive_rows = 0, on_front = 0, on_spread_front = 0;
    for (const auto& r : rows)
      if (r.adaptive) ++adaptive_rows, on_front += r.pareto, on_spread_front += r.pareto_spread;
    int virtual_on_front = 0, virtual_on_spread_front = 0;
    for (const auto& r : rows)
      if (!r.virtual_pages.empty()) virtual_on_front += r.pareto, virtual_on_spread_front += r.pareto_spread;

    const fs::path& dir = out->path();
    std::string csv = std::string(kCsvHeader) + "\n";
    for (const auto& r : rows) csv += csv_row(r, opt) + "\n";
    io::write_file_atomic(dir / "bench.csv", csv);

    // The c each technique's adaptive rows used and where it came from, keyed by technique.
    nlohmann::json calibration_per_technique = nlohmann::json::object();
    for (const Variant& v : variants) calibration_per_technique[v.technique] = apps::calibration_json(opt.calibration, v.settings);
    // The command without where its output went, then -o: the same for a merge of shards.
    std::ostringstream command;
    command << "penumbra-bench";
    for (const std::string& a : settings_args(args)) command << ' ' << a;
    command << " -o " << opt.output;
    nlohmann::json report = {
        {"tool", "penumbra-bench"},
        {"command", command.str()},
        {"device", device},
        {"timing_method", gpu ? "gpu_timer" : "wall_finish"},
        {"image_px", {opt.width, opt.height}},
        {"frames", opt.frames},
        {"warmup", opt.warmup},
        {"resolutions", opt.resolutions},
        {"radii_ws", opt.radii_ws},
        {"calibration", apps::calibration_json(opt.calibration, opt.base)},
        {"calibration_per_technique", calibration_per_technique},
        {"reference", {{"area_samples", opt.reference.area_samples},
                       {"area_resolution_texels", opt.reference.area_resolution_texels},
                       {"filter_resolution_texels", opt.reference.filter_resolution_texels}}},
        {"error_metric_for_pareto", "mean_abs (visibility, whole image)"},
        {"adaptive_on_front", {{"rows", adaptive_rows}, {"pareto", on_front}, {"pareto_spread", on_spread_front}}},
        {"virtual_on_front", {{"rows", virtual_rows}, {"pareto", virtual_on_front}, {"pareto_spread", virtual_on_spread_front}}},
        {"scenes", scene_reports},
        {"rows", nlohmann::json::array()}};
    for (const auto& r : rows) report["rows"].push_back(row_json(r));
    if (plots) {
      std::fprintf(stderr, "[%6.1f s] plotting...\n", elapsed_s());
      apps::run_python_script(opt.python, opt.plot_script, {(dir / "bench.csv").string(), dir.string()}, "the plots");
    }
    // A merge's elapsed_s is the parts' summed: the work the rows took, not the merge's second.
    double parts_s = 0;
    if (merged)
      for (const shard::Part& part : merged->parts) parts_s += part.payload.value("elapsed_s", 0.0);
    report["elapsed_s"] = merged ? parts_s : elapsed_s();
    io::write_file_atomic(dir / "report.json", json_input::dump(report, 2) + "\n");
    out->commit();
    std::fprintf(stderr, "[%6.1f s] done\n", elapsed_s());
    if (adaptive_rows > 0)
      std::cout << "adaptive rows on their variant's Pareto front: " << on_front << " of " << adaptive_rows << " (medians), "
                << on_spread_front << " of " << adaptive_rows << " (frame-time spreads that overlap are ties)\n";
    if (virtual_rows > 0)
      std::cout << "virtual map rows on their variant's Pareto front: " << virtual_on_front << " of " << virtual_rows << " (medians), "
                << virtual_on_spread_front << " of " << virtual_rows << " (spreads as ties)\n";
    std::cout << "wrote " << out->target().string() << "/ (" << rows.size() << " rows)\n";
    return 0;
  } catch (const std::exception& e) {
    return cli::fail(tool_name, e);
  }
}

}  // namespace
