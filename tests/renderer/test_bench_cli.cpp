// penumbra-bench end to end at tiny sizes: the CSV and report.json have their documented shape,
// every technique of the settings table gets rows, a configuration equal to its own reference
// measures zero error, and bad input is refused in one line with nothing written; three shards
// merged equal the unsharded run but for the frame times, and a bad merge writes nothing.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <map>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "shadows/settings.h"
#include "sharded_tool.h"
#include "subprocess.h"

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using ::testing::Not;

namespace penumbra {
namespace {

const std::vector<std::string> kColumns = {
    "scene", "technique", "variant", "filter_radius_ws", "resolution_texels", "adaptive", "width_px", "height_px", "frames",
    "timing_method", "frame_ms_median", "frame_ms_min", "frame_ms_max", "floor_ms", "reference_kind",
    "reference_resolution_texels", "reference_samples", "mean_abs", "rmse", "max_abs", "ssim", "psnr_db",
    "share_above_1_255", "pareto", "pareto_spread", "s_xy", "filter_radius_texels", "resolution_source", "required_texels", "cascades",
    "virtual_pages", "pages_resident", "memory_texels", "settings"};

// Fields of one CSV line; a field in double quotes may hold commas.
std::vector<std::string> csv_fields(const std::string& line) {
  std::vector<std::string> out(1);
  bool quoted = false;
  for (char c : line) {
    if (c == '"') quoted = !quoted;
    else if (c == ',' && !quoted) out.emplace_back();
    else out.back() += c;
  }
  return out;
}

std::vector<std::map<std::string, std::string>> read_csv(const fs::path& p, std::vector<std::string>& header) {
  std::istringstream in(test::read_file(p));
  std::string line;
  std::getline(in, line);
  header = csv_fields(line);
  std::vector<std::map<std::string, std::string>> rows;
  while (std::getline(in, line)) {
    const auto f = csv_fields(line);
    EXPECT_EQ(f.size(), header.size()) << line;
    std::map<std::string, std::string> row;
    for (std::size_t i = 0; i < std::min(f.size(), header.size()); ++i) row[header[i]] = f[i];
    rows.push_back(row);
  }
  return rows;
}

int line_count(const std::string& text) {
  if (text.empty()) return 0;
  const auto n = static_cast<int>(std::count(text.begin(), text.end(), '\n'));
  return text.back() == '\n' ? n : n + 1;
}

class BenchCli : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    tmp_ = fs::temp_directory_path() / ("penumbra-bench-" + std::string(info->name()) + "-" + std::to_string(::getpid()));
    fs::remove_all(tmp_);
    fs::create_directories(tmp_ / "scratch");
    fs::create_directories(tmp_ / "work");
  }
  void TearDown() override {
    std::error_code ec;
    if (!HasFailure()) fs::remove_all(tmp_, ec);
  }
  test::Result bench(std::vector<std::string> args) {
    const std::vector<std::string> tiny = {"--scenes", "two-planes", "--resolutions", "64,256", "--radii", "0.05",
                                           "--reference-resolution", "256", "--area-samples", "4", "--area-resolution", "256",
                                           "--width", "64", "--height", "36", "--frames", "2", "--warmup", "1"};
    // Tiny defaults first, each dropped where the test gives its own value.
    std::vector<std::string> all;
    for (std::size_t i = 0; i + 1 < tiny.size(); i += 2)
      if (std::find(args.begin(), args.end(), tiny[i]) == args.end()) all.insert(all.end(), {tiny[i], tiny[i + 1]});
    args.insert(args.begin(), all.begin(), all.end());
    return test::run_exe(PENUMBRA_BENCH_EXE, args, tmp_ / "scratch");
  }
  fs::path work() const { return tmp_ / "work"; }

  // A refused run: status ≠ 0, one line on stderr naming each needle, nothing in work/.
  void expect_refused(const std::vector<std::string>& args, const std::vector<std::string>& needles) {
    std::vector<std::string> a = args;
    a.insert(a.end(), {"-o", (work() / "out").string()});
    const test::Result r = bench(a);
    EXPECT_NE(r.exit_code, 0);
    EXPECT_EQ(line_count(r.err), 1) << r.err;
    for (const auto& n : needles) EXPECT_THAT(r.err, HasSubstr(n));
    EXPECT_TRUE(fs::is_empty(work())) << "a refused run left output";
  }

  fs::path tmp_;
};

TEST_F(BenchCli, TinyRunWritesTheDocumentedCsvReportAndPlot) {
  const fs::path out = work() / "out";
  const test::Result r = bench({"-o", out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("wrote"));

  std::set<std::string> files;
  for (const auto& e : fs::directory_iterator(out)) files.insert(e.path().filename().string());
  EXPECT_EQ(files, (std::set<std::string>{"bench.csv", "report.json", "pareto-two-planes.png", "pareto-two-planes.svg"}));
  EXPECT_EQ(std::vector<fs::path>(fs::directory_iterator(work()), fs::directory_iterator()).size(), 1u) << "no staging left";

  std::vector<std::string> header;
  const auto rows = read_csv(out / "bench.csv", header);
  EXPECT_EQ(header, kColumns);
  // hard, pcss, ...: one variant each; pcf, vsm: one per radius (one radius here); two
  // resolutions; an adaptive row for the variants the rule applies to.
  const auto techniques = shadows::technique_names();
  std::set<std::string> adaptive_techniques, radius_techniques = {"pcss"};
  for (const auto& row : rows)
    if (!row.at("filter_radius_ws").empty()) radius_techniques.insert(row.at("technique"));
  EXPECT_TRUE(radius_techniques.count("pcf") && radius_techniques.count("vsm"));
  const std::size_t n_rows = 2 * techniques.size() + radius_techniques.size();
  EXPECT_EQ(rows.size(), n_rows);
  EXPECT_THAT(r.err, HasSubstr(std::to_string(n_rows) + "/" + std::to_string(n_rows))) << "progress on stderr";
  std::set<std::string> seen, same_filter_variants;
  std::map<std::string, int> front_size;
  int area_rows = 0;
  for (const auto& row : rows) {
    seen.insert(row.at("technique"));
    EXPECT_EQ(row.at("scene"), "two-planes");
    EXPECT_THAT(row.at("timing_method"), ::testing::AnyOf("wall_finish", "gpu_timer"));
    EXPECT_GT(std::stod(row.at("frame_ms_median")), 0);
    EXPECT_LE(std::stod(row.at("frame_ms_min")), std::stod(row.at("frame_ms_median")));
    EXPECT_GE(std::stod(row.at("frame_ms_max")), std::stod(row.at("frame_ms_median")));
    EXPECT_GT(std::stod(row.at("floor_ms")), 0);
    EXPECT_EQ(row.at("frames"), "2");
    const double ssim = std::stod(row.at("ssim")), mean_abs = std::stod(row.at("mean_abs"));
    EXPECT_GE(mean_abs, 0);
    EXPECT_LE(std::stod(row.at("max_abs")), 1);
    EXPECT_LE(ssim, 1 + 1e-9);
    front_size[row.at("variant")] += row.at("pareto") == "1";
    if (row.at("adaptive") == "1") {
      adaptive_techniques.insert(row.at("technique"));
      EXPECT_THAT(row.at("resolution_source"), ::testing::AnyOf("rule", "pcss_per_pixel", "pcss_min_penumbra"));
      const double required = std::stod(row.at("required_texels")), res = std::stod(row.at("resolution_texels"));
      EXPECT_GT(required, 0);
      // Rounded up to the quantum and clamped to [adaptive.min_texels, adaptive.max_texels].
      EXPECT_TRUE(res >= std::min(required, 4096.0) && res <= 4096 && res >= 32) << res << " for " << required;
      continue;  // the reference-resolution checks below are for fixed rows
    }
    EXPECT_EQ(row.at("resolution_source"), "fixed");
    if (row.at("technique") == "pcss") {
      EXPECT_EQ(row.at("reference_kind"), "area_light");
      EXPECT_GT(mean_abs, 0) << "PCSS is not the area-light average";
    }
    if (row.at("reference_kind") == "area_light") {
      ++area_rows;
      EXPECT_EQ(row.at("reference_samples"), "4");
      EXPECT_EQ(row.at("filter_radius_ws"), "");
    } else {
      same_filter_variants.insert(row.at("variant"));
      EXPECT_EQ(row.at("reference_kind"), "same_filter");
      EXPECT_EQ(row.at("reference_resolution_texels"), "256");
      if (row.at("resolution_texels") == "256") {
        // The reference configuration itself: the same settings at the reference's size.
        EXPECT_EQ(mean_abs, 0) << row.at("variant");
        EXPECT_EQ(std::stod(row.at("max_abs")), 0) << row.at("variant");
        EXPECT_EQ(ssim, 1) << row.at("variant");
        EXPECT_EQ(row.at("psnr_db"), "inf");
      }
    }
    if (row.at("technique") == "pcf" || row.at("technique") == "vsm") {
      EXPECT_EQ(row.at("filter_radius_ws"), "0.05");
      EXPECT_THAT(row.at("settings"), HasSubstr("radius_unit=world"));
    }
  }
  EXPECT_EQ(seen, std::set<std::string>(techniques.begin(), techniques.end())) << "every technique of the table gets rows";
  EXPECT_EQ(adaptive_techniques, radius_techniques) << "an adaptive row for each filter the rule applies to";
  // `pareto` within a variant: a row off the front is beaten by another row (no slower, no less
  // accurate); the fastest row, and the fastest of the most accurate, are on it.
  for (const auto& [variant, n] : front_size) {
    std::vector<std::pair<double, double>> pts;  // (ms, error)
    std::vector<bool> front;
    for (const auto& row : rows) {
      if (row.at("variant") != variant) continue;
      pts.emplace_back(std::stod(row.at("frame_ms_median")), std::stod(row.at("mean_abs")));
      front.push_back(row.at("pareto") == "1");
    }
    std::size_t fastest = 0, best = 0;
    for (std::size_t i = 0; i < pts.size(); ++i) {
      if (pts[i].first < pts[fastest].first) fastest = i;
      if (pts[i].second < pts[best].second || (pts[i].second == pts[best].second && pts[i].first < pts[best].first)) best = i;
      if (front[i]) continue;
      bool beaten = false;
      for (std::size_t j = 0; j < pts.size(); ++j)
        beaten |= j != i && pts[j].first <= pts[i].first && pts[j].second <= pts[i].second;
      EXPECT_TRUE(beaten) << variant << " row " << i;
    }
    EXPECT_TRUE(front[fastest]) << variant;
    EXPECT_TRUE(front[best]) << variant;
  }
  // `pareto_spread`: frame-time ranges [min, max] that overlap are a tie. A row is off that front
  // exactly when another row is no less accurate, not slower beyond the spread, and more accurate
  // or faster beyond it.
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const auto& a = rows[i];
    bool beaten = false;
    for (std::size_t j = 0; j < rows.size(); ++j) {
      const auto& b = rows[j];
      if (j == i || b.at("variant") != a.at("variant")) continue;
      const double ae = std::stod(a.at("mean_abs")), be = std::stod(b.at("mean_abs"));
      const bool b_faster = std::stod(b.at("frame_ms_max")) < std::stod(a.at("frame_ms_min"));
      const bool b_slower = std::stod(b.at("frame_ms_min")) > std::stod(a.at("frame_ms_max"));
      beaten |= be <= ae && !b_slower && (be < ae || b_faster);
    }
    EXPECT_EQ(a.at("pareto_spread") == "1", !beaten) << a.at("variant") << " row " << i;
  }

  const nlohmann::json report = nlohmann::json::parse(test::read_file(out / "report.json"));
  EXPECT_EQ(report.at("tool"), "penumbra-bench");
  int adaptive_rows = 0, on_front = 0, on_spread_front = 0;
  for (const auto& row : rows)
    if (row.at("adaptive") == "1") ++adaptive_rows, on_front += row.at("pareto") == "1", on_spread_front += row.at("pareto_spread") == "1";
  EXPECT_EQ(report.at("adaptive_on_front"),
            (nlohmann::json{{"rows", adaptive_rows}, {"pareto", on_front}, {"pareto_spread", on_spread_front}}));
  EXPECT_THAT(r.out, HasSubstr("adaptive rows on their variant's Pareto front: " + std::to_string(on_front) + " of " +
                               std::to_string(adaptive_rows)));
  EXPECT_EQ(report.at("rows").size(), rows.size());
  ASSERT_EQ(report.at("scenes").size(), 1u);
  // One area-light reference per scene, shared by every soft-shadow technique; one per other variant.
  EXPECT_GT(area_rows, 0);
  EXPECT_EQ(report.at("scenes")[0].at("references").size(), same_filter_variants.size() + 1);
  EXPECT_GT(report.at("scenes")[0].at("floor_ms").at("median").get<double>(), 0);
  EXPECT_EQ(report.at("rows")[0].at("frame_ms").size(), 2u);
  // What each row gave the GPU to do (issue 47): every row shades its pixels; a shadow-map row
  // rasterizes texels, and more of them at a larger resolution of the same variant.
  std::map<std::string, std::map<int, std::uint64_t>> map_fragments;  // variant, resolution
  for (const auto& row : report.at("rows")) {
    const auto& work = row.at("work");
    ASSERT_TRUE(work.contains("shading")) << row.dump();
    EXPECT_GT(work.at("shading").at("fragments").get<std::uint64_t>(), 0u);
    // What the shading's lookups read per pixel shown: at least one texture instruction of at least 4 bytes.
    const auto& reads = work.at("shading_reads");
    EXPECT_GT(reads.at("pixels").get<std::uint64_t>(), 0u);
    EXPECT_GE(reads.at("instructions_per_pixel").get<double>(), 1.0);
    EXPECT_GE(reads.at("bytes_per_pixel").get<double>(), 4 * reads.at("instructions_per_pixel").get<double>());
    if (work.contains("shadow_map") && !row.at("adaptive").get<bool>())
      map_fragments[row.at("variant").get<std::string>()][row.at("resolution_texels").get<int>()] =
          work.at("shadow_map").at("fragments").get<std::uint64_t>();
  }
  int ordered = 0;
  for (const auto& [variant, by_resolution] : map_fragments) {
    const std::pair<const int, std::uint64_t>* coarser = nullptr;
    for (const auto& finer : by_resolution) {
      if (coarser) {
        EXPECT_LT(coarser->second, finer.second) << variant << " at " << coarser->first << " vs " << finer.first;
        ++ordered;
      }
      coarser = &finer;
    }
  }
  EXPECT_GT(ordered, 0) << "two resolutions of a shadow-map variant";
  EXPECT_TRUE(report.contains("device"));
  const auto png = fs::file_size(out / "pareto-two-planes.png");
  EXPECT_GT(png, 10000u) << "a real plot";
}

// The sun's virtual shadow map: under a sun (demo), the filters that read pages (box PCF with a
// world radius, PCSS with a box filter) get a row with pages marked by the rule and one by the
// footprint, measured against the variant's reference and ranked on its front; a spot-lit scene
// (two-planes) gets none, and --no-virtual leaves them out.
TEST_F(BenchCli, VirtualMapRowsForTheFiltersThatReadPagesUnderASun) {
  const fs::path out = work() / "out";
  const std::vector<std::string> args = {"--scenes", "demo,two-planes", "--techniques", "pcf,pcss", "--pcf.kernel", "grid",
                                         "--pcss.kernel", "grid", "--resolutions", "64", "--no-adaptive", "--no-plot"};
  std::vector<std::string> a = args;
  a.insert(a.end(), {"-o", out.string()});
  const test::Result r = bench(a);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::vector<std::string> header;
  const auto rows = read_csv(out / "bench.csv", header);
  // Per scene: pcf r=0.05 and pcss at 64²; demo adds two virtual rows to each.
  ASSERT_EQ(rows.size(), 2u + 2u + 4u);
  EXPECT_THAT(r.err, HasSubstr("+ 4 virtual = 8 rows"));
  std::map<std::string, std::set<std::string>> markings;  // variant -> rule, footprint
  std::map<std::string, std::string> map_reference;       // variant -> the 64² row's reference
  for (const auto& row : rows)
    if (row.at("virtual_pages").empty()) {
      EXPECT_EQ(row.at("resolution_source"), "fixed");
      EXPECT_EQ(row.at("pages_resident"), "0");
      EXPECT_EQ(std::stod(row.at("memory_texels")), 64.0 * 64.0) << "a 64² atlas";
      map_reference[row.at("scene") + row.at("variant")] = row.at("reference_kind") + row.at("reference_resolution_texels");
    }
  for (const auto& row : rows) {
    if (row.at("virtual_pages").empty()) continue;
    EXPECT_EQ(row.at("scene"), "demo") << "two-planes is lit by a spot";
    markings[row.at("variant")].insert(row.at("virtual_pages"));
    EXPECT_EQ(row.at("resolution_source"), "virtual_" + row.at("virtual_pages"));
    EXPECT_EQ(row.at("resolution_texels"), "0");
    EXPECT_EQ(row.at("cascades"), "0");
    EXPECT_EQ(row.at("adaptive"), "0");
    const int pages = std::stoi(row.at("pages_resident"));
    EXPECT_GT(pages, 0);
    // The resident pages (128² texels of 4 bytes) and the tables: more than the pages alone.
    EXPECT_GT(std::stod(row.at("memory_texels")), pages * 128.0 * 128.0);
    EXPECT_EQ(row.at("reference_kind") + row.at("reference_resolution_texels"), map_reference.at(row.at("scene") + row.at("variant")))
        << "the variant's own reference";
    const double mean_abs = std::stod(row.at("mean_abs"));
    EXPECT_TRUE(mean_abs >= 0 && mean_abs < 0.1) << row.at("variant") << " " << row.at("virtual_pages") << ": " << mean_abs;
  }
  EXPECT_EQ(markings, (std::map<std::string, std::set<std::string>>{{"pcf r=0.05", {"rule", "footprint"}}, {"pcss", {"rule", "footprint"}}}));
  const nlohmann::json report = nlohmann::json::parse(test::read_file(out / "report.json"));
  EXPECT_EQ(report.at("virtual_on_front").at("rows"), 4);
  int on_front = 0;
  for (const auto& row : rows) on_front += !row.at("virtual_pages").empty() && row.at("pareto") == "1";
  EXPECT_EQ(report.at("virtual_on_front").at("pareto"), on_front);
  EXPECT_THAT(r.out, HasSubstr("virtual map rows on their variant's Pareto front: " + std::to_string(on_front) + " of 4"));

  a = args;
  a.insert(a.end(), {"--no-virtual", "-o", (work() / "none").string()});
  const test::Result none = bench(a);
  ASSERT_EQ(none.exit_code, 0) << none.err;
  EXPECT_EQ(read_csv(work() / "none" / "bench.csv", header).size(), 4u) << "no virtual rows";
  EXPECT_THAT(none.out, Not(HasSubstr("virtual map rows")));
}

TEST_F(BenchCli, NoPlotAndNoAdaptiveWriteNeither) {
  const fs::path out = work() / "out";
  const test::Result r = bench({"--techniques", "hard,pcf", "--no-plot", "--no-adaptive", "-o", out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::vector<std::string> header;
  EXPECT_EQ(read_csv(out / "bench.csv", header).size(), 4u) << "no adaptive rows";
  std::set<std::string> files;
  for (const auto& e : fs::directory_iterator(out)) files.insert(e.path().filename().string());
  EXPECT_EQ(files, (std::set<std::string>{"bench.csv", "report.json"}));
}

TEST_F(BenchCli, BadInputIsRefusedInOneLineWithNothingWritten) {
  expect_refused({"--techniques", "pcf,fancy"}, {"--techniques", "fancy"});
  expect_refused({"--resolutions", "64,0"}, {"--resolutions", "'64,0'"});
  expect_refused({"--radii", "-1"}, {"--radii", "'-1'"});
  expect_refused({"--scenes", "no-such-scene"}, {"no-such-scene"});
  expect_refused({"--frames", "0"}, {"--frames"});
  expect_refused({"--pcf.kernel", "hexagon"}, {"--pcf.kernel", "hexagon"});
  expect_refused({"--plot-script", "/nonexistent/plot.py"}, {"--plot-script", "/nonexistent/plot.py"});
  expect_refused({"--resolutions", "65536"}, {"GL_MAX_TEXTURE_SIZE"});
  expect_refused({"--timing", "gpu"}, {"--timing", "gpu"});
}

TEST_F(BenchCli, TimingWallFinishIsTheWallClockOnEveryDevice) {
  const fs::path out = work() / "out";
  const test::Result r = bench({"--techniques", "hard", "--no-plot", "--no-adaptive", "--timing", "wall_finish", "-o", out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto report = nlohmann::json::parse(test::read_file(out / "report.json"));
  EXPECT_EQ(report.at("timing_method"), "wall_finish");
  for (const auto& row : report.at("rows")) EXPECT_EQ(row.at("timing_method"), "wall_finish");
}

// --calibration is read and recorded in report.json; an explicit --adaptive.c wins over the file.
TEST_F(BenchCli, CalibrationIsRecordedAndExplicitAdaptiveCWins) {
  const fs::path cal_file = tmp_ / "scratch" / "calibration.json";
  { std::ofstream(cal_file) << R"({"c": 4.25, "ci95": [3.5, 5.0]})" << "\n"; }
  const fs::path out = work() / "out";
  const std::vector<std::string> tiny = {"--techniques", "pcf", "--resolutions", "64", "--no-plot", "-o", out.string()};
  struct Case {
    std::vector<std::string> extra;
    std::string file_ends;
    double c;
    std::string source;
  };
  std::vector<double> required_per_c;
  for (const Case& c : {Case{{}, "data/calibration/default.json", 3.47, "file"},
                        Case{{"--calibration", cal_file.string()}, "calibration.json", 4.25, "file"},
                        Case{{"--calibration", cal_file.string(), "--adaptive.c", "6.5"}, "calibration.json", 6.5, "--adaptive.c"}}) {
    SCOPED_TRACE(c.source + " " + c.file_ends);
    std::vector<std::string> args = tiny;
    args.insert(args.end(), c.extra.begin(), c.extra.end());
    const test::Result r = bench(args);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const nlohmann::json report = nlohmann::json::parse(test::read_file(out / "report.json"));
    const auto& cal = report.at("calibration");
    EXPECT_THAT(cal.at("file").get<std::string>(), ::testing::EndsWith(c.file_ends));
    EXPECT_NEAR(cal.at("c").get<double>(), c.c, 1e-6);
    EXPECT_EQ(cal.at("source_of_c"), c.source);
    // The published entry has no interval (null); the file's entry has its own.
    if (c.file_ends == "data/calibration/default.json")
      EXPECT_TRUE(cal.at("ci95").is_null()) << cal.at("ci95");
    else
      EXPECT_EQ(cal.at("ci95").size(), 2u);
    // The rule used that c: the adaptive row's requirement is c · L_ws / r_ws, the same scene and
    // radius in every case.
    int adaptive_rows = 0;
    for (const auto& row : report.at("rows"))
      if (row.at("adaptive").get<bool>()) {
        ++adaptive_rows;
        required_per_c.push_back(row.at("required_texels").get<double>() / c.c);
      }
    EXPECT_EQ(adaptive_rows, 1);
  }
  ASSERT_EQ(required_per_c.size(), 3u);
  EXPECT_NEAR(required_per_c[1] / required_per_c[0], 1.0, 1e-4);
  EXPECT_NEAR(required_per_c[2] / required_per_c[0], 1.0, 1e-4);
}

// Issue 29: the bench's adaptive rows take --adaptive.visibility, and say the c it gives.
TEST_F(BenchCli, AChosenVisibilityGivesItsC) {
  const fs::path out = work() / "visibility";
  const test::Result r = bench({"--techniques", "pcf", "--resolutions", "64", "--no-plot", "--adaptive.visibility", "0.1", "-o", out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("texels at visibility F = 0.1"), std::string::npos) << r.out;
  const nlohmann::json report = nlohmann::json::parse(test::read_file(out / "report.json"));
  EXPECT_NEAR(report.at("calibration").at("c").get<double>(), 6.817, 1e-3);
}

TEST_F(BenchCli, BadCalibrationFileIsRefusedWithNothingWritten) {
  const fs::path bad = tmp_ / "scratch" / "bad-calibration.json";
  { std::ofstream(bad) << R"({"c": -1})" << "\n"; }
  expect_refused({"--calibration", bad.string()}, {bad.string(), ": c:"});
  expect_refused({"--calibration", (tmp_ / "scratch" / "missing.json").string()}, {"missing.json"});
}

TEST_F(BenchCli, ForeignDirectoryIsLeftUntouched) {
  const fs::path out = work() / "out";
  fs::create_directories(out);
  { std::ofstream(out / "notes.txt") << "mine\n"; }
  const test::Result r = bench({"--techniques", "hard", "--no-plot", "-o", out.string()});
  EXPECT_NE(r.exit_code, 0);
  EXPECT_EQ(line_count(r.err), 1) << r.err;
  EXPECT_THAT(r.err, HasSubstr(out.string()));
  EXPECT_EQ(test::read_file(out / "notes.txt"), "mine\n");
}


// --shard I/N --part FILE and `penumbra-bench merge` (docs/cluster.md): four techniques, two of
// which share the area-light reference, so that a shard may make it for either.
class BenchShards : public BenchCli {
 protected:
  test::Result bench_grid(std::vector<std::string> args) {
    args.insert(args.begin(), grid_.begin(), grid_.end());
    return bench(args);
  }
  test::Result merge(std::vector<std::string> args) { return test::run_merge(PENUMBRA_BENCH_EXE, std::move(args), tmp_ / "scratch"); }
  // Shard i of n of the grid into work()/part-i-of-n.json.
  fs::path part(int i, int n, std::vector<std::string> extra = {}) {
    return test::make_part([this](std::vector<std::string> args) { return bench_grid(std::move(args)); }, work(), i, n, std::move(extra));
  }
  void expect_refused(const std::vector<fs::path>& parts, const std::string& needle) {
    test::expect_merge_refused(PENUMBRA_BENCH_EXE, tmp_ / "scratch", work(), parts, needle);
  }
  // The grid unsharded, in 3 shards and merged (parts out of order): every non-timing field equal.
  void expect_three_shards_merge_to_the_unsharded_run(std::size_t rows);
  std::vector<std::string> grid_ = {"--techniques", "hard,pcf,pcss,erosion", "--no-plot"};
};

// Frame times (and the Pareto marks drawn from them, the floor, the references' render time and
// the run's elapsed seconds) are measurements; everything else is the same text.
const std::set<std::string> kTimingColumns = {"frame_ms_median", "frame_ms_min", "frame_ms_max", "floor_ms", "pareto", "pareto_spread"};

nlohmann::json without_timing(nlohmann::json report) {
  for (const char* key : {"elapsed_s", "adaptive_on_front", "virtual_on_front"}) report.erase(key);
  for (auto& scene : report.at("scenes")) {
    scene.erase("floor_ms");
    for (auto& reference : scene.at("references")) reference.erase("render_ms");
  }
  for (auto& row : report.at("rows"))
    for (const char* key : {"frame_ms", "frame_ms_median", "floor_ms", "pareto", "pareto_spread"}) row.erase(key);
  return report;
}

void BenchShards::expect_three_shards_merge_to_the_unsharded_run(std::size_t n_rows) {
  const fs::path full = work() / "full", merged = work() / "merged";
  const test::Result whole = bench_grid({"-o", full.string()});
  ASSERT_EQ(whole.exit_code, 0) << whole.err;
  std::vector<fs::path> parts;
  for (int i = 0; i < 3; ++i) parts.push_back(part(i, 3));
  EXPECT_FALSE(fs::exists(work() / "out")) << "a shard writes its part alone";
  // The rule: row k is shard k mod 3's, whatever the rows' techniques.
  const auto part0 = nlohmann::json::parse(test::read_file(parts[0]));
  std::vector<std::size_t> items, every_third;
  for (const auto& row : part0.at("payload").at("rows")) items.push_back(row.at("item").get<std::size_t>());
  for (std::size_t k = 0; k < n_rows; k += 3) every_third.push_back(k);
  EXPECT_EQ(items, every_third);

  const test::Result m = merge({parts[2].string(), parts[0].string(), parts[1].string(), "-o", merged.string()});
  ASSERT_EQ(m.exit_code, 0) << m.err;
  EXPECT_THAT(m.out, HasSubstr("wrote " + merged.string() + "/ (" + std::to_string(n_rows) + " rows)"));

  std::vector<std::string> header_full, header_merged;
  const auto rows_full = read_csv(full / "bench.csv", header_full), rows_merged = read_csv(merged / "bench.csv", header_merged);
  EXPECT_EQ(header_merged, header_full);
  ASSERT_EQ(rows_merged.size(), n_rows);
  ASSERT_EQ(rows_merged.size(), rows_full.size());
  for (std::size_t k = 0; k < rows_full.size(); ++k)
    for (const auto& [column, value] : rows_full[k])
      if (!kTimingColumns.count(column)) {
        EXPECT_EQ(rows_merged[k].at(column), value) << "row " << k << ", " << column;
      }
  // The merged times are the parts' own, and the front is drawn over them: some row is on it.
  int front = 0;
  for (const auto& row : rows_merged) front += row.at("pareto") == "1";
  EXPECT_GT(front, 0);

  nlohmann::json report_full = nlohmann::json::parse(test::read_file(full / "report.json"));
  nlohmann::json report_merged = nlohmann::json::parse(test::read_file(merged / "report.json"));
  // The command as the unsharded run records it, with the merge's -o.
  EXPECT_THAT(report_full.at("command").get<std::string>(), HasSubstr(" -o " + full.string()));
  std::string command = report_full.at("command").get<std::string>();
  command.replace(command.find(" -o " + full.string()), 4 + full.string().size(), " -o " + merged.string());
  EXPECT_EQ(report_merged.at("command"), command);
  report_full.erase("command");
  report_merged.erase("command");
  EXPECT_EQ(without_timing(report_merged).dump(1), without_timing(report_full).dump(1));
  EXPECT_EQ(report_merged.at("scenes").at(0).at("references").size(), report_full.at("scenes").at(0).at("references").size());
}

TEST_F(BenchShards, ThreeShardsMergedEqualTheUnshardedRunApartFromTimes) { expect_three_shards_merge_to_the_unsharded_run(10); }

// The virtual map's rows (pages resident, the page tables' memory) under the demo scene's sun.
TEST_F(BenchShards, VirtualMapRowsMergeToo) {
  grid_ = {"--scenes", "demo,two-planes", "--techniques", "pcf,pcss", "--pcf.kernel", "grid", "--pcss.kernel", "grid",
           "--resolutions", "64", "--no-adaptive", "--no-plot"};
  expect_three_shards_merge_to_the_unsharded_run(8);
}

TEST_F(BenchShards, AMergeOfMissingTwiceOrForeignPartsIsRefusedWithNothingWritten) {
  // Other settings (one more frame per row), made first: the part's name is the shard's.
  const fs::path other = work() / "other.json";
  fs::rename(part(1, 3, {"--frames", "3"}), other);
  const fs::path p0 = part(0, 3), p1 = part(1, 3), p2 = part(2, 3);
  expect_refused({p0, p2}, "shard 1/3 missing");
  expect_refused({p0, p1, p2, p1}, p1.string() + ": shard 1/3 again");
  const fs::path copy = work() / "copy-of-1.json";
  fs::copy_file(p1, copy);
  expect_refused({p0, p1, copy, p2}, copy.string() + ": shard 1/3 again");
  expect_refused({p0, other, p2}, other.string() + ": made with other settings");
  // Another shard count.
  const fs::path half = part(1, 2);
  expect_refused({p0, half, p2}, half.string() + ": shard 1/2, but");
  // Another tool's part, and a part edited after it was written.
  const fs::path edited = work() / "edited.json";
  std::string text = test::read_file(p1);
  text.replace(text.find("\"--frames\""), 10, "\"--warmup\"");
  { std::ofstream(edited) << text; }
  expect_refused({p0, edited, p2}, edited.string() + ": its settings do not match its fingerprint");
}

TEST_F(BenchShards, BadShardOptionsAreRefusedNamingTheOption) {
  const std::string part_file = (work() / "p.json").string();
  const test::ToolRun run = [this](std::vector<std::string> args) { return bench_grid(std::move(args)); };
  for (const std::string shard : {"0/0", "3/2", "junk", "1/", "-1/2"})
    test::expect_usage_refused(run, {"--shard", shard, "--part", part_file}, "--shard");
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{"--shard", "0/2"}, "--shard: needs --part"},
      {{"--part", part_file, "-o", (work() / "out").string()}, "--part: only with --shard"},
      {{"--shard", "0/2", "--part", part_file, "-o", (work() / "out").string()}, "--output: a shard writes a part"},
      {{}, "--output is required"}};
  for (const auto& [args, needle] : cases) test::expect_usage_refused(run, args, needle);
  EXPECT_TRUE(fs::is_empty(work())) << "a refused shard wrote something";
}

}  // namespace
}  // namespace penumbra
