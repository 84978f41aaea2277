// penumbra-compare as a user runs it: pooled values on stdout, the map in -o DIR (raw values in
// flip.exr, magma colours in flip.png, the numbers in flip.json), pixels per degree from a study
// config's display, and one line with exit 1 for mismatched sizes or a file it cannot read.
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "io/image_io.h"
#include "subprocess.h"

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using ::testing::Not;

namespace {

class CompareCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("penumbra-compare-test-" + std::to_string(::getpid()) + "-" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  penumbra::test::Result compare(const std::vector<std::string>& args) { return penumbra::test::run_exe(PENUMBRA_COMPARE_EXE, args, dir_); }

  // A grey square of `value` on black, `w`×`h`, RGB.
  fs::path png(const std::string& name, int w, int h, std::uint8_t value, int square_x) {
    penumbra::io::Image8 img{w, h, 3, std::vector<std::uint8_t>(static_cast<std::size_t>(w) * h * 3, 0)};
    for (int y = h / 4; y < 3 * h / 4; ++y)
      for (int x = square_x; x < square_x + w / 2; ++x)
        for (int c = 0; c < 3; ++c) img.at(x, y, c) = value;
    const fs::path p = dir_ / name;
    penumbra::io::write_png(p, img);
    return p;
  }
  fs::path dir_;
};

// "mean   0.123456" -> 0.123456
double printed(const std::string& out, const std::string& label) {
  const auto at = out.find(label);
  if (at == std::string::npos) return -1;
  return std::stod(out.substr(at + label.size()));
}

TEST_F(CompareCli, PrintsPooledValuesAndWritesTheMap) {
  const fs::path ref = png("ref.png", 64, 48, 200, 16), test = png("test.png", 64, 48, 200, 17);
  const fs::path out = dir_ / "out";
  const auto r = compare({ref.string(), test.string(), "-o", out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("67.02 px/deg"));
  EXPECT_THAT(r.out, HasSubstr("weighted median"));
  EXPECT_THAT(r.out, HasSubstr("share above 0.05"));
  // The frame observer: the whole square moved by one pixel side by side is a shift its windows
  // explain, so it is detected with a probability well inside (0, 1), below F = the published entry's.
  const double p_shift = printed(r.out, "detection probability");
  EXPECT_GT(p_shift, 0.0);
  EXPECT_LT(p_shift, 0.6737);
  EXPECT_THAT(r.out, HasSubstr("patches above F        0 of 1: not visible at F = 0.6737 (the published entry, data/calibration/default.json)"));
  const double mean = printed(r.out, "mean");
  EXPECT_GT(mean, 0.0);

  const penumbra::io::ImageF map = penumbra::io::read_imagef(out / "flip.exr");
  ASSERT_EQ(map.width, 64);
  ASSERT_EQ(map.height, 48);
  ASSERT_EQ(map.channels, 1);
  const double map_mean = std::accumulate(map.pixels.begin(), map.pixels.end(), 0.0) / static_cast<double>(map.pixels.size());
  EXPECT_NEAR(map_mean, mean, 1e-6);
  EXPECT_EQ(*std::max_element(map.pixels.begin(), map.pixels.end()) > 0.5f, true);  // the square's shifted sides
  const penumbra::io::Image8 colours = penumbra::io::read_image8(out / "flip.png");
  EXPECT_EQ(colours.width, 64);
  EXPECT_EQ(colours.channels, 3);

  std::ifstream in(out / "flip.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_NEAR(j.at("mean").get<double>(), mean, 1e-6);
  EXPECT_EQ(j.at("width").get<int>(), 64);
  EXPECT_EQ(j.at("reference").at("encoding"), "srgb");
  EXPECT_NEAR(j.at("detection_probability").get<double>(), printed(r.out, "detection probability"), 1e-4);
  EXPECT_EQ(j.at("visible"), false);

  // detection.json: every patch (2° at 67.02 px/deg: 134 px, so one patch holds the 64×48 frame),
  // and detection.png: the test image, tinted.
  std::ifstream det_in(out / "detection.json");
  const nlohmann::json det = nlohmann::json::parse(det_in);
  ASSERT_EQ(det.at("patches").size(), 1u);
  EXPECT_EQ(det.at("patches")[0].at("width"), 64);
  EXPECT_EQ(det.at("patches")[0].at("height"), 48);
  EXPECT_NEAR(det.at("p_detect_max").get<double>(), j.at("detection_probability").get<double>(), 1e-12);
  EXPECT_EQ(det.at("criterion_f"), 0.6737);
  const penumbra::io::Image8 tinted = penumbra::io::read_image8(out / "detection.png");
  EXPECT_EQ(tinted.width, 64);
  EXPECT_EQ(tinted.height, 48);
  EXPECT_LE(j.at("weighted_q1").get<double>(), j.at("weighted_median").get<double>());
  EXPECT_LE(j.at("weighted_median").get<double>(), j.at("weighted_q3").get<double>());

  // The same pair: 0.
  const auto same = compare({ref.string(), ref.string()});
  ASSERT_EQ(same.exit_code, 0) << same.err;
  EXPECT_EQ(printed(same.out, "mean"), 0.0);
  EXPECT_EQ(printed(same.out, "detection probability"), 0.0);
  EXPECT_THAT(same.out, HasSubstr("patches above F        0 of 1: not visible at F = 0.6737"));
  // The square brighter (200 -> 230) is no shift: seen almost surely.
  const fs::path bright = png("bright.png", 64, 48, 230, 16);
  const auto brighter = compare({ref.string(), bright.string()});
  ASSERT_EQ(brighter.exit_code, 0) << brighter.err;
  EXPECT_GT(printed(brighter.out, "detection probability"), 0.99);
  EXPECT_THAT(brighter.out, HasSubstr("patches above F        1 of 1: visible at F = 0.6737 (the published entry, data/calibration/default.json)"));
}

TEST_F(CompareCli, CriterionFromOptionOrCalibrationFile) {
  // A faint change: a square 1 code value brighter than the reference's, so that its detection
  // probability lies inside (0, 1) and F decides.
  const fs::path ref = png("ref.png", 160, 120, 200, 40), test = png("test.png", 160, 120, 201, 40);
  const auto base = compare({ref.string(), test.string(), "--ppd", "38.2"});
  ASSERT_EQ(base.exit_code, 0) << base.err;
  const double p = printed(base.out, "detection probability");
  ASSERT_GT(p, 0.0);
  ASSERT_LT(p, 0.99);
  char below[32], above[32];
  std::snprintf(below, sizeof below, "%.6f", 0.5 * p);
  std::snprintf(above, sizeof above, "%.6f", std::min(0.999, 0.5 * (1 + p)));
  const auto low_f = compare({ref.string(), test.string(), "--ppd", "38.2", "--criterion-f", below});
  const auto high_f = compare({ref.string(), test.string(), "--ppd", "38.2", "--criterion-f", above});
  EXPECT_THAT(low_f.out, HasSubstr(": visible at F = "));
  EXPECT_THAT(high_f.out, HasSubstr(": not visible at F = "));
  EXPECT_THAT(high_f.out, HasSubstr("(--criterion-f)"));
  // A calibration file's entries give F; one whose entries disagree is refused with one line.
  const fs::path one = dir_ / "one.json", two = dir_ / "two.json";
  const std::string entry = R"({"technique": "pcf", "kernel": "KERNEL", "c": 3, "obtained_by": "study",
      "threshold": {"task": "2afc", "guess": 0.5, "criterion_f": FVALUE, "family": "log-weibull", "beta": 3.5}})";
  auto make = [&](const std::string& kernel, const std::string& f) {
    std::string e = entry;
    e.replace(e.find("KERNEL"), 6, kernel);
    e.replace(e.find("FVALUE"), 6, f);
    return e;
  };
  std::ofstream(one) << R"({"schema_version": 2, "entries": [)" << make("grid", below) << "]}";
  std::ofstream(two) << R"({"schema_version": 2, "entries": [)" << make("grid", below) << ", " << make("disk", above) << "]}";
  const auto from_file = compare({ref.string(), test.string(), "--ppd", "38.2", "--calibration", one.string()});
  ASSERT_EQ(from_file.exit_code, 0) << from_file.err;
  EXPECT_THAT(from_file.out, HasSubstr(": visible at F = "));
  EXPECT_THAT(from_file.out, HasSubstr("(the entries of " + one.string() + ")"));
  const auto disagree = compare({ref.string(), test.string(), "--calibration", two.string()});
  EXPECT_EQ(disagree.exit_code, 1);
  EXPECT_THAT(disagree.err, HasSubstr("penumbra-compare: " + two.string() + ": its entries state different criteria"));
  EXPECT_EQ(std::count(disagree.err.begin(), disagree.err.end(), '\n'), 1) << disagree.err;
  // Out of range, or both at once: usage errors.
  EXPECT_EQ(compare({ref.string(), test.string(), "--criterion-f", "1"}).exit_code, 2);
  EXPECT_EQ(compare({ref.string(), test.string(), "--criterion-f", "0.5", "--calibration", one.string()}).exit_code, 2);
}

TEST_F(CompareCli, PixelsPerDegreeFromOptionOrStudyDisplay) {
  const fs::path ref = png("ref.png", 64, 48, 200, 16), test = png("test.png", 64, 48, 200, 17);
  const auto given = compare({ref.string(), test.string(), "--ppd", "20"});
  const auto fallback = compare({ref.string(), test.string()});
  const auto flips = compare({ref.string(), test.string(), "--ppd", "67.0206433"});
  ASSERT_EQ(given.exit_code, 0) << given.err;
  ASSERT_EQ(fallback.exit_code, 0) << fallback.err;
  EXPECT_THAT(given.out, HasSubstr("20.00 px/deg (--ppd)"));
  EXPECT_NE(printed(given.out, "mean"), printed(fallback.out, "mean"));
  EXPECT_NEAR(printed(flips.out, "mean"), printed(fallback.out, "mean"), 1e-6);  // the default is FLIP's viewer
  // data/studies/default.json: 1920 px over 527 mm, seen from 600 mm.
  const auto study = compare({ref.string(), test.string(), "--display", std::string(PENUMBRA_DATA_DIR) + "/studies/default.json"});
  ASSERT_EQ(study.exit_code, 0) << study.err;
  EXPECT_THAT(study.out, HasSubstr("38.15 px/deg (the display of"));
  // A display block without the distance is refused, naming the file and field.
  const fs::path config = dir_ / "config.json";
  std::ofstream(config) << R"({"display": {"width_px": 1920, "width_mm": 527}})";
  const auto missing = compare({ref.string(), test.string(), "--display", config.string()});
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_THAT(missing.err, HasSubstr(config.string() + ": display.viewing_distance_mm: missing"));
  // --ppd and --display contradict each other: a usage error.
  const auto both = compare({ref.string(), test.string(), "--ppd", "40", "--display", config.string()});
  EXPECT_EQ(both.exit_code, 2);
}

TEST_F(CompareCli, RefusesMismatchedSizesAndUnreadableFilesWithOneLine) {
  const fs::path ref = png("ref.png", 64, 48, 200, 16), small = png("small.png", 32, 48, 200, 8);
  const fs::path garbage = dir_ / "garbage.png";
  std::ofstream(garbage) << "not an image";
  const fs::path out = dir_ / "out";
  struct Case {
    std::vector<std::string> args;
    std::string names;
  };
  const Case cases[] = {
      {{ref.string(), small.string()}, small.string() + ": 32×48 pixels, but the reference " + ref.string() + " has 64×48"},
      {{ref.string(), (dir_ / "nowhere.png").string()}, (dir_ / "nowhere.png").string()},
      {{garbage.string(), ref.string()}, garbage.string()},
  };
  for (const Case& c : cases) {
    std::vector<std::string> args = c.args;
    args.insert(args.end(), {"-o", out.string()});
    const auto r = compare(args);
    EXPECT_EQ(r.exit_code, 1) << r.err;
    EXPECT_THAT(r.err, HasSubstr("penumbra-compare: " + c.names));
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_FALSE(fs::exists(out)) << "nothing written for " << c.names;
  }
}

TEST_F(CompareCli, HelpNamesItsPageAndVersion) {
  const auto help = compare({"--help"});
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_THAT(help.out, HasSubstr("compare.md"));
  EXPECT_THAT(help.out, HasSubstr("--display"));
  const auto version = compare({"--version"});
  EXPECT_EQ(version.exit_code, 0);
  EXPECT_THAT(version.out, HasSubstr("penumbra-compare "));
  const auto usage = compare({"only-one.png"});
  EXPECT_EQ(usage.exit_code, 2);
}

}  // namespace
