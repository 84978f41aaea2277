// penumbra-render as a user runs it: a good run writes images and a report; every bad input is
// refused with exit status ≠ 0 and exactly one line on stderr naming what was wrong, and leaves no
// output (not even a staging directory) behind; an existing directory is replaced only when it is
// a previous penumbra-render output.
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <set>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "adaptive/calibration.h"
#include "shadows/settings.h"
#include "shadows/technique.h"
#include <nlohmann/json.hpp>

#include "io/image_io.h"
#include "subprocess.h"

namespace fs = std::filesystem;
using ::testing::HasSubstr;

namespace {

using penumbra::test::read_file;
using penumbra::test::Result;

Result run_render(const std::vector<std::string>& args, const fs::path& scratch) {
  return penumbra::test::run_exe(PENUMBRA_RENDER_EXE, args, scratch);
}

const std::vector<std::string> kSmall = {"--width", "64", "--height", "48", "--resolution", "64",
                                         "--frames", "1", "--warmup", "0"};

std::vector<std::string> small_args(std::vector<std::string> extra) {
  std::vector<std::string> args = kSmall;
  args.insert(args.end(), extra.begin(), extra.end());
  return args;
}

// Names under `dir` (one level), sorted.
std::set<std::string> listing(const fs::path& dir) {
  std::set<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.insert(e.path().filename().string());
  return names;
}

// Number of lines in `text`, a trailing newline not opening another one.
int line_count(const std::string& text) {
  if (text.empty()) return 0;
  const auto n = static_cast<int>(std::count(text.begin(), text.end(), '\n'));
  return text.back() == '\n' ? n : n + 1;
}

nlohmann::json read_json(const fs::path& p) {
  std::ifstream in(p);
  return nlohmann::json::parse(in);
}

class RenderCli : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = std::string(info->test_suite_name()) + "-" + info->name();
    std::replace(name.begin(), name.end(), '/', '_');
    tmp_ = fs::temp_directory_path() / ("penumbra-cli-" + name + "-" + std::to_string(::getpid()));
    fs::remove_all(tmp_);
    fs::create_directories(tmp_);
    scratch_ = tmp_ / "scratch";
    fs::create_directories(scratch_);
    work_ = tmp_ / "work";  // the only things here are what the test or penumbra-render put here
    fs::create_directories(work_);
  }
  void TearDown() override {
    std::error_code ec;
    if (!HasFailure()) fs::remove_all(tmp_, ec);
  }

  // Checks what every refused run must do: status ≠ 0, one line on stderr that contains each of
  // `needles`, nothing new in the work folder (no output, no `*.partial-*` staging directory).
  void expect_refused(const std::vector<std::string>& args, const std::vector<std::string>& needles) {
    const auto before = listing(work_);
    const Result r = run_render(args, scratch_);
    EXPECT_NE(r.exit_code, 0) << r.err;
    EXPECT_NE(r.exit_code, -1) << "killed by a signal";
    EXPECT_EQ(line_count(r.err), 1) << "stderr:\n" << r.err;
    for (const auto& n : needles) EXPECT_THAT(r.err, HasSubstr(n));
    EXPECT_EQ(listing(work_), before) << "a refused run changed " << work_;
    EXPECT_FALSE(fs::exists(work_ / "out"));
  }

  fs::path tmp_, scratch_, work_;
};

// The one render of a single-technique, single-resolution run, as listed by the summary report.
fs::path only_render_dir(const fs::path& out) {
  const auto summary = read_json(out / "report.json");
  const auto& renders = summary.at("renders");
  EXPECT_EQ(renders.size(), 1u) << summary.dump(2);
  return out / renders.at(0).at("name").get<std::string>();
}

void expect_render_files(const fs::path& dir, const std::vector<std::string>& passes) {
  SCOPED_TRACE(dir.string());
  ASSERT_TRUE(fs::is_regular_file(dir / "lit.png"));
  ASSERT_TRUE(fs::is_regular_file(dir / "visibility.exr"));
  ASSERT_TRUE(fs::is_regular_file(dir / "report.json"));

  const auto lit = penumbra::io::read_image8(dir / "lit.png");
  EXPECT_EQ(lit.width, 64);
  EXPECT_EQ(lit.height, 48);
  const auto vis = penumbra::io::read_imagef(dir / "visibility.exr");
  ASSERT_EQ(vis.width, 64);
  ASSERT_EQ(vis.height, 48);
  ASSERT_EQ(vis.channels, 1);
  const auto [lo, hi] = std::minmax_element(vis.pixels.begin(), vis.pixels.end());
  for (float v : vis.pixels) ASSERT_TRUE(std::isfinite(v) && v >= 0.0f && v <= 1.0f) << v;
  EXPECT_LT(*lo, 0.5f) << "the demo scene has shadows";
  EXPECT_GT(*hi, 0.5f) << "the demo scene has lit receivers";

  const auto report = read_json(dir / "report.json");
  EXPECT_EQ(report.at("resolution_texels"), 64);
  EXPECT_EQ(report.at("image_px"), nlohmann::json({64, 48}));
  EXPECT_EQ(report.at("passes_run").get<std::vector<std::string>>(), passes);
  const double s_xy = report.at("light").at("s_xy").get<double>();
  EXPECT_TRUE(std::isfinite(s_xy) && s_xy > 0) << s_xy;
  // Wall clock around glFinish is recorded on every device (and is all there is on llvmpipe),
  // once per pass run.
  std::vector<std::string> wall_passes;
  for (const auto& t : report.at("timings")) {
    if (t.at("method") != "wall_finish") continue;
    wall_passes.push_back(t.at("pass").get<std::string>());
    EXPECT_GE(t.at("median_ms").get<double>(), 0.0);
    EXPECT_LE(t.at("min_ms").get<double>(), t.at("max_ms").get<double>());
  }
  EXPECT_EQ(wall_passes, passes) << report.at("timings").dump(2);
}

}  // namespace

TEST_F(RenderCli, GoodRunWritesImagesAndReport) {
  const fs::path out = work_ / "out";
  const Result r = run_render(small_args({"--technique", "pcf", "-o", out.string()}), scratch_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err, "") << "a good run prints nothing on stderr when it is not a terminal";
  EXPECT_THAT(r.out, HasSubstr("pcf-disk")) << "PCF's default kernel: the one the study's configs draw (issue 44)";
  expect_render_files(only_render_dir(out), {"shadow_map", "depth_prepass", "shading"});
  EXPECT_EQ(listing(work_), std::set<std::string>{"out"}) << "no staging directory left";
}

// --virtual-debug: the sun's virtual shadow map for the view, beside the render: the level per
// pixel by the rule and by the footprint, the pool with the pages drawn for this view and those
// kept from the previous path frame; the rule never asks for more pages than the footprint. A spot
// light, or PCF with a radius in texels, is refused before anything is rendered.
TEST_F(RenderCli, VirtualDebugWritesTheLevelsAndThePool) {
  const fs::path out = work_ / "out";
  const Result r = run_render({"--scene", "outdoor", "--path-frame", "120", "--width", "160", "--height", "90", "--resolution", "256",
                               "--frames", "1", "--warmup", "0", "--virtual-debug", "--pcf.radius_unit", "world", "--pcf.radius", "0.12",
                               "-o", out.string()},
                              scratch_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("virtual shadow map: "));
  const auto levels = penumbra::io::read_image8(out / "virtual-levels.png");
  EXPECT_EQ(levels.width, 2 * 160);
  const auto pool = penumbra::io::read_image8(out / "virtual-pool.png");
  EXPECT_EQ(pool.width, 1024);
  const auto v = nlohmann::json::parse(read_file(out / "report.json")).at("virtual_debug");
  EXPECT_GT(v.at("pages_rule").get<int>(), 0);
  EXPECT_LE(v.at("pages_rule").get<int>(), v.at("pages_footprint").get<int>());
  EXPECT_EQ(v.at("drawn").get<int>() + v.at("cached").get<int>() + v.at("missing").get<int>(), v.at("pages_rule").get<int>());
  EXPECT_GT(v.at("cached").get<int>(), 0) << "the previous path frame's pages are kept";

  // PCSS: the debug view marks in the renderer's two rounds (each pixel's search, then the
  // penumbra it finds), so its rule asks for the pages the renderer's frame asked for (the surface
  // comes from another pass: a few pixels may differ), and fewer than the footprint; marking every
  // pixel at the minimum penumbra (the views' first way) asked for as many as the footprint, 117.
  const fs::path pcss = work_ / "pcss";
  const Result rp = run_render({"--scene", "outdoor", "--path-frame", "120", "--width", "480", "--height", "270", "--technique", "pcss",
                                "--pcss.kernel", "grid", "--map.virtual_pages", "rule", "--frames", "1", "--warmup", "0",
                                "--virtual-debug", "-o", pcss.string()},
                               scratch_);
  ASSERT_EQ(rp.exit_code, 0) << rp.err;
  const auto debug = nlohmann::json::parse(read_file(pcss / "report.json")).at("virtual_debug");
  const int asked = nlohmann::json::parse(read_file(pcss / "pcss" / "report.json")).at("virtual_map").at("pages").at("requested");
  const int rule = debug.at("pages_rule");
  EXPECT_GT(asked, 50);
  EXPECT_NEAR(rule, asked, 0.1 * asked) << "the debug view marks as the renderer does";
  EXPECT_LT(rule, debug.at("pages_footprint").get<int>());

  for (const auto& [args, why] : std::vector<std::pair<std::vector<std::string>, std::string>>{
           {{"--scene", "outdoor-spot", "--virtual-debug"}, "--virtual-debug: the virtual shadow map is the sun's"},
           {{"--scene", "outdoor", "--virtual-debug", "--pcf.radius_unit", "texels"}, "--virtual-debug: pcf marks pages by a world radius"},
           {{"--scene", "outdoor", "--virtual-debug", "--technique", "vsm"}, "--virtual-debug: vsm marks pages by a world radius"},
           {{"--scene", "outdoor", "--virtual-debug", "--technique", "msm"}, "--virtual-debug: pages are marked for pcf, pcss or vsm, not msm"}}) {
    std::vector<std::string> with_output = args;
    with_output.insert(with_output.end(), {"-o", (work_ / "refused").string()});
    const Result bad = run_render(small_args(with_output), scratch_);
    EXPECT_EQ(bad.exit_code, 2) << bad.err;
    EXPECT_THAT(bad.err, HasSubstr(why));
    EXPECT_EQ(line_count(bad.err), 1) << bad.err;
    EXPECT_FALSE(fs::exists(work_ / "refused"));
  }
}

TEST_F(RenderCli, AllTechniquesWriteEveryRenderMontageAndSummary) {
  const fs::path out = work_ / "out";
  const Result r = run_render(small_args({"--technique", "all", "-o", out.string()}), scratch_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // What `--technique all` renders, from the registry (a new technique needs no edit here): one
  // render per technique, one per choice of its variant setting (pcf-grid, pcf-poisson, pcf-disk);
  // the passes a filtered-moments technique runs include the blur; a screen-space technique's post
  // passes are its own, listed here.
  const std::map<std::string, std::vector<std::string>> screen_space = {
      {"edtsm", {"shadow_map", "gbuffer", "sites", "edt", "edt_penumbra", "mean_filter", "shading"}},
      {"edtssm", {"shadow_map", "gbuffer", "sites", "edt", "edt_penumbra", "mean_filter", "shading"}},
      {"erosion", {"shadow_map", "gbuffer", "edges", "erosion_minmax", "erosion", "shading"}}};
  std::set<std::string> renders;
  std::map<std::string, std::vector<std::string>> passes;
  for (const std::string_view name : penumbra::shadows::technique_names()) {
    const penumbra::shadows::Technique t = penumbra::shadows::technique_from_string(name);
    const auto& entry = penumbra::shadows::technique_entry(t);
    penumbra::shadows::ShadowSettings settings;
    settings.technique = t;
    std::vector<std::string> run = {"shadow_map", "depth_prepass", "shading"};  // the camera's depth first (map.depth_prepass)
    if (entry.post) {
      ASSERT_TRUE(screen_space.contains(std::string(name))) << name << ": a screen-space technique; list its passes above";
      run = screen_space.at(std::string(name));
    } else if (entry.moments && entry.moments(settings)) {
      run = {"shadow_map", "vsm_blur", "depth_prepass", "shading"};
    }
    std::vector<std::string> names;
    for (const std::string& choice : penumbra::shadows::variant_choices(t)) names.push_back(std::string(name) + "-" + choice);
    if (names.empty()) names.emplace_back(name);
    for (const auto& n : names) {
      renders.insert(n);
      passes[n] = run;
    }
  }
  EXPECT_GE(renders.size(), 14u) << "every technique of the registry, PCF once per kernel";
  std::set<std::string> expected = renders;
  expected.insert({"montage.png", "report.json"});
  EXPECT_EQ(listing(out), expected);
  for (const auto& name : renders) expect_render_files(out / name, passes.at(name));
  const auto montage = penumbra::io::read_image8(out / "montage.png");
  EXPECT_GT(montage.width, 0);
  EXPECT_GT(montage.height, 0);
  const auto summary = read_json(out / "report.json");
  std::set<std::string> listed;
  for (const auto& render : summary.at("renders")) {
    listed.insert(render.at("name").get<std::string>());
    EXPECT_EQ(render.at("resolution_texels"), 64);
    EXPECT_FALSE(render.at("timings").empty());
  }
  EXPECT_EQ(listed, renders);
  EXPECT_EQ(listing(work_), std::set<std::string>{"out"});
}

TEST_F(RenderCli, PreviousOutputIsReplacedOnSuccess) {
  const fs::path out = work_ / "out";
  ASSERT_EQ(run_render(small_args({"--technique", "pcf", "-o", out.string()}), scratch_).exit_code, 0);
  std::ofstream(out / "stale.txt") << "from an older run\n";
  const Result r = run_render(small_args({"--technique", "hard", "-o", out.string()}), scratch_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(listing(out), (std::set<std::string>{"hard", "report.json"}));
  EXPECT_EQ(listing(work_), std::set<std::string>{"out"});
}

TEST_F(RenderCli, PreviousOutputIsKeptWhenARunFails) {
  const fs::path out = work_ / "out";
  ASSERT_EQ(run_render(small_args({"--technique", "pcf", "-o", out.string()}), scratch_).exit_code, 0);
  const auto before = listing(out);
  const std::string report_before = read_file(out / "report.json");
  const Result r = run_render(small_args({"--technique", "hard", "--resolution", "65536", "-o", out.string()}), scratch_);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_EQ(line_count(r.err), 1) << r.err;
  EXPECT_EQ(listing(out), before);
  EXPECT_EQ(read_file(out / "report.json"), report_before);
  EXPECT_EQ(listing(work_), std::set<std::string>{"out"}) << "no staging directory left";
}

// "-o out/" names the same directory as "-o out": the staging directory lands beside it (not
// inside, where replacing the output would delete it) and the previous output is replaced.
TEST_F(RenderCli, OutputWithTrailingSlashIsReplacedOnSuccess) {
  const fs::path out = work_ / "out";
  ASSERT_EQ(run_render(small_args({"--technique", "hard", "-o", out.string()}), scratch_).exit_code, 0);
  const Result r = run_render(small_args({"--technique", "pcf", "--pcf.kernel", "poisson", "-o", out.string() + "/"}), scratch_);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(listing(out), (std::set<std::string>{"pcf-poisson", "report.json"}));
  EXPECT_EQ(listing(work_), std::set<std::string>{"out"});
}

TEST_F(RenderCli, ForeignDirectoryIsRefusedAndLeftUntouched) {
  const fs::path out = work_ / "out";
  fs::create_directories(out);
  std::ofstream(out / "thesis.tex") << "precious\n";
  const Result r = run_render(small_args({"--technique", "pcf", "-o", out.string()}), scratch_);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_EQ(line_count(r.err), 1) << r.err;
  EXPECT_THAT(r.err, HasSubstr(out.string()));
  EXPECT_EQ(listing(out), std::set<std::string>{"thesis.tex"});
  EXPECT_EQ(read_file(out / "thesis.tex"), "precious\n");
  EXPECT_EQ(listing(work_), std::set<std::string>{"out"}) << "no staging directory left";
}

TEST_F(RenderCli, RegularFileAsOutputIsRefusedAndLeftUntouched) {
  const fs::path out = work_ / "out";
  std::ofstream(out) << "a file\n";
  const Result r = run_render(small_args({"-o", out.string()}), scratch_);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_EQ(line_count(r.err), 1) << r.err;
  EXPECT_THAT(r.err, HasSubstr(out.string()));
  EXPECT_EQ(read_file(out), "a file\n");
  EXPECT_EQ(listing(work_), std::set<std::string>{"out"});
}

// --- refused inputs: one case per bad value ---

struct BadCase {
  std::string name;
  std::vector<std::string> args;       // replaces the value given in kSmall when it sets the same option
  std::vector<std::string> needles;    // what the one stderr line must contain; {bad_scene} is substituted
  bool with_output = true;
};

void PrintTo(const BadCase& c, std::ostream* os) { *os << c.name; }

class RenderCliRefuses : public RenderCli, public ::testing::WithParamInterface<BadCase> {};

TEST_P(RenderCliRefuses, WithOneLineAndNoOutput) {
  const fs::path bad_scene = scratch_ / "bad_scene.json";
  std::ofstream(bad_scene) << R"({"name": "bad", "camera": {"fov_deg": 50}, "objects": []})" << "\n";
  auto subst = [&](std::string s) {
    if (s == "{bad_scene}") return bad_scene.string();
    return s;
  };
  // Base arguments, minus any option the case sets itself (a repeated option is its own error).
  std::vector<std::string> args;
  for (std::size_t i = 0; i < kSmall.size(); i += 2)
    if (std::find(GetParam().args.begin(), GetParam().args.end(), kSmall[i]) == GetParam().args.end()) {
      args.push_back(kSmall[i]);
      args.push_back(kSmall[i + 1]);
    }
  for (const auto& a : GetParam().args) args.push_back(subst(a));
  if (GetParam().with_output) {
    args.push_back("-o");
    args.push_back((work_ / "out").string());
  }
  std::vector<std::string> needles;
  for (const auto& n : GetParam().needles) needles.push_back(subst(n));
  expect_refused(args, needles);
}

// 65 resolutions: one more than a list may hold.
std::string sixty_five_resolutions() {
  std::string list = "64";
  for (int i = 1; i < 65; ++i) list += "," + std::to_string(64 + i);  // distinct: a repeat is refused on its own (issue 45)
  return list;
}

INSTANTIATE_TEST_SUITE_P(
    BadInputs, RenderCliRefuses,
    ::testing::Values(
        BadCase{"resolution_zero", {"--resolution", "0"}, {"--resolution", "'0'"}},
        BadCase{"resolution_not_a_number", {"--resolution", "abc"}, {"--resolution", "'abc'"}},
        BadCase{"resolution_too_large", {"--resolution", "99999999"}, {"--resolution", "99999999"}},
        BadCase{"resolution_list_gap", {"--resolution", "64,,128"}, {"--resolution"}},
        BadCase{"resolution_above_device_limit", {"--resolution", "65536"}, {"--resolution", "65536"}},
        BadCase{"pcf_radius_negative", {"--pcf.radius", "-1"}, {"--pcf.radius", "'-1'"}},
        BadCase{"pcf_radius_nan", {"--pcf.radius", "nan"}, {"--pcf.radius", "'nan'"}},
        BadCase{"light_size_nan", {"--light-size", "nan"}, {"--light-size", "expected a finite number"}},  // issue 14.8
        BadCase{"pcf_taps_not_integer", {"--pcf.poisson_taps", "2.5"}, {"--pcf.poisson_taps", "'2.5'"}},
        BadCase{"pcf_kernel_unknown", {"--pcf.kernel", "box"}, {"--pcf.kernel", "'box'", "poisson"}},
        BadCase{"technique_unknown", {"--technique", "foo"}, {"--technique", "foo"}},
        BadCase{"width_zero", {"--width", "0"}, {"--width"}},
        BadCase{"map_fit_not_bool", {"--map.fit", "maybe"}, {"--map.fit", "'maybe'"}},
        BadCase{"vsm_bleed_reduction_above_max", {"--vsm.bleed_reduction", "1.5"}, {"--vsm.bleed_reduction", "'1.5'"}},
        BadCase{"scene_unknown_name", {"--scene", "nosuchscene"}, {"scene", "'nosuchscene'"}},
        BadCase{"scene_missing_file", {"--scene", "/nonexistent/x.json"}, {"/nonexistent/x.json"}},
        BadCase{"scene_bad_field", {"--scene", "{bad_scene}"}, {"{bad_scene}", "camera.fov_deg"}},
        BadCase{"path_frame_without_path", {"--path-frame", "3"}, {"--path-frame", "'demo' has no camera path"}},
        BadCase{"path_frame_beyond_path", {"--scene", "outdoor", "--path-frame", "360"}, {"--path-frame", "359"}},
        BadCase{"unknown_option", {"--bogus"}, {"--bogus"}},
        // Issue 27: options taken and not used, lists without end.
        BadCase{"map_resolution_beside_resolution", {"--map.resolution_texels", "128"}, {"--map.resolution_texels", "--resolution"}},
        BadCase{"map_resolution_above_device_limit", {"--resolution", "64", "--map.resolution_texels", "65536"}, {"--map.resolution_texels"}},
        BadCase{"option_of_a_technique_not_rendered", {"--technique", "hard", "--vsm.radius", "3"}, {"--vsm.radius", "--technique hard"}},
        BadCase{"resolution_list_too_long", {"--resolution", sixty_five_resolutions()}, {"--resolution", "at most 64"}},
        // Issue 31: a technique that reads no pages is refused before anything renders.
        BadCase{"virtual_pages_for_poisson_pcf", {"--technique", "pcf", "--pcf.kernel", "poisson", "--map.virtual_pages", "rule"}, {"--map.virtual_pages", "kernel=poisson"}},
        BadCase{"missing_output", {"--technique", "hard"}, {"--output"}, false}),
    [](const ::testing::TestParamInfo<BadCase>& param_info) { return param_info.param.name; });

// --- the calibration file (issue 12: the loop closed in every app) ---

// The default file (the published c) is read and recorded in the summary and in every render's
// report; its c is the one the renderer used.
TEST_F(RenderCli, DefaultCalibrationIsRecorded) {
  const fs::path out = work_ / "out";
  const Result r = run_render(small_args({"--technique", "pcf", "-o", out.string()}), scratch_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const fs::path& report_path : {out / "report.json", only_render_dir(out) / "report.json"}) {
    SCOPED_TRACE(report_path.string());
    const auto cal = read_json(report_path).at("calibration");
    EXPECT_THAT(cal.at("file").get<std::string>(), ::testing::EndsWith("data/calibration/default.json"));
    EXPECT_NEAR(cal.at("c").get<double>(), 3.47, 1e-6);
    EXPECT_TRUE(cal.at("ci95").is_null()) << "the thesis gives no interval, and none is written: " << cal.at("ci95");
    EXPECT_EQ(cal.at("source_of_c"), "file");
  }
  EXPECT_NEAR(read_json(only_render_dir(out) / "report.json").at("settings").at("adaptive").at("c").get<double>(), 3.47, 1e-6);
}

// A fitted calibration sets adaptive.c; an explicit --adaptive.c wins over it, and the report says so.
TEST_F(RenderCli, CalibrationFileSetsCAndExplicitAdaptiveCWins) {
  const fs::path cal_file = scratch_ / "calibration.json";
  std::ofstream(cal_file) << R"({"c": 4.25, "ci95": [3.5, 5.0], "condition": "step"})" << "\n";
  struct Case {
    std::vector<std::string> extra;
    double c;
    std::string source;
  };
  for (const Case& c : {Case{{}, 4.25, "file"}, Case{{"--adaptive.c", "6.5"}, 6.5, "--adaptive.c"}}) {
    SCOPED_TRACE(c.source);
    const fs::path out = work_ / "out";
    std::vector<std::string> args = {"--technique", "pcf", "--calibration", cal_file.string(), "-o", out.string()};
    args.insert(args.end(), c.extra.begin(), c.extra.end());
    const Result r = run_render(small_args(args), scratch_);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto summary = read_json(out / "report.json");
    const auto render = read_json(only_render_dir(out) / "report.json");
    for (const auto& cal : {summary.at("calibration"), render.at("calibration")}) {
      EXPECT_EQ(cal.at("file"), cal_file.string());
      EXPECT_NEAR(cal.at("c").get<double>(), c.c, 1e-6);
      EXPECT_EQ(cal.at("ci95"), nlohmann::json({3.5, 5.0}));
      EXPECT_EQ(cal.at("source_of_c"), c.source);
    }
    EXPECT_NEAR(render.at("settings").at("adaptive").at("c").get<double>(), c.c, 1e-6);
  }
}

// Issue 15: c per technique. Each render uses its technique's entry (pcf grid and pcf poisson
// apart), a technique without one the PCF entry, said to be a fallback, in its report; the
// summary report.json of a one-technique run says the same (it described the default technique).
TEST_F(RenderCli, EachTechniqueUsesItsOwnCalibrationEntry) {
  const fs::path cal_file = scratch_ / "per-technique.json";
  std::ofstream(cal_file) << R"({"schema_version": 2, "entries": [
      {"technique": "pcf", "kernel": "grid", "c": 2.5, "ci95": [2.0, 3.0], "obtained_by": "study", "participants": 3},
      {"technique": "pcf", "kernel": "poisson", "c": 3.25, "obtained_by": "image-observer"},
      {"technique": "vsm", "c": 6.0, "obtained_by": "simulated"}]})"
                          << "\n";
  struct Case {
    std::vector<std::string> args;
    std::string dir;  // the render's directory
    double c;
    bool fallback;
    std::string from;
  };
  for (const Case& c : {Case{{"--technique", "pcf", "--pcf.kernel", "grid"}, "pcf-grid", 2.5, false, "pcf grid entry (people, 3 participants)"},
                        Case{{"--technique", "pcf", "--pcf.kernel", "poisson", "--pcf.rotate", "false"}, "pcf-poisson", 3.25, false,
                             "pcf poisson entry (image observer)"},
                        // Issue 48: rotated per pixel (the default) it is another filter than the entry's.
                        Case{{"--technique", "pcf", "--pcf.kernel", "poisson"}, "pcf-poisson", 3.25, true,
                             "pcf poisson entry (image observer), not measured for pcf poisson rotated per pixel: measured unrotated (the "
                             "study draws one tap pattern for every pixel); an entry for pcf poisson measured rotated, or pcf.rotate false "
                             "with a pcf poisson entry would match"},
                        Case{{"--technique", "vsm"}, "vsm", 6.0, false, "vsm entry (psychometric simulation)"},
                        Case{{"--technique", "rpcf"}, "rpcf", 2.5, true,
                             "pcf grid entry (people, 3 participants), not measured for rpcf: measured for pcf, not for rpcf; a rpcf entry "
                             "would match"}}) {
    SCOPED_TRACE(c.dir);
    const fs::path out = work_ / ("out-" + c.dir + "-" + std::to_string(c.args.size()));
    std::vector<std::string> args = c.args;
    args.insert(args.end(), {"--calibration", cal_file.string(), "-o", out.string()});
    const Result r = run_render(small_args(args), scratch_);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto render = read_json(out / c.dir / "report.json");
    const auto& cal = render.at("calibration");
    EXPECT_NEAR(cal.at("c").get<double>(), c.c, 1e-6);
    EXPECT_NEAR(render.at("settings").at("adaptive").at("c").get<double>(), c.c, 1e-6);
    EXPECT_EQ(cal.at("fallback").get<bool>(), c.fallback);
    EXPECT_EQ(cal.at("from"), c.from);
    EXPECT_EQ(cal.at("fallback_reason").is_null(), !c.fallback);
    EXPECT_EQ(cal.at("schema_version"), 2);
    EXPECT_EQ(read_json(out / "report.json").at("calibration"), cal) << "the summary names the rendered technique's c";
  }
}

// Issue 48: kernel matching is loud. The main job's PCF grid with the published (disk) entry, and the
// rotated Poisson disk with predicted.json's unrotated Poisson entry, each print the fallback with
// what would match on their "c for" line and record it in report.json.
TEST_F(RenderCli, AnotherKernelOrRotationIsPrintedAsAFallback) {
  struct Case {
    std::vector<std::string> args;
    std::string calibration, dir, printed, reason;
  };
  for (const Case& c : {Case{{"--pcf.kernel", "grid"}, "default.json", "pcf-grid", "not measured for pcf grid", "disk kernel"},
                        Case{{"--pcf.kernel", "poisson"}, "predicted.json", "pcf-poisson", "not measured for pcf poisson rotated per pixel",
                             "unrotated"}}) {
    SCOPED_TRACE(c.dir);
    std::vector<std::string> args = c.args;
    const fs::path out = work_ / ("fallback-" + c.dir);
    // The shipped files, beside this source in the tree.
    const fs::path shipped = fs::path(__FILE__).parent_path().parent_path().parent_path() / "data" / "calibration" / c.calibration;
    args.insert(args.end(), {"--technique", "pcf", "--adaptive.enabled", "true", "--calibration", shipped.string(), "-o", out.string()});
    const Result r = run_render(small_args(args), scratch_);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find(c.printed), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("would match"), std::string::npos) << r.out;
    const auto cal = read_json(out / c.dir / "report.json").at("calibration");
    EXPECT_TRUE(cal.at("fallback").get<bool>());
    EXPECT_NE(cal.at("fallback_reason").get<std::string>().find(c.reason), std::string::npos) << cal.dump();
    EXPECT_FALSE(cal.at("would_match").get<std::string>().empty());
  }
}

// Issue 44: a lab's fit of the shipped lab config (default-lab.json draws with the disk kernel)
// writes the entry pcf disk; a render with PCF's defaults uses it as measured, not as a fallback
// for another kernel.
TEST_F(RenderCli, PcfsDefaultKernelUsesTheLabsEntry) {
  const fs::path cal_file = scratch_ / "lab.json";
  std::ofstream(cal_file) << R"({"schema_version": 2, "entries": [
      {"technique": "pcf", "kernel": "disk", "c": 3.1, "ci95": [2.8, 3.4], "obtained_by": "study", "participants": 8}]})"
                          << "\n";
  const fs::path out = work_ / "out-lab";
  const Result r = run_render(small_args({"--technique", "pcf", "--adaptive.enabled", "true", "--calibration", cal_file.string(), "-o",
                                          out.string()}),
                              scratch_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out.find("not measured for"), std::string::npos) << r.out;
  const auto cal = read_json(out / "pcf-disk" / "report.json").at("calibration");
  EXPECT_EQ(cal.at("fallback").get<bool>(), false);
  EXPECT_EQ(cal.at("from"), "pcf disk entry (people, 8 participants)");
  EXPECT_NEAR(cal.at("c").get<double>(), 3.1, 1e-6);
}

// Issue 26: a render with the adaptive rule says the c it uses, where it came from and what the fitter
// flagged, before it renders: an entry written with --allow-unusable is named NOT USABLE.
TEST_F(RenderCli, TheAdaptiveRulesCIsPrintedWithItsFlags) {
  const fs::path cal_file = scratch_ / "flagged.json";
  std::ofstream(cal_file) << R"({"schema_version": 2, "entries": [
      {"technique": "pcf", "kernel": "disk", "c": 0.647, "obtained_by": "study", "participants": 1,
       "flags": ["not_converged", "slope_at_upper_bound", "one_participant"], "usable": false,
       "unusable_because": ["not_converged", "interval_open"]}]})"
                          << "\n";
  const fs::path out = work_ / "out-flagged";
  const Result r = run_render(small_args({"--technique", "pcf", "--pcf.kernel", "disk", "--adaptive.enabled", "true", "--calibration",
                                          cal_file.string(), "-o", out.string()}),
                              scratch_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string line = "c for pcf disk = 0.647 texels at the entry's criterion, detection probability F = 0.646: pcf disk entry "
                           "(people, 1 participant) of " + cal_file.string() +
                           "; NOT USABLE: not_converged, interval_open; flags: not_converged, slope_at_upper_bound, one_participant";
  EXPECT_NE(r.out.find(line + "\n"), std::string::npos) << r.out;
  EXPECT_LT(r.out.find(line), r.out.find("technique ")) << "said before the table of renders";
  const auto cal = read_json(out / "pcf-disk" / "report.json").at("calibration");
  EXPECT_EQ(cal.at("usable"), false);
  EXPECT_EQ(cal.at("observers"), "people");
  EXPECT_EQ(cal.at("flags").size(), 3u);
  // Without the adaptive rule c is not used, and not said.
  const Result fixed = run_render(small_args({"--technique", "pcf", "--calibration", cal_file.string(), "-o", (work_ / "out-fixed").string()}), scratch_);
  ASSERT_EQ(fixed.exit_code, 0) << fixed.err;
  EXPECT_EQ(fixed.out.find("c for "), std::string::npos) << fixed.out;
}

// Issue 29: --adaptive.visibility chooses the detection probability the rule is for. At F 0.1
// (about 55 % correct in 2AFC) the published entry's c becomes c(0.1) = 1.96 c(F*) on its
// psychometric function as data/calibration/default.json reads it (log-Weibull, slope 3.5,
// criterion F* 0.6737), and the map grows by that factor (within a resolution quantum of 32 texels).
TEST_F(RenderCli, AChosenVisibilityEnlargesTheMapByTheRatioOfItsC) {
  auto render = [&](const std::vector<std::string>& extra, const std::string& name) {
    std::vector<std::string> args = {"--technique", "pcf", "--pcf.kernel", "poisson", "--pcf.radius", "0.1", "--pcf.radius_unit", "world",
                                     "--adaptive.enabled", "true"};
    args.insert(args.end(), extra.begin(), extra.end());
    args.insert(args.end(), {"-o", (work_ / name).string()});
    const Result r = run_render(small_args(args), scratch_);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return std::make_pair(r.out, read_json(work_ / name / "pcf-poisson" / "report.json"));
  };
  const auto [out_default, base] = render({}, "criterion");
  const auto [out_low, low] = render({"--adaptive.visibility", "0.1"}, "low");
  const double factor = penumbra::adaptive::c_at_visibility(3.47, 0.6737, 0.1, 3.5) / 3.47;
  EXPECT_NEAR(factor, 1.965, 0.01);
  EXPECT_NEAR(low.at("calibration").at("c").get<double>(), 3.47 * factor, 1e-3);
  EXPECT_EQ(low.at("calibration").at("visibility").get<double>(), 0.1) << "a double: the value typed";
  const double r0 = base.at("resolution_texels").get<double>(), r1 = low.at("resolution_texels").get<double>();
  EXPECT_GT(r1, r0);
  EXPECT_NEAR(r1 / r0, factor, 32.0 / r0 * factor + 1e-9) << r0 << " -> " << r1;
  EXPECT_NE(out_low.find("c for pcf poisson = 6.82 texels at visibility F = 0.1"), std::string::npos) << out_low;
  // Issue 48: the published entry has no interval, yet at F 0.1 c carries the psychometric family's
  // spread (the log-Weibull asks the most there), printed and recorded.
  EXPECT_NE(out_low.find("over c, the slope and the psychometric family (the family alone ["), std::string::npos) << out_low;
  const nlohmann::json& at = low.at("calibration").at("ci95_at_visibility");
  ASSERT_TRUE(at.is_array()) << low.at("calibration").dump();
  EXPECT_LT(at[0].get<double>(), 0.95 * 3.47 * factor);
  EXPECT_GE(at[1].get<double>(), 3.47 * factor - 1e-9);
  EXPECT_TRUE(base.at("calibration").find("ci95_at_visibility") == base.at("calibration").end()) << "none at the criterion";
  EXPECT_NE(out_default.find("at the entry's criterion, detection probability F = 0.674"), std::string::npos) << out_default;
  // A visibility no function reaches is refused by the settings table.
  const Result bad = run_render(small_args({"--adaptive.visibility", "1.5", "-o", (work_ / "bad").string()}), scratch_);
  EXPECT_EQ(bad.exit_code, 2) << bad.err;
}

// Issue 48: --adaptive.observer-percentile asks the entry's population (penumbra-fit's multilevel
// block) for the P-th percentile observer's c, as --adaptive.visibility asks for a detection
// probability: the fitted percentile's own c and interval, the median observer at the population's
// mean c, printed and recorded; an entry without a population and an explicit --adaptive.c are
// refused naming the option.
TEST_F(RenderCli, AnObserverPercentileIsReadFromTheEntrysPopulation) {
  const fs::path file = work_ / "population.json";
  std::ofstream(file) << R"json({"schema_version": 2, "entries": [
      {"technique": "pcf", "kernel": "disk", "c": 3.13, "ci95": [2.73, 3.73], "obtained_by": "simulated", "participants": 6,
       "population": {"participants": 6, "condition": "the worst condition (stair/1)", "mean_c": 3.184, "mean_c_ci95": [2.732, 3.734],
                      "sd_log10": 0.05, "sd_log10_ci95": [0.02, 0.09], "observer_percentile": "90", "percentile_c": 3.273,
                      "percentile_c_ci95": [2.824, 4.583]}},
      {"technique": "vsm", "c": 3.06, "obtained_by": "image-observer"}]})json";
  auto render = [&](const std::vector<std::string>& extra, const std::string& name) {
    std::vector<std::string> args = {"--calibration", file.string(), "--adaptive.enabled", "true"};
    args.insert(args.end(), extra.begin(), extra.end());
    args.insert(args.end(), {"-o", (work_ / name).string()});
    return run_render(small_args(args), scratch_);
  };
  const Result p90 = render({"--technique", "pcf", "--adaptive.observer-percentile", "90"}, "p90");
  ASSERT_EQ(p90.exit_code, 0) << p90.err;
  const nlohmann::json cal = read_json(work_ / "p90" / "pcf-disk" / "report.json").at("calibration");
  EXPECT_NEAR(cal.at("c").get<double>(), 3.273, 1e-6);
  EXPECT_EQ(cal.at("observer_percentile").get<double>(), 90.0);
  EXPECT_EQ(cal.at("ci95_for_percentile"), nlohmann::json({2.824, 4.583}));
  EXPECT_EQ(cal.at("c_at_criterion").get<double>(), 3.13) << "the sample's c, recorded beside";
  EXPECT_THAT(p90.out, HasSubstr("c for pcf disk = 3.27 texels for the 90th-percentile observer (c 3.27 [2.82, 4.58] at the entry's "
                                 "criterion; population of 6 participants: mean c 3.18, sd 0.05 log10, the fitted percentile)"));
  const Result median = render({"--technique", "pcf", "--adaptive.observer-percentile", "50"}, "p50");
  ASSERT_EQ(median.exit_code, 0) << median.err;
  EXPECT_NEAR(read_json(work_ / "p50" / "pcf-disk" / "report.json").at("calibration").at("c").get<double>(), 3.184, 1e-6);
  EXPECT_THAT(median.out, HasSubstr("from the mean and the spread"));
  const Result none = render({"--technique", "vsm", "--adaptive.observer-percentile", "90"}, "vsm");
  EXPECT_EQ(none.exit_code, 2);
  EXPECT_THAT(none.err, HasSubstr("--adaptive.observer-percentile: vsm entry (image observer) has no population block"));
  EXPECT_EQ(line_count(none.err), 1) << none.err;
  const Result both = render({"--technique", "pcf", "--adaptive.c", "3", "--adaptive.observer-percentile", "90"}, "both");
  EXPECT_EQ(both.exit_code, 2);
  EXPECT_THAT(both.err, HasSubstr("--adaptive.observer-percentile: not read: --adaptive.c gives c itself"));
}

// Issue 45: adaptive.visibility is a double in 0 (the entry's criterion) or [0.001, 0.999]. As a
// float, 1e-45 .. 5e-324 became 0 and quietly meant the criterion; 1e-15 gave c = 69 215 texels;
// 1e-17 failed blaming adaptive.c, exit 1. Each is refused in one line naming the option, exit 2.
TEST_F(RenderCli, VisibilityOutsideItsRangeIsRefusedNamingTheOption) {
  for (const char* value : {"1e-45", "5e-324", "1e-300", "1e-15", "1e-17", "0.0009", "-0.1", "0.9995", "1"}) {
    SCOPED_TRACE(value);
    const Result r = run_render(small_args({"--technique", "pcf", "--adaptive.enabled", "true", "--adaptive.visibility", value, "-o",
                                            (work_ / "out").string()}),
                                scratch_);
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_EQ(line_count(r.err), 1) << r.err;
    EXPECT_THAT(r.err, HasSubstr("--adaptive.visibility"));
    EXPECT_THAT(r.err, HasSubstr("0 or a number in [0.001, 0.999]"));
    EXPECT_FALSE(fs::exists(work_ / "out"));
  }
  // The ends of the range are taken, and give a c within adaptive.c's range from the published entry.
  for (const char* value : {"0.001", "0.999"}) {
    SCOPED_TRACE(value);
    const fs::path out = work_ / (std::string("edge-") + value);
    const Result r = run_render(small_args({"--technique", "pcf", "--adaptive.enabled", "true", "--adaptive.visibility", value, "-o", out.string()}),
                                scratch_);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const double c = read_json(only_render_dir(out) / "report.json").at("calibration").at("c").get<double>();
    EXPECT_TRUE(c >= 0.01 && c <= 100) << c;
  }
}

// Issue 45: c at a visibility is bounded: a valid entry (criterion F 1e-6, slope 0.01) at F 0.999
// gave c = 0 and failed blaming adaptive.c. The line names the option and the entry, exit 2.
TEST_F(RenderCli, CAtAVisibilityOutsideAdaptiveCsRangeIsRefusedNamingTheEntry) {
  const fs::path cal = scratch_ / "shallow.json";
  std::ofstream(cal) << R"({"schema_version": 2, "entries": [{"technique": "pcf", "c": 3.47, "obtained_by": "simulated",
      "threshold": {"task": "2afc", "guess": 0.5, "criterion_f": 1e-6, "family": "log-weibull", "beta": 0.01}}]})"
                     << "\n";
  for (const auto& [calibration, value] : std::vector<std::pair<std::string, std::string>>{{cal.string(), "0.999"}, {"", "0.001"}}) {
    SCOPED_TRACE(value);
    std::vector<std::string> args = {"--technique", "pcf", "--adaptive.enabled", "true", "--adaptive.visibility", value, "-o", (work_ / "out").string()};
    if (!calibration.empty()) args.insert(args.end(), {"--calibration", calibration});
    const Result r = run_render(small_args(args), scratch_);
    if (calibration.empty()) {  // the published entry at the range's end: c 25.3, taken
      EXPECT_EQ(r.exit_code, 0) << r.err;
      continue;
    }
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_EQ(line_count(r.err), 1) << r.err;
    EXPECT_THAT(r.err, HasSubstr("--adaptive.visibility: at F = 0.999 the pcf entry"));
    EXPECT_THAT(r.err, HasSubstr(cal.string()));
    EXPECT_THAT(r.err, HasSubstr("outside [0.01, 100]"));
    EXPECT_THAT(r.err, ::testing::Not(HasSubstr("adaptive.c must")));
  }
}

// Issue 45: options taken and not used, each refused in one line naming the option (exit 2) from
// the one list of what a configuration reads (shadows::unread_setting).
TEST_F(RenderCli, SettingsNoConfigurationReadsAreRefused) {
  const std::vector<std::string> virtual_pcf = {"--technique", "pcf", "--pcf.kernel", "grid", "--pcf.radius_unit", "world", "--pcf.radius", "0.05"};
  const auto with_virtual = [&](const std::string& marking, std::vector<std::string> extra) {
    std::vector<std::string> args = virtual_pcf;
    args.insert(args.end(), {"--map.virtual_pages", marking});
    args.insert(args.end(), extra.begin(), extra.end());
    return args;
  };
  struct Case {
    std::string name;
    std::vector<std::string> args;
    std::vector<std::string> needles;
  };
  const std::vector<Case> cases = {
      {"c_beside_visibility", {"--adaptive.enabled", "true", "--adaptive.c", "3", "--adaptive.visibility", "0.1"},
       {"--adaptive.visibility: not read", "--adaptive.c"}},
      {"visibility_with_the_rule_off", {"--adaptive.visibility", "0.1"}, {"--adaptive.visibility: not read", "adaptive.enabled false"}},
      {"visibility_with_footprint_pages", with_virtual("footprint", {"--adaptive.visibility", "0.1"}),
       {"--adaptive.visibility: not read", "footprint"}},
      {"pool_without_a_virtual_map", {"--map.virtual_pool_pages", "4"}, {"--map.virtual_pool_pages: not read", "map.virtual_pages is off"}},
      {"cache_without_a_virtual_map", {"--map.virtual_cache", "false"}, {"--map.virtual_cache: not read", "map.virtual_pages is off"}},
      {"bounds_without_a_virtual_map", {"--map.virtual_bounds", "false"}, {"--map.virtual_bounds: not read"}},
      {"page_floor_without_a_virtual_map", {"--map.virtual_min_texel_px", "0.5"}, {"--map.virtual_min_texel_px: not read"}},
      {"page_tiles_without_a_virtual_map", {"--map.virtual_page_tiles", "false"}, {"--map.virtual_page_tiles: not read"}},
      {"cascade_floor_with_a_virtual_map", with_virtual("rule", {"--adaptive.min_texel_px", "0.5"}),
       {"--adaptive.min_texel_px: not read", "map.virtual_min_texel_px"}},
      {"cascades_with_a_virtual_map", with_virtual("rule", {"--map.cascades", "4"}), {"--map.cascades: not read", "virtual shadow map"}},
      {"adaptive_maps_with_a_virtual_map", with_virtual("rule", {"--adaptive.enabled", "true"}), {"--adaptive.enabled: not read"}},
      {"resolutions_with_a_virtual_map", with_virtual("rule", {"--resolution", "64,4096"}),
       {"--resolution: not read (it sets map.resolution_texels)", "virtual shadow map"}},
      {"map_resolution_with_a_virtual_map", with_virtual("rule", {"--map.resolution_texels", "512"}), {"--map.resolution_texels"}}};
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    // The base arguments without --resolution (a virtual map reads none) unless the case gives it.
    std::vector<std::string> args = {"--width", "64", "--height", "48", "--frames", "1", "--warmup", "0"};
    args.insert(args.end(), c.args.begin(), c.args.end());
    args.insert(args.end(), {"-o", (work_ / "out").string()});
    const Result r = run_render(args, scratch_);
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_EQ(line_count(r.err), 1) << r.err;
    for (const auto& n : c.needles) EXPECT_THAT(r.err, HasSubstr(n));
    EXPECT_FALSE(fs::exists(work_ / "out"));
  }
  // What they are refused beside is read: the same options in the configurations that read them run.
  for (const auto& args : std::vector<std::vector<std::string>>{
           {"--adaptive.enabled", "true", "--adaptive.visibility", "0.1"},
           with_virtual("rule", {"--adaptive.visibility", "0.1", "--map.virtual_pool_pages", "8", "--map.virtual_cache", "false",
                                 "--map.virtual_min_texel_px", "2"}),
           {"--adaptive.min_texel_px", "1", "--map.virtual_min_texel_px", "2", "--virtual-debug", "--scene", "outdoor", "--pcf.radius_unit",
            "world", "--pcf.radius", "0.12"},
           {"--resolution", "64", "--map.cascades", "2"}}) {
    std::vector<std::string> full = {"--width", "64", "--height", "48", "--frames", "1", "--warmup", "0", "-o", (work_ / "ok").string()};
    full.insert(full.end(), args.begin(), args.end());
    const Result r = run_render(full, scratch_);
    EXPECT_EQ(r.exit_code, 0) << r.err;
  }
}

// Issue 45: a page pool too small for the view. One slot cannot hold even the coarsest level's
// pages under the demo's view (its ground straddles a page corner of every level): refused in one
// line naming the option, exit 2. Four slots hold a coarse floor: the pages that do not fit are
// said on stderr, and no pixel is shaded lit for want of a page.
TEST_F(RenderCli, APagePoolTooSmallIsRefusedOrWarnedAndNeverShadesLit) {
  const std::vector<std::string> args = {"--scene", "demo", "--width", "96", "--height", "64", "--frames", "1", "--warmup", "0",
                                         "--technique", "pcf", "--pcf.kernel", "grid", "--pcf.radius_unit", "world", "--pcf.radius", "0.05",
                                         "--map.virtual_pages", "rule"};
  const auto run = [&](const std::string& pool, const fs::path& out) {
    std::vector<std::string> a = args;
    a.insert(a.end(), {"--map.virtual_pool_pages", pool, "-o", out.string()});
    return run_render(a, scratch_);
  };
  const Result one = run("1", work_ / "one");
  EXPECT_EQ(one.exit_code, 2) << one.err;
  EXPECT_EQ(line_count(one.err), 1) << one.err;
  EXPECT_THAT(one.err, HasSubstr("--map.virtual_pool_pages 1: a pool of 1 page slot cannot hold"));
  EXPECT_THAT(one.err, HasSubstr("give at least 2"));
  EXPECT_FALSE(fs::exists(work_ / "one"));

  const Result full = run("32", work_ / "full");
  ASSERT_EQ(full.exit_code, 0) << full.err;
  EXPECT_EQ(full.err, "") << "a pool that holds the view warns of nothing";
  const Result four = run("2", work_ / "four");
  ASSERT_EQ(four.exit_code, 0) << four.err;
  EXPECT_EQ(line_count(four.err), 1) << four.err;
  EXPECT_THAT(four.err, HasSubstr("warning: virtual shadow map: "));
  EXPECT_THAT(four.err, HasSubstr("(--map.virtual_pool_pages 2)"));
  const nlohmann::json v = read_json(only_render_dir(work_ / "four") / "report.json").at("virtual_map");
  EXPECT_GT(v.at("pages").at("missing").get<int>(), 0) << v;
  EXPECT_GT(v.at("pages").at("floor_level").get<int>(), 0) << v;
  EXPECT_EQ(v.at("shaded_pixels").at("none").get<int>(), 0) << "pixels shaded lit for want of a page: " << v;
  // The shadow stays: as many shadowed pixels, within a few, as with a pool that holds every page.
  const auto shadowed = [&](const fs::path& out) {
    int n = 0;
    for (const float x : penumbra::io::read_imagef(only_render_dir(out) / "visibility.exr").pixels) n += x < 0.5f;
    return n;
  };
  const int with_full = shadowed(work_ / "full"), with_four = shadowed(work_ / "four");
  EXPECT_GT(with_full, 20);
  EXPECT_GT(with_four, with_full / 2) << with_four << " shadowed pixels against " << with_full;
}

// A bad calibration file is refused before anything is created: one line naming the file and field.
TEST_F(RenderCli, BadCalibrationFileIsRefusedWithNoOutput) {
  struct Case {
    std::string name, content, field;
  };
  const Case cases[] = {{"c_not_a_number", R"({"c": "big"})", "c"},
                        {"c_missing", R"({"ci95": [3, 4]})", "c"},
                        {"ci95_excludes_c", R"({"c": 3.47, "ci95": [4, 5]})", "ci95"},
                        {"unknown_version", R"({"schema_version": 9, "entries": []})", "schema_version"},
                        {"unknown_technique", R"({"schema_version": 2, "entries": [{"technique": "nope", "c": 3, "obtained_by": "study"}]})",
                         "entries[0].technique"},
                        // Issue 27: a kernel the technique does not have stood in as its fallback.
                        {"unknown_kernel", R"({"schema_version": 2, "entries": [{"technique": "pcf", "kernel": "gauss", "c": 3, "obtained_by": "study"}]})",
                         "entries[0].kernel"}};
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    const fs::path file = scratch_ / (c.name + ".json");
    std::ofstream(file) << c.content << "\n";
    expect_refused(small_args({"--calibration", file.string(), "-o", (work_ / "out").string()}), {file.string(), ": " + c.field + ":"});
  }
  const fs::path missing = scratch_ / "missing.json";
  expect_refused(small_args({"--calibration", missing.string(), "-o", (work_ / "out").string()}), {missing.string()});
}

// Issue 27: --map.resolution_texels was taken and the report said 2048. Alone it is the resolution
// rendered (as one --resolution).
TEST_F(RenderCli, MapResolutionTexelsAloneIsTheResolutionRendered) {
  const fs::path out = work_ / "out";
  const Result r = run_render({"--width", "64", "--height", "48", "--frames", "1", "--warmup", "0", "--technique", "pcf",
                               "--map.resolution_texels", "96", "-o", out.string()},
                              scratch_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(read_json(only_render_dir(out) / "report.json").at("resolution_texels"), 96);
}

// Issue 27: --esm.radius 1e6 took 29.8 s and --evsm.radius 1e6 23.5 s, VSM at the same radius
// 0.98 s: their blur summed each texel's window anew. A radius wider than the map renders, and
// every visibility is finite; that its work is bounded by the map (not its seconds: a loaded
// machine made a wall-clock bound here fail) is MomentsBlur.AWindowWiderThanTheMapFetchesNoMoreThanTheMapBounds.
TEST_F(RenderCli, ABlurRadiusWiderThanTheMapRenders) {
  for (const char* t : {"vsm", "esm", "evsm"}) {
    SCOPED_TRACE(t);
    const fs::path out = work_ / t;
    const Result r = run_render({"--width", "64", "--height", "48", "--resolution", "512", "--frames", "1", "--warmup", "0", "--technique",
                                 t, std::string("--") + t + ".radius", "1e6", "-o", out.string()},
                                scratch_);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const penumbra::io::ImageF visibility = penumbra::io::read_imagef(only_render_dir(out) / "visibility.exr");
    for (const float v : visibility.pixels) ASSERT_TRUE(std::isfinite(v) && v >= 0 && v <= 1) << v;
  }
}

// Issue 27: one sphere at x = 1e20 made the light fit overflow (near = far = 3.4e38, s_xy null)
// and every pixel lit. The far sphere stays out of the fit: the ball still casts its shadow and
// every number in the report is finite.
TEST_F(RenderCli, AFarAwayObjectLeavesTheShadowsAndTheReportFinite) {
  const fs::path scene = scratch_ / "far.json";
  std::ofstream(scene) << R"({"name": "far",
    "camera": {"projection": "perspective", "position": [0, 7, 13], "target": [0, 1, 0], "fov_y_deg": 50, "near_ws": 0.1, "far_ws": 60},
    "light": {"type": "directional", "direction": [-0.3, -1, -0.2], "size": 0.5},
    "objects": [{"name": "ground", "shape": "plane", "size": [20, 20]},
                {"name": "ball", "shape": "sphere", "radius": 1.2, "translate": [0, 1.5, 2]},
                {"name": "faraway", "shape": "sphere", "radius": 1, "translate": [1e20, 0, 0]}]})"
                       << "\n";
  const fs::path out = work_ / "out";
  const Result r = run_render({"--scene", scene.string(), "--width", "96", "--height", "64", "--resolution", "256", "--frames", "1",
                               "--warmup", "0", "--technique", "pcf", "-o", out.string()},
                              scratch_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const fs::path dir = only_render_dir(out);
  const nlohmann::json light = read_json(dir / "report.json").at("light");
  for (const char* key : {"near_ws", "far_ws", "extent_ws", "s_xy"}) {
    ASSERT_TRUE(light.at(key).is_number()) << key << ": " << light;
    EXPECT_LT(std::abs(light.at(key).get<double>()), 1e6) << key;
  }
  const penumbra::io::ImageF visibility = penumbra::io::read_imagef(dir / "visibility.exr");
  float darkest = 1;
  for (const float v : visibility.pixels) darkest = std::min(darkest, v);
  EXPECT_LT(darkest, 0.2f) << "the ball's shadow is gone";
}

// Issue 45: the far-away objects of issue 27 in every way of drawing the sun's shadows. The
// virtual shadow map took its depth range from the scene's bounds: a sphere at x = 1e20, a box of
// size 1e30 or an OBJ triangle with a vertex at 1e30 left every pixel lit, exit 0. Its light view
// and depth range now come from the maps' bounded fit (fitting.h's sun_shadow_region): the pixel
// darkest in the ball's shadow without the object stays dark with it, and the report stays finite.
TEST_F(RenderCli, FarAwayObjectsLeaveTheShadowsInEveryWayOfDrawingTheSun) {
  std::ofstream(scratch_ / "far.obj") << "v 1e30 -0.5 -5\nv -5 -0.5 -5\nv -5 -0.5 5\nf 1 2 3\n";
  const std::string base = R"("camera": {"projection": "perspective", "position": [0, 7, 13], "target": [0, 1, 0], "fov_y_deg": 50, "near_ws": 0.1, "far_ws": 60},
    "light": {"type": "directional", "direction": [-0.3, -1, -0.2], "size": 0.5},
    "objects": [{"name": "ground", "shape": "plane", "size": [20, 20]},
                {"name": "ball", "shape": "sphere", "radius": 1.2, "translate": [0, 1.5, 2]})";
  const std::vector<std::pair<std::string, std::string>> objects = {
      {"none", ""},
      {"sphere_at_1e20", R"(, {"name": "faraway", "shape": "sphere", "radius": 1, "translate": [1e20, 0, 0]})"},
      {"box_of_1e30", R"(, {"name": "enormous", "shape": "box", "size": [1e30, 1e30, 1e30], "translate": [0, 0, -1e30]})"},
      {"obj_vertex_at_1e30", R"(, {"name": "sliver", "shape": "model", "path": "far.obj"})"}};
  const std::vector<std::pair<std::string, std::vector<std::string>>> ways = {
      {"single_map", {"--resolution", "256"}},
      {"cascades", {"--resolution", "256", "--map.cascades", "4"}},
      {"virtual_rule", {"--map.virtual_pages", "rule"}},
      {"virtual_footprint", {"--map.virtual_pages", "footprint"}}};
  for (const auto& [way, way_args] : ways) {
    std::size_t shadow_pixel = 0;
    for (const auto& [name, object] : objects) {
      SCOPED_TRACE(way + ", " + name);
      const fs::path scene = scratch_ / (name + ".json");
      std::ofstream(scene) << "{\"name\": \"" << name << "\", " << base << object << "]}\n";
      const fs::path out = work_ / (way + "-" + name);
      std::vector<std::string> args = {"--scene", scene.string(), "--width", "96", "--height", "64", "--frames", "1", "--warmup", "0",
                                       "--technique", "pcf", "--pcf.kernel", "grid", "--pcf.radius_unit", "world", "--pcf.radius", "0.05",
                                       "-o", out.string()};
      args.insert(args.end(), way_args.begin(), way_args.end());
      const Result r = run_render(args, scratch_);
      ASSERT_EQ(r.exit_code, 0) << r.err;
      const fs::path dir = only_render_dir(out);
      const nlohmann::json report = read_json(dir / "report.json");
      for (const char* key : {"near_ws", "far_ws", "extent_ws", "s_xy"}) {
        ASSERT_TRUE(report.at("light").at(key).is_number()) << key << ": " << report.at("light");
        EXPECT_LT(std::abs(report.at("light").at(key).get<double>()), 1e6) << key;
      }
      if (way_args.front() == "--map.virtual_pages") {
        const nlohmann::json& v = report.at("virtual_map");
        for (const char* key : {"near_ws", "far_ws"}) {
          ASSERT_TRUE(v.at("light").at(key).is_number()) << key << ": " << v;
          EXPECT_LT(std::abs(v.at("light").at(key).get<double>()), 1e6) << key;
        }
        EXPECT_EQ(v.at("shaded_pixels").at("none").get<int>(), 0) << v;
      }
      const penumbra::io::ImageF visibility = penumbra::io::read_imagef(dir / "visibility.exr");
      if (name == "none") {
        shadow_pixel = static_cast<std::size_t>(std::min_element(visibility.pixels.begin(), visibility.pixels.end()) - visibility.pixels.begin());
        ASSERT_LT(visibility.pixels[shadow_pixel], 0.2f) << "no shadow of the ball to compare with";
      }
      EXPECT_LT(visibility.pixels[shadow_pixel], 0.2f) << "the ball's shadow is gone";
    }
  }
}
