// penumbra-compare: the perceptual difference of a test image against a reference as LDR-FLIP
// (metrics/flip.h) for a viewer at a stated number of pixels per degree: its pooled values on
// stdout, and with -o DIR the per-pixel map (flip.exr, raw values; flip.png, FLIP's magma colours)
// and flip.json (the same numbers). A PNG (any file but OpenEXR) holds sRGB code values; an
// OpenEXR holds linear RGB, clamped to [0, 1] (LDR-FLIP has no tone mapping). docs/compare.md.
#include <CLI/CLI.hpp>

#include <cstdio>
#include <fstream>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "cli/checks.h"
#include "cli/main.h"
#include "io/atomic_file.h"
#include "io/image_io.h"
#include "io/staged_dir.h"
#include "json/json_fields.h"
#include "json/json_input.h"
#include "metrics/flip.h"
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

// Pixels per degree from a study config's display block (data/studies/*.json, docs/study-config.md):
// width_px, width_mm and viewing_distance_mm, each required here (the study would take its
// defaults for a missing one; a comparison should not rest on a silent default).
double display_pixels_per_degree(const std::string& file) {
  const nlohmann::json j = ji::read_file(file);
  const ji::Reader r(file);
  auto number = [](const char* name, const char* unit) {
    ji::Field f;
    f.name = name;
    f.type = std::string(name) == "width_px" ? ji::Type::integer : ji::Type::number;
    f.required = true;
    f.why = "penumbra-compare takes the viewing geometry from it";
    f.min = 1;
    f.max = 100000;
    f.unit = unit;
    return f;
  };
  ji::ObjectSpec display{{number("width_px", ""), number("width_mm", "mm"), number("viewing_distance_mm", "mm")}, false};
  ji::Field block;
  block.name = "display";
  block.type = ji::Type::object;
  block.required = true;
  block.why = "a study config's display block: width_px, width_mm, viewing_distance_mm";
  block.object = ji::spec(display);
  if (!j.is_object()) r.fail("", "expected an object (a study config), got " + ji::describe(j));
  const nlohmann::json* d = r.get(j, "", block);
  return metrics::pixels_per_degree(r.number(*d, "display", display, "width_px"), r.number(*d, "display", display, "width_mm") / 1000.0,
                                    r.number(*d, "display", display, "viewing_distance_mm") / 1000.0);
}

io::ImageF read(const std::string& path) {
  io::ImageF img = io::read_imagef(path);
  if (img.width <= 0 || img.height <= 0) throw std::runtime_error(path + ": cannot read image: it has no pixels");
  if (img.channels < 1 || img.channels > 4)
    throw std::runtime_error(path + ": has " + std::to_string(img.channels) + " channels; expected grey, grey and alpha, RGB or RGBA");
  return img;
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
  app.add_option("-o,--output", output, "write DIR/flip.exr, DIR/flip.png, DIR/flip.json (DIR replaced as a whole on success)")
      ->check(cli::path_given());
  if (const auto status = cli::parse(app, argc, argv, kTool)) return *status;
  try {
    std::string ppd_source = app.count("--ppd") ? "--ppd" : "FLIP's default viewer";
    if (!display_config.empty()) {
      ppd = display_pixels_per_degree(display_config);
      ppd_source = "the display of " + display_config;
    }
    // An unusable output is refused before the work (check_output's rule, by the staging itself).
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

    std::printf("LDR-FLIP of %s against %s: %d×%d, %.2f px/deg (%s)\n", test_path.c_str(), reference_path.c_str(), reference.width,
                reference.height, ppd, ppd_source.c_str());
    std::printf("mean                   %.6f\n", p.mean);
    std::printf("weighted median        %.6f\n", p.weighted_median);
    std::printf("weighted quartiles     %.6f, %.6f\n", p.weighted_q1, p.weighted_q3);
    std::printf("min, max               %.6f, %.6f\n", p.min, p.max);
    std::printf("share above %-10g %.2f %%\n", p.threshold, 100.0 * p.share_above);
    // The observer's probability of seeing the difference is the image observer's (issue 46, a
    // later part); FLIP alone does not give it.
    std::printf("detection probability  not computed (no observer model on frames yet)\n");

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
          {"detection_probability", nullptr},  // the image observer's, not yet (docs/compare.md)
      };
      io::write_file_atomic(out->path() / "flip.json", ji::dump(report, 2) + "\n");
      out->commit();
      std::printf("wrote %s/flip.exr, flip.png, flip.json\n", output.c_str());
    }
    return 0;
  } catch (const std::exception& e) {
    return cli::fail(kTool, e);
  }
}
