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
  EXPECT_THAT(r.out, HasSubstr("detection probability  not computed"));
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
  EXPECT_TRUE(j.at("detection_probability").is_null());
  EXPECT_LE(j.at("weighted_q1").get<double>(), j.at("weighted_median").get<double>());
  EXPECT_LE(j.at("weighted_median").get<double>(), j.at("weighted_q3").get<double>());

  // The same pair: 0.
  const auto same = compare({ref.string(), ref.string()});
  ASSERT_EQ(same.exit_code, 0) << same.err;
  EXPECT_EQ(printed(same.out, "mean"), 0.0);
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
