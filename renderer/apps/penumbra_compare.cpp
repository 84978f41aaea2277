// penumbra-compare: the perceptual difference of a test image against a reference as LDR-FLIP
// (metrics/flip.h) for a viewer at a stated number of pixels per degree: its pooled values on
// stdout, and with -o DIR the per-pixel map (flip.exr, raw values; flip.png, FLIP's magma colours)
// and flip.json (the same numbers). Beside it the frame observer (metrics/frame_observer.h): the
// probability that a participant of the study tells the test from the reference, per patch of 2°
// and for the frame (the largest patch's), "visible" above a calibration entry's criterion F; with
// -o also detection.json (every patch) and detection.png (the test image, each patch tinted by
// its p_detect). A PNG (any file but OpenEXR) holds sRGB code values; an OpenEXR holds linear RGB,
// clamped to [0, 1] (LDR-FLIP has no tone mapping). docs/compare.md.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "adaptive/calibration.h"
#include "apps/display_geometry.h"
#include "cli/checks.h"
#include "cli/main.h"
#include "io/atomic_file.h"
#include "io/image_io.h"
#include "io/staged_dir.h"
#include "json/json_fields.h"
#include "json/json_input.h"
#include "metrics/flip.h"
#include "metrics/frame_observer.h"
#include "tool/tool.h"

using namespace penumbra;
namespace ji = penumbra::json_input;

namespace {

constexpr const char* kTool = "penumbra-compare";

// OpenEXR's magic number (v/1 and 0x01) at the start of the file decides linear against sRGB,
// not the name.
metrics::Encoding encoding_of(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  char magic[4] = {};
  in.read(magic, 4);
  const bool exr = in.gcount() == 4 && magic[0] == 0x76 && magic[1] == 0x2f && magic[2] == 0x31 && magic[3] == 0x01;
  return exr ? metrics::Encoding::linear : metrics::Encoding::srgb;
}

const char* encoding_name(metrics::Encoding e) { return e == metrics::Encoding::linear ? "linear" : "srgb"; }

io::ImageF read(const std::string& path) {
  io::ImageF img = io::read_imagef(path);
  if (img.width <= 0 || img.height <= 0) throw std::runtime_error(path + ": cannot read image: it has no pixels");
  if (img.channels < 1 || img.channels > 4)
    throw std::runtime_error(path + ": has " + std::to_string(img.channels) + " channels; expected grey, grey and alpha, RGB or RGBA");
  return img;
}

// The criterion F of a calibration file: its entries' threshold.criterion_f (an entry without a
// threshold block has the published design's, 0.6465). Entries that disagree are refused: which
// one a comparison of frames stands for is not the file's to say.
double calibration_criterion(const std::string& file) {
  const adaptive::Calibration calibration = adaptive::load_calibration(file);
  if (calibration.entries.empty()) throw std::runtime_error(file + ": no entries, so no criterion F; give --criterion-f");
  const double f = calibration.entries.front().definition().criterion_f;
  for (const adaptive::CalibrationEntry& e : calibration.entries)
    if (e.definition().criterion_f != f) {
      char line[160];
      std::snprintf(line, sizeof line, ": its entries state different criteria (%s %g, %s %g); give --criterion-f", e.label().c_str(),
                    e.definition().criterion_f, calibration.entries.front().label().c_str(), f);
      throw std::runtime_error(file + line);
    }
  return f;
}

// A luminance in [0, 1] as an sRGB code value.
double linear_to_srgb(double v) { return v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1 / 2.4) - 0.055; }

// The test image with each patch tinted by its p_detect (green 0, yellow at F, red 1), a thin grid
// between patches and a red frame around the patches above F.
io::Image8 detection_image(const io::ImageF& test, metrics::Encoding encoding, const metrics::FrameDetection& d) {
  io::Image8 out{test.width, test.height, 3, std::vector<std::uint8_t>(static_cast<std::size_t>(test.width) * test.height * 3)};
  for (const metrics::PatchDetection& p : d.patches) {
    // green -> yellow over [0, F], yellow -> red over [F, 1]
    const double t = p.p_detect;
    const double tint[3] = {t < d.criterion_f ? t / d.criterion_f : 1.0, t < d.criterion_f ? 1.0 : 1.0 - (t - d.criterion_f) / (1 - d.criterion_f), 0.0};
    const bool seen = p.p_detect > d.criterion_f;
    for (int y = p.y_px; y < p.y_px + p.height_px; ++y)
      for (int x = p.x_px; x < p.x_px + p.width_px; ++x) {
        const int edge = std::min({x - p.x_px, y - p.y_px, p.x_px + p.width_px - 1 - x, p.y_px + p.height_px - 1 - y});
        for (int c = 0; c < 3; ++c) {
          double v = std::clamp(static_cast<double>(test.at(x, y, test.channels < 3 ? 0 : c)), 0.0, 1.0);
          if (encoding == metrics::Encoding::linear) v = linear_to_srgb(v);
          v = 0.65 * v + 0.35 * tint[c];
          if (seen && edge < 2) v = c == 0 ? 1.0 : 0.0;
          else if (edge == 0) v *= 0.6;
          out.at(x, y, c) = static_cast<std::uint8_t>(std::lround(255 * std::clamp(v, 0.0, 1.0)));
        }
      }
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"LDR-FLIP of TEST against REFERENCE: the perceptual difference a viewer flipping between them sees."};
  cli::describe_tool(app, kTool, "compare.md");
  std::string reference_path, test_path, display_config, output;
  double ppd = metrics::kFlipDefaultPixelsPerDegree;
  double threshold = 0.05;
  app.add_option("REFERENCE", reference_path, "reference image (PNG: sRGB; OpenEXR: linear RGB, clamped to [0, 1])")
      ->required()
      ->check(cli::path_given());
  app.add_option("TEST", test_path, "test image, the reference's size")->required()->check(cli::path_given());
  auto* ppd_opt = app.add_option("--ppd", ppd, "pixels per degree of visual angle (default 67.02: FLIP's 0.7 m wide 3840-pixel monitor at 0.7 m)")
                      ->check(cli::finite_range(1, 1000));
  app.add_option("--display", display_config,
                 "pixels per degree from a study config's display block (width_px, width_mm, viewing_distance_mm)")
      ->check(cli::path_given())
      ->excludes(ppd_opt);
  app.add_option("--threshold", threshold, "share of pixels with FLIP above this (default 0.05)")->check(cli::finite_range(0, 1));
  std::string calibration_file = tool::data_file("calibration/default.json").string();
  double criterion_f = NAN;
  metrics::FrameObserverParams observer;
  auto* f_opt = app.add_option("--criterion-f", criterion_f,
                               "detection probability F above which a patch is visible (default: the --calibration entry's)")
                    ->check(cli::finite_range(1e-6, 0.999999));
  app.add_option("--calibration", calibration_file,
                 "calibration.json whose entries' threshold.criterion_f is F (default: the published entry, data/calibration/default.json)")
      ->check(cli::path_given())
      ->excludes(f_opt);
  app.add_option("--patch-deg", observer.patch_deg, "side of the frame observer's square patches, degrees (default 2)")
      ->check(cli::finite_range(0.05, 90));
  app.add_option("-o,--output", output,
                 "write DIR/flip.exr, flip.png, flip.json, detection.json, detection.png (DIR replaced as a whole on success)")
      ->check(cli::path_given());
  if (const auto status = cli::parse(app, argc, argv, kTool)) return *status;
  try {
    std::string ppd_source = app.count("--ppd") ? "--ppd" : "FLIP's default viewer";
    if (!display_config.empty()) {
      ppd = apps::display_pixels_per_degree(display_config, "penumbra-compare");
      ppd_source = "the display of " + display_config;
    }
    // An unusable output is refused before the work (check_output's rule, by the staging itself).
    std::string criterion_from = "--criterion-f";
    if (!app.count("--criterion-f")) {
      criterion_f = calibration_criterion(calibration_file);
      criterion_from = app.count("--calibration") ? "the entries of " + calibration_file : "the published entry, data/calibration/default.json";
    }
    std::optional<io::StagedDirectory> out;
    if (!output.empty()) out.emplace(output, "flip.json");

    const io::ImageF reference = read(reference_path);
    const io::ImageF test = read(test_path);
    if (test.width != reference.width || test.height != reference.height)
      throw std::runtime_error(test_path + ": " + std::to_string(test.width) + "×" + std::to_string(test.height) + " pixels, but the reference " +
                               reference_path + " has " + std::to_string(reference.width) + "×" + std::to_string(reference.height));
    const metrics::Encoding reference_encoding = encoding_of(reference_path), test_encoding = encoding_of(test_path);
    const metrics::FlipResult flip = metrics::ldr_flip(reference, reference_encoding, test, test_encoding, {ppd, threshold});
    const metrics::FlipPooled& p = flip.pooled;
    observer.pixels_per_degree = ppd;
    observer.criterion_f = criterion_f;
    const metrics::FrameDetection seen = metrics::detect_difference(reference, reference_encoding, test, test_encoding, observer);

    std::printf("LDR-FLIP of %s against %s: %d×%d, %.2f px/deg (%s)\n", test_path.c_str(), reference_path.c_str(), reference.width,
                reference.height, ppd, ppd_source.c_str());
    std::printf("mean                   %.6f\n", p.mean);
    std::printf("weighted median        %.6f\n", p.weighted_median);
    std::printf("weighted quartiles     %.6f, %.6f\n", p.weighted_q1, p.weighted_q3);
    std::printf("min, max               %.6f, %.6f\n", p.min, p.max);
    std::printf("share above %-10g %.2f %%\n", p.threshold, 100.0 * p.share_above);
    std::printf("detection probability  %.4f (the largest of %d patches of %g°, %d px: the frame observer)\n", seen.p_detect_max,
                static_cast<int>(seen.patches.size()), observer.patch_deg, seen.patch_px);
    std::printf("patches above F        %d of %d: %s at F = %g (%s)\n", seen.patches_visible, static_cast<int>(seen.patches.size()),
                seen.visible ? "visible" : "not visible", criterion_f, criterion_from.c_str());

    if (out) {
      io::write_exr(out->path() / "flip.exr", flip.map);
      io::write_png(out->path() / "flip.png", metrics::flip_magma(flip.map));
      const nlohmann::json report = {
          {"tool", tool::version_line(kTool)},
          {"metric", "LDR-FLIP (Andersson et al. 2020)"},
          {"reference", {{"path", reference_path}, {"encoding", encoding_name(reference_encoding)}}},
          {"test", {{"path", test_path}, {"encoding", encoding_name(test_encoding)}}},
          {"width", reference.width},
          {"height", reference.height},
          {"pixels_per_degree", ppd},
          {"pixels_per_degree_from", ppd_source},
          {"mean", p.mean},
          {"weighted_median", p.weighted_median},
          {"weighted_q1", p.weighted_q1},
          {"weighted_q3", p.weighted_q3},
          {"min", p.min},
          {"max", p.max},
          {"threshold", p.threshold},
          {"share_above_threshold", p.share_above},
          {"detection_probability", seen.p_detect_max},  // the frame observer's largest patch (detection.json)
          {"visible", seen.visible},
          {"criterion_f", criterion_f},
      };
      io::write_file_atomic(out->path() / "flip.json", ji::dump(report, 2) + "\n");
      nlohmann::json patches = nlohmann::json::array();
      for (const metrics::PatchDetection& q : seen.patches)
        patches.push_back({{"x", q.x_px}, {"y", q.y_px}, {"width", q.width_px}, {"height", q.height_px}, {"deviation", q.deviation},
                           {"p_correct", q.p_correct}, {"p_detect", q.p_detect}, {"visible", q.p_detect > criterion_f}});
      const nlohmann::json detection = {
          {"tool", tool::version_line(kTool)},
          {"model", "frame observer (renderer/metrics/frame_observer.h): 2AFC p_correct = Phi(deviation / (sqrt2 weber)), "
                    "p_detect = (p_correct - 0.5) / 0.5; a model of the study's observer, not measured with people on frames"},
          {"reference", reference_path},
          {"test", test_path},
          {"pixels_per_degree", ppd},
          {"observer", {{"patch_deg", observer.patch_deg}, {"blur_sigma_arcmin", observer.blur_sigma_arcmin},
                        {"window_deg", observer.window_deg}, {"window_max_deg", observer.window_max_deg},
                        {"pool_arcmin", observer.pool_arcmin}, {"contrast_deg", observer.contrast_deg},
                        {"contrast_floor", observer.contrast_floor}, {"black_level", observer.black_level}, {"weber", observer.weber}}},
          {"criterion_f", criterion_f},
          {"criterion_from", criterion_from},
          {"p_detect_max", seen.p_detect_max},
          {"patches_visible", seen.patches_visible},
          {"patches_x", seen.patches_x},
          {"patches_y", seen.patches_y},
          {"patch_px", seen.patch_px},
          {"visible", seen.visible},
          {"patches", patches},
      };
      io::write_file_atomic(out->path() / "detection.json", ji::dump(detection, 2) + "\n");
      io::write_png(out->path() / "detection.png", detection_image(test, test_encoding, seen));
      out->commit();
      std::printf("wrote %s/flip.exr, flip.png, flip.json, detection.json, detection.png\n", output.c_str());
    }
    return 0;
  } catch (const std::exception& e) {
    return cli::fail(kTool, e);
  }
}
