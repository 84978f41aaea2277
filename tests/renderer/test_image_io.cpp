// io image files, whichever backend the build uses (PENUMBRA_IMAGE_IO: OpenImageIO, or minimal
// libpng + OpenEXR for the GPU bundle): PNG and EXR round trips, reading across pixel types, the
// montage's layout, and errors that name the file and leave nothing behind.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include <unistd.h>

#include "io/image_io.h"

namespace fs = std::filesystem;

namespace penumbra::io {
namespace {

class ImageIo : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("penumbra-image-io-" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

template <class T>
Image<T> pattern(int w, int h, int channels, T (*value)(int, int, int)) {
  Image<T> img{w, h, channels, std::vector<T>(static_cast<std::size_t>(w) * h * channels)};
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < channels; ++c) img.at(x, y, c) = value(x, y, c);
  return img;
}

TEST_F(ImageIo, PngRoundTripKeepsEveryChannelCount) {
  for (int channels = 1; channels <= 4; ++channels) {
    // Alpha (channel 1 of 2, 3 of 4) opaque: OpenImageIO premultiplies it, which rounds colours.
    auto img = pattern<std::uint8_t>(7, 5, channels, [](int x, int y, int c) { return static_cast<std::uint8_t>(37 * x + 11 * y + 80 * c); });
    if (channels % 2 == 0)
      for (int y = 0; y < 5; ++y)
        for (int x = 0; x < 7; ++x) img.at(x, y, channels - 1) = 255;
    const fs::path file = dir_ / ("p" + std::to_string(channels) + ".png");
    write_png(file, img);
    const Image8 back = read_image8(file);
    EXPECT_EQ(back.width, 7);
    EXPECT_EQ(back.height, 5);
    EXPECT_EQ(back.channels, channels);
    EXPECT_EQ(back.pixels, img.pixels) << channels << " channels";
  }
}

TEST_F(ImageIo, ExrRoundTripIsExactInFloat) {
  for (int channels : {1, 3, 4}) {
    const auto img = pattern<float>(9, 4, channels, [](int x, int y, int c) { return 0.125f * x - 0.3f * y + 2.5f * c + 1e-3f; });
    const fs::path file = dir_ / ("v" + std::to_string(channels) + ".exr");
    write_exr(file, img);
    const ImageF back = read_imagef(file);
    ASSERT_EQ(back.width, 9);
    ASSERT_EQ(back.height, 4);
    ASSERT_EQ(back.channels, channels);
    EXPECT_EQ(back.pixels, img.pixels) << channels << " channels";  // float channels, lossless zip
  }
}

TEST_F(ImageIo, ReadsAcrossPixelTypes) {
  const Image8 png = pattern<std::uint8_t>(3, 2, 3, [](int x, int, int c) { return static_cast<std::uint8_t>(x * 100 + c); });
  write_png(dir_ / "a.png", png);
  const ImageF as_float = read_imagef(dir_ / "a.png");
  EXPECT_FLOAT_EQ(as_float.at(2, 1, 2), 202.0f / 255.0f);

  const ImageF exr = pattern<float>(4, 1, 1, [](int x, int, int) { return x * 0.5f - 0.25f; });  // -0.25, 0.25, 0.75, 1.25
  write_exr(dir_ / "b.exr", exr);
  const Image8 as_byte = read_image8(dir_ / "b.exr");
  EXPECT_EQ(as_byte.at(0, 0), 0);
  EXPECT_EQ(as_byte.at(1, 0), 64);
  EXPECT_EQ(as_byte.at(2, 0), 191);
  EXPECT_EQ(as_byte.at(3, 0), 255);
}

TEST_F(ImageIo, MontageTilesScaledImagesOnGrey) {
  const Image8 red = pattern<std::uint8_t>(40, 20, 4, [](int, int, int c) { return static_cast<std::uint8_t>(c == 0 || c == 3 ? 255 : 0); });
  const Image8 blue = pattern<std::uint8_t>(40, 20, 3, [](int, int, int c) { return static_cast<std::uint8_t>(c == 2 ? 200 : 0); });
  const Image8 m = montage({red, blue, red}, {}, 2, 10);  // 2 columns of 10x5 tiles, 2 rows
  ASSERT_EQ(m.width, 20);
  ASSERT_EQ(m.height, 10);
  ASSERT_EQ(m.channels, 3);
  EXPECT_NEAR(m.at(5, 2, 0), 255, 1);   // red tile
  EXPECT_NEAR(m.at(5, 2, 1), 0, 1);
  EXPECT_NEAR(m.at(15, 2, 2), 200, 1);  // blue tile
  EXPECT_NEAR(m.at(15, 2, 0), 0, 1);
  EXPECT_NEAR(m.at(5, 7, 0), 255, 1);   // red again, second row
  EXPECT_NEAR(m.at(15, 7, 0), 26, 1);  // empty cell: 0.1 grey
  EXPECT_TRUE(montage({}, {}, 3, 640).pixels.empty());
}

TEST_F(ImageIo, FailedWriteNamesTheFileAndLeavesNothing) {
  const fs::path file = dir_ / "missing" / "x.png";
  try {
    write_png(file, pattern<std::uint8_t>(2, 2, 3, [](int, int, int) { return std::uint8_t{1}; }));
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(file.string()), std::string::npos) << e.what();
  }
  EXPECT_THROW(write_exr(dir_ / "y.exr", ImageF{3, 3, 1, std::vector<float>(8)}), std::runtime_error);  // 8 != 3*3
  EXPECT_FALSE(fs::exists(dir_ / "y.exr"));
  EXPECT_FALSE(fs::exists(dir_ / ".y.exr.partial"));
}

TEST_F(ImageIo, UnreadableFilesNameThePath) {
  std::ofstream(dir_ / "text.png") << "not an image";
  for (const fs::path& p : {dir_ / "text.png", dir_ / "absent.exr"}) {
    try {
      read_image8(p);
      FAIL() << "no exception for " << p;
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(p.string()), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace penumbra::io
