// penumbra-demo --headless end to end at a tiny size: report.json, frames.csv and the images have
// their documented shape, the adaptive run used the rule's resolution and stayed close to the
// fixed image; bad input is refused in one line with nothing written.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "subprocess.h"

namespace fs = std::filesystem;
using ::testing::HasSubstr;

namespace penumbra {
namespace {

class DemoCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("penumbra-demo-test-" + std::to_string(::getpid()) + "-" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  test::Result demo(std::vector<std::string> args) { return test::run_exe(PENUMBRA_DEMO_EXE, args, dir_); }
  fs::path dir_;
};

TEST_F(DemoCli, HeadlessComparisonWritesTheReport) {
  const fs::path out = dir_ / "out";
  // 16 reference samples instead of the default 64: the report's shape is what is tested here.
  const auto r = demo({"--headless", "--scene", "demo", "--frames", "3", "--width", "192", "--height", "108", "--techniques", "pcf,pcss",
                       "--reference-samples", "16", "-o", out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // The adoption question comes first: adaptive against the engine front at equal perceived
  // difference (FLIP), PCSS also against the ray-traced sun, then at equal RMSE.
  EXPECT_EQ(r.out.rfind("penumbra-demo: adaptive against the engine's Pareto front at equal perceived difference", 0), 0u) << r.out;
  const std::string head = r.out.substr(0, r.out.find("\n\n"));
  EXPECT_THAT(head, HasSubstr("pcss   at RMSE"));
  EXPECT_LT(head.find("pcf    at FLIP"), head.find("pcf    at RMSE"));
  EXPECT_THAT(head, HasSubstr("pcss   at FLIP"));
  EXPECT_THAT(head, ::testing::ContainsRegex("pcss   at FLIP [0-9.]+ against the ray-traced sun"));
  EXPECT_THAT(r.out, HasSubstr("speedup"));
  const auto report = nlohmann::json::parse(test::read_file(out / "report.json"));
  ASSERT_EQ(report.at("techniques").size(), 2u);
  // FLIP's viewing geometry: the study's default display (1920 px, 527 mm wide, seen from 600 mm).
  EXPECT_NEAR(report.at("perceptual").at("pixels_per_degree").get<double>(), 2 * 600 * std::tan(0.5 * M_PI / 180) * 1920 / 527, 1e-6);
  for (const auto& t : report["techniques"]) {
    SCOPED_TRACE(t.at("technique").get<std::string>());
    const bool pcss = t["technique"] == "pcss";
    // The perceived difference beside the RMSE for every timed configuration; the lit frames it
    // compares are composed from the visibility within a code value or two of the renderer's (but
    // for isolated pixels of the virtual maps).
    EXPECT_LT(t.at("perceptual").at("lit_frames").at("share_above_2_codes").get<double>(), 0.001);
    EXPECT_EQ(t["perceptual"].at("flip_evaluations").get<int>(), (pcss ? 2 : 1) * 11);
    EXPECT_THAT(t["perceptual"].at("target").get<std::string>(), HasSubstr(pcss ? "PCSS at converged resolution and taps" : "4 cascades of 81"));
    std::vector<const nlohmann::json*> rows = {&t.at("adaptive"), &t.at("fixed")};
    for (const auto& b : t.at("baselines")) rows.push_back(&b);
    for (const auto& v : t.at("virtual")) rows.push_back(&v);
    for (const auto* row : rows) {
      const auto& flip = row->at("flip");
      EXPECT_EQ(flip.at("frames").get<int>(), 1);
      EXPECT_GT(flip.at("mean").get<double>(), 0);
      EXPECT_LT(flip.at("mean").get<double>(), 0.1);
      EXPECT_GE(flip.at("max_max").get<double>(), flip.at("weighted_median_mean").get<double>());
      EXPECT_GE(flip.at("share_above_mean").get<double>(), 0);
      EXPECT_LE(flip.at("share_above_mean").get<double>(), 1);
      EXPECT_EQ(flip.at("per_frame")[0].at("mean").get<double>(), flip.at("mean").get<double>());
      EXPECT_EQ(row->contains("flip_ray_traced"), pcss);
      EXPECT_EQ(row->contains("reference_error_converged"), pcss);
      EXPECT_EQ(row->contains("observer_ray_traced"), pcss);
      // The frame observer on the same pair, at the calibration entry's F (data/calibration/default.json).
      const auto& seen = row->at("observer");
      EXPECT_EQ(seen.at("frames").get<int>(), 1);
      EXPECT_EQ(seen.at("criterion_f").get<double>(), 0.6737);
      EXPECT_GE(seen.at("p_detect_max").get<double>(), 0);
      EXPECT_LE(seen.at("p_detect_max").get<double>(), 1);
      EXPECT_EQ(seen.at("visible").get<bool>(), seen.at("p_detect_max").get<double>() > 0.6737);
      EXPECT_GE(seen.at("patches_per_frame")[0].get<int>(), 1);
      // Issue 47: what the shadow gave the GPU to do per frame, and what its lookups read per
      // pixel (scripts/gpu_cost_model.py reads these).
      const auto& work = row->at("work");
      EXPECT_EQ(work.at("frames").get<int>(), 3);
      EXPECT_GT(work.at("primitives").at("median").get<double>(), 0);
      EXPECT_GT(work.at("depth_texels").at("median").get<double>(), 0);
      EXPECT_LE(work.at("depth_texels").at("median").get<double>(), work.at("fragments").at("median").get<double>());
      // The camera's passes are the floor's work, not the shadow's: a map's primitives are its maps'
      // triangles alone (no depth prepass), a virtual map's its pages' (no position pass).
      EXPECT_EQ(work.at("primitives").at("median").get<double>(), row->at("map_triangles").at("median").get<double>());
      EXPECT_GE(work.at("reads").at("frames").get<int>(), 1);
      EXPECT_GT(work.at("reads").at("pixels_per_frame").get<double>(), 192 * 108 / 4);
      EXPECT_GE(work.at("reads").at("instructions_per_pixel").get<double>(), 1);
      EXPECT_GE(work.at("reads").at("bytes_per_pixel").get<double>(), 4 * work.at("reads").at("instructions_per_pixel").get<double>());
    }
    // The family's verdict: the cheapest configuration (median frame time) the observer cannot
    // tell from the reference, or none.
    {
      std::string cheapest = "none";
      double best_ms = 1e300;
      for (const auto* row : rows)
        if (!row->at("observer").at("visible").get<bool>() && row->at("frame_ms").at("median").get<double>() < best_ms) {
          best_ms = row->at("frame_ms").at("median").get<double>();
          cheapest = row == &t["adaptive"] ? "adaptive" : row == &t["fixed"] ? "fixed-2048" : row->at("name").get<std::string>();
        }
      EXPECT_EQ(t.at("observer").at("cheapest_by_time").get<std::string>(), cheapest);
      EXPECT_THAT(r.out, HasSubstr(t["observer"].at("line").get<std::string>()));
    }
    // The headline reads the front at equal FLIP: the adaptive rule's FLIP, and the time front of the
    // engine family by FLIP mean and median frame time (no member both faster and closer).
    const auto& ef = t.at("equal_flip");
    EXPECT_EQ(ef.at("adaptive_error").get<double>(), t.at("adaptive").at("flip").at("mean").get<double>());
    {
      std::vector<const nlohmann::json*> by_flip = {&t["fixed"]};
      std::vector<std::string> by_flip_names = {"fixed-2048"};
      for (const auto& b : t["baselines"]) by_flip.push_back(&b), by_flip_names.push_back(b["name"]);
      std::vector<std::string> front;
      for (std::size_t a = 0; a < by_flip.size(); ++a) {
        const double ea = by_flip[a]->at("flip").at("mean").get<double>(), ta = by_flip[a]->at("frame_ms").at("median").get<double>();
        bool dominated = false;
        for (std::size_t b = 0; b < by_flip.size(); ++b) {
          const double eb = by_flip[b]->at("flip").at("mean").get<double>(), tb = by_flip[b]->at("frame_ms").at("median").get<double>();
          dominated = dominated || (b != a && eb <= ea && tb <= ta && (eb < ea || tb < ta));
        }
        if (!dominated) front.push_back(by_flip_names[a]);
      }
      std::vector<std::string> listed = ef.at("time").at("front").get<std::vector<std::string>>();
      std::sort(front.begin(), front.end()), std::sort(listed.begin(), listed.end());
      EXPECT_EQ(listed, front);
    }
    if (pcss) {
      EXPECT_EQ(t.at("equal_flip_ray_traced").at("adaptive_error").get<double>(),
                t.at("adaptive").at("flip_ray_traced").at("mean").get<double>());
      EXPECT_GT(t.at("adaptive").at("reference_error_converged").at("rmse_mean").get<double>(), 0);
    }
    EXPECT_TRUE(fs::exists(out / (t["technique"].get<std::string>() + "-flip-montage.png")));
    EXPECT_EQ(t.at("fixed").at("resolution_texels").get<int>(), 2048);
    const auto& res = t.at("adaptive").at("resolution_texels");
    EXPECT_GE(res.at("min").get<double>(), 32);
    EXPECT_LT(res.at("max").get<double>(), 2048);  // the demo's filters need less than the fixed map
    EXPECT_GT(t.at("adaptive").at("frame_ms").at("median").get<double>(), 0);
    EXPECT_GT(t.at("speedup_median").get<double>(), 0);
    EXPECT_GE(t.at("image").at("ssim_min").get<double>(), 0.99);
    EXPECT_LE(t.at("image").at("max_abs_max").get<double>(), 0.25);
    // Fixed | adaptive | difference, each 192 px image under a band of ceil(40 × 192 / 720) = 11
    // rows for its label, scaled to 720 px (the PNG's IHDR: width, height, big-endian, bytes 16, 20).
    const std::string png = test::read_file(out / (t["technique"].get<std::string>() + "-fixed-vs-adaptive.png"));
    ASSERT_GT(png.size(), 24u);
    const auto be32 = [&](std::size_t at) {
      std::uint32_t v = 0;
      for (std::size_t k = 0; k < 4; ++k) v = v << 8 | static_cast<unsigned char>(png[at + k]);
      return v;
    };
    EXPECT_EQ(be32(16), 3u * 720u);
    EXPECT_EQ(be32(20), 720u * (108u + 11u) / 192u) << "the label band above the images";
    // The engine family along the same path: one map of twice the fixed size, four cascades of it
    // (the engine baseline, compared with itself), single maps of half and four times it, two
    // cascades of once and twice it, each with its texels and its SSIM.
    const auto& baselines = t.at("baselines");
    ASSERT_EQ(baselines.size(), 6u);
    std::vector<std::string> family;
    for (const auto& b : baselines) family.push_back(b.at("name"));
    EXPECT_THAT(family, ::testing::ElementsAre("fixed-4096", "4x2048-cascades", "fixed-1024", "fixed-8192", "2x2048-cascades",
                                               "2x4096-cascades"));
    EXPECT_EQ(baselines[0].at("name"), "fixed-4096");
    EXPECT_EQ(baselines[0].at("texels_rendered").at("median").get<double>(), 4096.0 * 4096.0);
    EXPECT_EQ(baselines[1].at("name"), "4x2048-cascades");
    EXPECT_EQ(t.at("engine_baseline"), "4x2048-cascades");
    EXPECT_EQ(baselines[1].at("texels_rendered").at("median").get<double>(), 4 * 2048.0 * 2048.0);
    EXPECT_GE(baselines[1].at("texels_allocated").get<double>(), 4 * 2048.0 * 2048.0);
    EXPECT_EQ(baselines[1].at("ssim_vs_engine_min").get<double>(), 1.0);
    EXPECT_GT(baselines[1].at("frame_ms").at("median").get<double>(), 0);
    EXPECT_GT(t.at("speedup_vs_engine_median").get<double>(), 0);
    EXPECT_GE(t.at("adaptive").at("ssim_vs_engine_min").get<double>(), 0.99);
    EXPECT_LT(t.at("adaptive").at("texels_rendered").at("median").get<double>(), 2048.0 * 2048.0);
    EXPECT_EQ(t.at("fixed").at("texels_rendered").at("median").get<double>(), 2048.0 * 2048.0);
    // Error of the visibility against the reference at the orbit's middle frame, for every
    // configuration in the tables; the engine's cascades are closer to it than one fixed map.
    EXPECT_EQ(t.at("reference").at("frames").get<int>(), 1);
    // PCF: 8188² on llvmpipe (16384² textures), 8192² where larger textures fit.
    EXPECT_THAT(t.at("reference").at("description").get<std::string>(),
                HasSubstr(t["technique"] == "pcf"      ? "4 cascades of 81"
                          : PENUMBRA_HAS_RAY_TRACING ? "ray-traced: 16 shadow rays per pixel"
                                                     : "4 cascades of 4096²"));
    // Adaptive against the engine family's Pareto front at equal error: the front's members are
    // marked, the ratios carry an interval around their median over the path's frames.
    const auto& eq = t.at("equal_error");
    for (const char* key : {"time", "memory"}) {
      SCOPED_TRACE(key);
      const auto& side = eq.at(key);
      EXPECT_GE(side.at("front").size(), 1u);
      const auto& ratio = side.at("ratio");
      EXPECT_GT(ratio.at("median").get<double>(), 0);
      EXPECT_LE(ratio.at("ci95")[0].get<double>(), ratio.at("median").get<double>());
      EXPECT_GE(ratio.at("ci95")[1].get<double>(), ratio.at("median").get<double>());
      EXPECT_EQ(ratio.at("frames").get<int>(), 3);
      EXPECT_THAT(side.at("position").get<std::string>(), ::testing::AnyOf("on_front", "more_accurate_than_front", "less_accurate_than_front"));
    }
    EXPECT_EQ(eq.at("adaptive_error").get<double>(), t.at("adaptive").at("reference_error").at("rmse_mean").get<double>());
    int on_time_front = t.at("fixed").at("on_front").at("time").get<bool>() ? 1 : 0;
    for (const auto& b : baselines) on_time_front += b.at("on_front").at("time").get<bool>() ? 1 : 0;
    EXPECT_EQ(on_time_front, static_cast<int>(eq.at("time").at("front").size()));
    EXPECT_TRUE(fs::exists(out / (t["technique"].get<std::string>() + "-crops-gain.png")));
    for (const auto* row : {&t.at("adaptive"), &t.at("fixed"), &baselines[0], &baselines[1]}) {
      const auto& err = row->at("reference_error");
      EXPECT_EQ(err.at("frames").get<int>(), 1);
      EXPECT_GT(err.at("rmse_mean").get<double>(), 0.0);
      EXPECT_LT(err.at("rmse_mean").get<double>(), 0.2);
      EXPECT_GT(err.at("ssim_min").get<double>(), 0.5);
    }
    // Flicker along the path per configuration (3 frames: 2 frame pairs), beside the rule without
    // hysteresis and the floor of a world-fixed map; a fixed map never changes its resolution. Box
    // PCF and PCSS also draw the sun's virtual map three ways.
    const std::size_t configurations = 13;
    const auto& flicker = t.at("flicker");
    ASSERT_EQ(flicker.size(), configurations);
    std::vector<std::string> names;
    for (const auto& f : flicker) {
      SCOPED_TRACE(f.at("configuration").get<std::string>());
      names.push_back(f.at("configuration"));
      EXPECT_EQ(f.at("mean_abs_per_frame").size(), 2u);
      EXPECT_GE(f.at("mean_abs_mean").get<double>(), 0.0);
      EXPECT_LT(f.at("mean_abs_mean").get<double>(), 0.05);
    }
    std::vector<std::string> expected = {"adaptive",        "fixed-2048",      "fixed-4096",      "4x2048-cascades",
                                         "fixed-1024",      "fixed-8192",      "2x2048-cascades", "2x4096-cascades",
                                         "adaptive, no hysteresis", "floor (world-fixed map)"};
    expected.insert(expected.end(), {"virtual rule", "virtual footprint", "virtual rule, cached"});
    EXPECT_EQ(names, expected);
    // The virtual maps, each read against the engine front at its own error, with its pages.
    {
      ASSERT_EQ(t.at("virtual").size(), 3u);
      for (const auto& v : t["virtual"]) {
        SCOPED_TRACE(v.at("name").get<std::string>());
        EXPECT_GT(v.at("equal_error").at("error").get<double>(), 0);
        EXPECT_GT(v.at("equal_error").at("time").at("ratio").at("median").get<double>(), 0);
        EXPECT_GT(v.at("equal_error").at("memory").at("ratio").at("median").get<double>(), 0);
        // The shadow's own cost: the frame above the unshadowed floor, read against the front too.
        EXPECT_GT(v.at("equal_error").at("shadow_cost").at("ratio").at("median").get<double>(), 0);
        EXPECT_LT(v.at("shadow_ms").at("median").get<double>(), v.at("frame_ms").at("median").get<double>());
        EXPECT_GT(t.at("floor").at("frame_ms").at("median").get<double>(), 0);
        EXPECT_GT(v.at("last_frame").at("pages").at("requested").get<int>(), 0);
        EXPECT_EQ(v.at("last_frame").at("shaded_pixels").at("none").get<int>(), 0);
        std::string label = t.at("technique").get<std::string>();
        label.resize(6, ' ');  // the headline's column
        EXPECT_THAT(r.out, HasSubstr(label + " " + v.at("name").get<std::string>() + " at RMSE"));
      }
      const auto& cached = t["virtual"][2].at("last_frame").at("pages");
      EXPECT_LT(cached.at("drawn").get<int>(), cached.at("requested").get<int>()) << "the cached rule keeps the pages the orbit still sees";
    }
    EXPECT_EQ(flicker[1].at("resolution_changes").get<int>(), 0);
    // Texels per frame along the path for every configuration.
    ASSERT_EQ(t.at("along_path").size(), configurations);
    for (const auto& row : t["along_path"]) EXPECT_EQ(row.at("texels").size(), 3u);
    EXPECT_TRUE(fs::exists(out / (t["technique"].get<std::string>() + "-crops.png")));
  }
  EXPECT_THAT(r.out, HasSubstr("flicker along the path"));
  EXPECT_THAT(r.out, HasSubstr("4x2048-cascades"));
  EXPECT_EQ(report.at("techniques")[1].at("adaptive").at("resolution_source"), "pcss_per_pixel");
  std::istringstream csv(test::read_file(out / "frames.csv"));
  std::string line;
  int rows = -1;
  while (std::getline(csv, line)) ++rows;
  EXPECT_EQ(rows, 2 * 3 * 13);  // technique x frame x configuration
  for (const char* plot : {"front.png", "demo.png", "error.png", "flicker.png", "path.png"}) EXPECT_TRUE(fs::exists(out / plot)) << plot;
  EXPECT_EQ(report.at("path"), "orbit");
}

// A configuration equal to the reference (with --fixed-resolution 8188 the sweep's four cascades
// of 8188² are PCF's reference on llvmpipe) shows no perceived difference: FLIP 0 everywhere and
// the frame observer at the guess rate (p_detect 0); a coarser map does show one.
TEST_F(DemoCli, AConfigurationEqualToTheReferenceHasNoPerceivedDifference) {
  const fs::path out = dir_ / "out";
  const auto r = demo({"--headless", "--scene", "demo", "--frames", "1", "--width", "64", "--height", "36", "--techniques", "pcf", "--sweep",
                       "--fixed-resolution", "8188", "--no-virtual", "--no-plot", "-o", out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto report = nlohmann::json::parse(test::read_file(out / "report.json"));
  const auto& t = report.at("techniques")[0];
  const std::string reference = t.at("reference").at("description");
  if (reference.find("4 cascades of 8188²") == std::string::npos) GTEST_SKIP() << "the reference here is " << reference;
  bool seen = false;
  for (const auto& b : t.at("baselines")) {
    SCOPED_TRACE(b.at("name").get<std::string>());
    if (b["name"] == "4x8188-cascades") {
      seen = true;
      EXPECT_EQ(b.at("reference_error").at("rmse_mean").get<double>(), 0.0);
      EXPECT_EQ(b.at("flip").at("mean").get<double>(), 0.0);
      EXPECT_EQ(b.at("flip").at("max_max").get<double>(), 0.0);
      EXPECT_EQ(b.at("observer").at("p_detect_max").get<double>(), 0.0);
      EXPECT_FALSE(b.at("observer").at("visible").get<bool>());
    } else if (b["name"] == "fixed-1024") {
      EXPECT_GT(b.at("flip").at("mean").get<double>(), 0.001);
      EXPECT_GT(b.at("flip").at("max_max").get<double>(), 0.05);
      EXPECT_GT(b.at("observer").at("p_detect_max").get<double>(), 0.0);
    }
  }
  EXPECT_TRUE(seen);
}

// A scene with a camera path is walked along it: --path short visits stations of three
// consecutive frames spread over the whole path (flicker only within a station), --path full
// every frame.
TEST_F(DemoCli, ShortPathVisitsStationsOfTheScenesCameraPath) {
  const fs::path out = dir_ / "outdoor";
  const auto r = demo({"--headless", "--scene", "outdoor", "--frames", "6", "--width", "64", "--height", "36", "--techniques", "pcf",
                       "--no-plot", "--no-baselines", "--no-reference", "-o", out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto report = nlohmann::json::parse(test::read_file(out / "report.json"));
  EXPECT_EQ(report.at("path"), "short");
  EXPECT_EQ(report.at("path_length").get<int>(), 360);
  EXPECT_EQ(report.at("path_frame_index"), nlohmann::json({0, 1, 2, 357, 358, 359}));
  const auto& t = report.at("techniques")[0];
  EXPECT_FALSE(t.contains("reference")) << "--no-reference";
  EXPECT_TRUE(t.at("adaptive").at("reference_error").is_null());
  for (const auto& f : t.at("flicker")) EXPECT_EQ(f.at("mean_abs_per_frame").size(), 4u) << "two pairs per station";
  // The walk at eye height and the overview need different maps: the rule without hysteresis
  // follows at once (with it, a smaller need waits shrink_delay_frames).
  const auto& along = t.at("along_path");
  const auto raw = std::find_if(along.begin(), along.end(), [](const auto& row) { return row.at("configuration") == "adaptive, no hysteresis"; });
  ASSERT_NE(raw, along.end());
  const auto& texels = raw->at("texels");
  EXPECT_NE(texels[0].get<double>(), texels[5].get<double>());
  // The van drives up the street (scene::ObjectPath): the cached virtual map redraws the pages
  // over its old and new place in a station's later frames, fewer than a frame drawn whole.
  const auto row = [&](const std::string& name) {
    const auto it = std::find_if(along.begin(), along.end(), [&](const auto& c) { return c.at("configuration") == name; });
    EXPECT_NE(it, along.end()) << name;
    return *it;
  };
  const auto cached = row("virtual rule, cached"), whole = row("virtual rule");
  EXPECT_FALSE(whole.contains("pages_invalidated")) << "uncached: every page is dropped anyway";
  for (const int k : {1, 2, 4, 5}) {  // a station's second and third frames
    EXPECT_GT(cached.at("pages_invalidated")[k].get<double>(), 0) << "frame index " << k;
    EXPECT_LT(cached.at("pages_drawn")[k].get<double>(), whole.at("pages_drawn")[k].get<double>()) << "frame index " << k;
  }
  EXPECT_THAT(r.err, HasSubstr("frame 359"));  // progress names the path frame (the last one at least)

  const auto bad = demo({"--headless", "--scene", "outdoor", "--path", "half", "--no-plot", "-o", (dir_ / "bad").string()});
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_THAT(bad.err, HasSubstr("--path"));
  EXPECT_FALSE(fs::exists(dir_ / "bad"));
}

// --sweep measures the whole engine family (4 single maps, 3 × 3 cascade configurations) and the
// plots draw a dozen configurations.
TEST_F(DemoCli, SweepMeasuresTheWholeEngineFamilyAndPlotsIt) {
  const fs::path out = dir_ / "sweep";
  const auto r = demo({"--headless", "--scene", "demo", "--frames", "2", "--width", "64", "--height", "36", "--techniques", "pcf",
                       "--sweep", "--no-reference", "-o", out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto report = nlohmann::json::parse(test::read_file(out / "report.json"));
  EXPECT_EQ(report.at("engine_family"), "sweep");
  const auto& t = report.at("techniques")[0];
  std::vector<std::string> family;
  for (const auto& b : t.at("baselines")) family.push_back(b.at("name"));
  EXPECT_EQ(family.size(), 12u);  // 13 with fixed-2048, the fixed map; 4x2048 first (the engine baseline)
  EXPECT_EQ(family.front(), "4x2048-cascades");
  for (const char* name : {"fixed-1024", "fixed-8192", "2x1024-cascades", "3x4096-cascades", "4x4096-cascades"})
    EXPECT_NE(std::find(family.begin(), family.end(), name), family.end()) << name;
  EXPECT_EQ(t.at("equal_error").at("unavailable"), "no reference (--no-reference): no error to compare at");
  EXPECT_THAT(r.out, HasSubstr("pcf    no reference (--no-reference)"));
  for (const char* plot : {"demo.png", "flicker.png", "path.png"}) EXPECT_TRUE(fs::exists(out / plot)) << plot;
}

// --pages (issue 31): the pages a virtual shadow map of the sun marks, by the rule and by the pixel
// footprint (the rule's texel is never finer than the footprint's, so it never marks more pages),
// drawn into the pool from nothing and along the path with the cache. A spot light has no clipmap:
// refused in one line.
TEST_F(DemoCli, PagesCountsTheRulesAndTheFootprintsPages) {
  const fs::path out = dir_ / "pages";
  const auto r = demo({"--pages", "--scene", "outdoor", "--frames", "3", "--width", "96", "--height", "54", "-o", out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto report = nlohmann::json::parse(test::read_file(out / "pages.json"));
  ASSERT_EQ(report.at("techniques").size(), 2u);
  for (const auto& t : report.at("techniques")) {
    ASSERT_EQ(t.at("frames").size(), 3u);
    for (const auto& f : t.at("frames")) {
      EXPECT_GT(f.at("pages_rule").get<int>(), 0);
      EXPECT_LE(f.at("pages_rule").get<int>(), f.at("pages_footprint").get<int>());
      EXPECT_EQ(f.at("unmarked_rule").get<int>(), 0);
      // The pages drawn into the pool: all of them from nothing; along the path only what the
      // cache lacks (the first frame: all).
      for (const char* m : {"rule", "footprint"}) {
        SCOPED_TRACE(m);
        const auto& u = f.at(std::string("uncached_") + m);
        EXPECT_EQ(u.at("drawn").get<int>(), f.at(std::string("pages_") + m).get<int>());
        EXPECT_EQ(u.at("missing").get<int>(), 0);
        EXPECT_GT(u.at("triangles").get<std::int64_t>(), 0);
        const auto& c = f.at(std::string("cached_") + m);
        EXPECT_EQ(c.at("drawn").get<int>() + c.at("cached").get<int>(), c.at("requested").get<int>());
        if (&f == &t.at("frames").front()) {
          EXPECT_EQ(c.at("cached").get<int>(), 0);
        }
      }
    }
    EXPECT_GE(t.at("pages_ratio_footprint_over_rule").at("median").get<double>(), 1.0);
  }
  EXPECT_THAT(r.out, HasSubstr("median footprint / rule pages"));
  // The debug view: each station's levels, rule | footprint, two tiles of 96 px per row (PNG's IHDR).
  const std::string png = test::read_file(out / "levels.png");
  ASSERT_GT(png.size(), 24u);
  const auto be32 = [&](std::size_t at) {
    return (static_cast<unsigned>(static_cast<unsigned char>(png[at])) << 24) | (static_cast<unsigned>(static_cast<unsigned char>(png[at + 1])) << 16) |
           (static_cast<unsigned>(static_cast<unsigned char>(png[at + 2])) << 8) | static_cast<unsigned>(static_cast<unsigned char>(png[at + 3]));
  };
  EXPECT_EQ(png.substr(1, 3), "PNG");
  EXPECT_EQ(be32(16), 2u * 96u);
  EXPECT_GE(be32(20), 2u * 54u) << "a station's row and the key's";
  const auto spot = demo({"--pages", "--scene", "two-planes", "-o", (dir_ / "spot").string()});
  EXPECT_EQ(spot.exit_code, 2) << "the command line must change";
  EXPECT_THAT(spot.err, HasSubstr("--pages: the virtual shadow map is the sun's"));
  EXPECT_FALSE(fs::exists(dir_ / "spot"));
}

// --light-size reaches the renderer: a wider light widens PCSS's penumbrae, so fewer pixels are
// held at the minimum penumbra.
TEST_F(DemoCli, LightSizeOverridesTheScene) {
  auto clamped_share = [&](const std::string& size) {
    const fs::path out = dir_ / ("light-" + size);
    const auto r = demo({"--headless", "--scene", "demo", "--frames", "2", "--width", "192", "--height", "108", "--techniques", "pcss", "--no-plot",
                         "--no-baselines", "--no-reference", "--light-size", size, "-o", out.string()});
    EXPECT_EQ(r.exit_code, 0) << r.err;
    const auto report = nlohmann::json::parse(test::read_file(out / "report.json"));
    EXPECT_EQ(report.at("light").at("size").get<double>(), std::stod(size));
    EXPECT_EQ(report.at("light").at("size_unit"), "deg");
    EXPECT_FALSE(report.at("techniques")[0].contains("baselines")) << "--no-baselines";
    return report.at("techniques")[0].at("adaptive").at("pcss_requirement").at("clamped_fraction").get<double>();
  };
  const double small = clamped_share("3");
  const double large = clamped_share("12");
  EXPECT_GT(small, 0.9);
  EXPECT_LT(large, small - 0.1);
}

// The calibration file sets c unless --adaptive.c is given; report.json records which one was used.
TEST_F(DemoCli, ExplicitAdaptiveCWinsOverTheCalibrationFile) {
  for (const bool explicit_c : {false, true}) {
    SCOPED_TRACE(explicit_c ? "--adaptive.c" : "file");
    const fs::path out = dir_ / (explicit_c ? "explicit" : "file");
    std::vector<std::string> args = {"--headless", "--scene", "demo", "--frames", "1", "--width", "64", "--height", "36", "--techniques", "pcf",
                                     "--fixed-resolution", "256", "--no-plot", "--no-baselines", "-o", out.string()};
    if (explicit_c) args.insert(args.end(), {"--adaptive.c", "6.5"});
    const auto r = demo(args);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto report = nlohmann::json::parse(test::read_file(out / "report.json"));
    const auto& cal = report.at("calibration");
    const double c = explicit_c ? 6.5 : 3.47;
    EXPECT_NEAR(cal.at("c").get<double>(), c, 1e-6);
    EXPECT_EQ(cal.at("source_of_c"), explicit_c ? "--adaptive.c" : "file");
    EXPECT_THAT(cal.at("file").get<std::string>(), ::testing::EndsWith("data/calibration/default.json"));
    EXPECT_EQ(cal.at("bound"), "c");
    EXPECT_NEAR(report.at("techniques")[0].at("settings_adaptive").at("adaptive").at("c").get<double>(), c, 1e-6);
  }
}

// Without the engine family there is no front to read the virtual maps against, but they are
// still measured: report.json lists them with their error against the reference and says why
// there is no equal-error reading.
TEST_F(DemoCli, WithoutBaselinesTheVirtualMapsStillReportTheirError) {
  const fs::path out = dir_ / "virtual-alone";
  const auto r = demo({"--headless", "--scene", "demo", "--frames", "1", "--width", "64", "--height", "36", "--techniques", "pcf",
                       "--fixed-resolution", "256", "--no-plot", "--no-baselines", "-o", out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto report = nlohmann::json::parse(test::read_file(out / "report.json"));
  const auto& t = report.at("techniques")[0];
  ASSERT_EQ(t.at("virtual").size(), 3u);
  for (const auto& v : t.at("virtual")) {
    SCOPED_TRACE(v.at("name").get<std::string>());
    EXPECT_GT(v.at("reference_error").at("rmse_mean").get<double>(), 0);
    EXPECT_THAT(v.at("equal_error").at("why_not").get<std::string>(), HasSubstr("--no-baselines"));
    EXPECT_FALSE(v.at("equal_error").contains("time"));
  }
}

// Issue 29: the demo takes --adaptive.visibility too, says it, and records the c it gives.
TEST_F(DemoCli, AChosenVisibilityGivesItsC) {
  const fs::path out = dir_ / "visibility";
  const auto r = demo({"--headless", "--scene", "demo", "--frames", "1", "--width", "64", "--height", "36", "--techniques", "pcf",
                       "--fixed-resolution", "256", "--no-plot", "--no-baselines", "--adaptive.visibility", "0.1", "-o", out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find(" = 6.82 texels at visibility F = 0.1 (the entry's c 3.47 is at its criterion F = 0.674)"), std::string::npos)
      << r.out;
  const auto report = nlohmann::json::parse(test::read_file(out / "report.json"));
  EXPECT_NEAR(report.at("techniques")[0].at("settings_adaptive").at("adaptive").at("c").get<double>(), 6.817, 1e-3);
}

TEST_F(DemoCli, BadInputIsOneLineAndWritesNothing) {
  const fs::path out = dir_ / "out";
  struct Case {
    std::vector<std::string> args;
    std::string says;
  };
  const Case cases[] = {
      {{"--headless", "--techniques", "pcf,nope"}, "--techniques: expected hard, pcf"},  // issue 45: refused while parsing, exit 2
      {{"--headless", "--techniques", "pcf,pcf"}, "--techniques: 'pcf' is given twice"},
      {{"--headless", "--light-size", "180"}, "--light-size 180: a directional light's angular diameter must lie in [0, 90]"},
      {{"--headless", "--calibration", (dir_ / "missing.json").string()}, "missing.json"},
      {{"--headless", "--pcf.radius", "-1"}, "pcf.radius"},
      {{"--headless", "--scene", "nowhere"}, "nowhere"},
      {{"--headless", "--light-size", "-2"}, "--light-size"},
      // Issue 27: the Python was checked only after the whole run, and "scene ... built" came
      // before an error line; options of a technique not compared were ignored.
      {{"--headless", "--python", (dir_ / "no-python").string()}, "--python"},
      {{"--headless", "--techniques", "pcf", "--vsm.radius", "3"}, "--vsm.radius"},
      {{"--headless", "--calibration", ""}, "--calibration"},
      {{"--headless", "--map.resolution_texels", "512", "--fixed-resolution", "1024"}, "--map.resolution_texels"},
      // FLIP's viewing geometry: a study config with a display block (issue 46).
      {{"--headless", "--display", (dir_ / "no-display.json").string()}, "no-display.json"},
      {{"--headless", "--display", (dir_ / "study.json").string()}, "study.json: display: missing"},
  };
  std::ofstream(dir_ / "study.json") << "{\"trials\": 3}\n";
  for (const auto& c : cases) {
    std::vector<std::string> args = c.args;
    if (std::find(args.begin(), args.end(), "--scene") == args.end()) args.insert(args.end(), {"--scene", "demo"});
    if (std::find(args.begin(), args.end(), "--python") == args.end()) args.push_back("--no-plot");
    args.insert(args.end(), {"--frames", "1", "--width", "32", "--height", "32", "-o", out.string()});
    const auto r = demo(args);
    EXPECT_NE(r.exit_code, 0) << c.says;
    EXPECT_THAT(r.err, HasSubstr(c.says));
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_FALSE(fs::exists(out)) << c.says;
    if (c.says.rfind("--", 0) == 0) {
      EXPECT_EQ(r.exit_code, 2) << c.says << ": the command line must change";
    }
  }
}

// Issue 45: the main job does not time a virtual configuration whose pool missed pages (its frame
// would be that of coarser shadows): one line naming the configuration, the frame and the pool
// that holds the pages, exit 1, nothing written.
TEST_F(DemoCli, AVirtualConfigurationThatMissesPagesIsNotTimed) {
  const fs::path out = dir_ / "small-pool";
  std::vector<std::string> args = {"--headless", "--scene", "demo", "--frames", "1", "--width", "64", "--height", "36",
                                   "--techniques", "pcf", "--fixed-resolution", "256", "--no-plot", "--no-baselines",
                                   "-o", out.string()};
  args.insert(args.end(), {"--map.virtual_pool_pages", "2"});
  const auto r = demo(args);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  const std::string last = r.err.substr(r.err.rfind('\n', r.err.size() - 2) + 1);
  EXPECT_THAT(last, HasSubstr("penumbra-demo: pcf, virtual rule, path frame 0: not timed: virtual shadow map: "));
  EXPECT_THAT(last, HasSubstr("did not fit a pool of 4 slots (--map.virtual_pool_pages 2)"));
  EXPECT_FALSE(fs::exists(out));
}

}  // namespace
}  // namespace penumbra
