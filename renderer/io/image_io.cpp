#include "io/image_io.h"

#include <stdexcept>
#include <string_view>

#include "io/atomic_file.h"
#include "io/image_codec.h"

namespace penumbra::io {
namespace {

// Encoded in memory and written by write_file_atomic: the image libraries ignored a failed write
// (a full disk left a truncated PNG that was then renamed into place); write(2) does not.
template <class T, class Encode>
void write_image(const std::filesystem::path& path, const Image<T>& image, Encode encode) {
  if (image.width <= 0 || image.height <= 0 || image.pixels.size() != static_cast<std::size_t>(image.width) * image.height * image.channels)
    throw std::runtime_error(path.string() + ": image has inconsistent size");
  std::vector<unsigned char> bytes;
  try {
    bytes = encode(image);
  } catch (const std::exception& e) {
    throw std::runtime_error(path.string() + ": cannot encode the image: " + e.what());
  }
  write_file_atomic(path, std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
}

}  // namespace

void write_png(const std::filesystem::path& path, const Image8& image) { write_image(path, image, codec::encode_png); }
void write_exr(const std::filesystem::path& path, const ImageF& image) { write_image(path, image, codec::encode_exr); }

Image8 read_image8(const std::filesystem::path& path) { return codec::read_image8(path); }
ImageF read_imagef(const std::filesystem::path& path) { return codec::read_imagef(path); }

Image8 montage(const std::vector<Image8>& images, const std::vector<std::string>& labels, int columns, int tile_width) {
  if (images.empty()) return {};
  return codec::montage(images, labels, columns, tile_width);
}

}  // namespace penumbra::io
