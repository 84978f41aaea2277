#pragma once
// Images on the CPU: a plain pixel array, rows stored top row first. Header only, below gl/ (which
// reads windows back into it); files are read and written by renderer/io/image_io.h.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace penumbra::image {

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

}  // namespace penumbra::image
