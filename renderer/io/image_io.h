#pragma once
// Images on the CPU and their files (OpenImageIO). Rows are stored top row first.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace penumbra::io {

template <class T>
struct Image {
  int width = 0;
  int height = 0;
  int channels = 0;
  std::vector<T> pixels;  // width * height * channels, row-major, top row first

  T& at(int x, int y, int c = 0) { return pixels[(static_cast<std::size_t>(y) * width + x) * channels + c]; }
  T at(int x, int y, int c = 0) const { return pixels[(static_cast<std::size_t>(y) * width + x) * channels + c]; }
};
using Image8 = Image<std::uint8_t>;
using ImageF = Image<float>;

// Reverses the row order in place: GL reads rows bottom up, these images store them top down.
template <class T>
void flip_vertical(Image<T>& img) {
  const std::size_t row = static_cast<std::size_t>(img.width) * static_cast<std::size_t>(img.channels);
  for (int y = 0; y < img.height / 2; ++y)
    std::swap_ranges(img.pixels.begin() + static_cast<std::ptrdiff_t>(static_cast<std::size_t>(y) * row),
                     img.pixels.begin() + static_cast<std::ptrdiff_t>(static_cast<std::size_t>(y + 1) * row),
                     img.pixels.begin() + static_cast<std::ptrdiff_t>(static_cast<std::size_t>(img.height - 1 - y) * row));
}

// Write through a temporary file in the same folder and rename, so a reader never sees half a
// file. Throw std::runtime_error naming the path on failure.
void write_png(const std::filesystem::path& path, const Image8& image);
void write_exr(const std::filesystem::path& path, const ImageF& image);

Image8 read_image8(const std::filesystem::path& path);
ImageF read_imagef(const std::filesystem::path& path);

// Tiles images (all 8-bit RGB/RGBA) into `columns` columns, each scaled to `tile_width` pixels
// wide, with its label drawn in the corner where a font is available.
Image8 montage(const std::vector<Image8>& images, const std::vector<std::string>& labels, int columns, int tile_width);

}  // namespace penumbra::io
