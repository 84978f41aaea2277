#include "io/image_io.h"

#include <fstream>
#include <stdexcept>

#include "io/image_codec.h"

namespace penumbra::io {
namespace {

std::filesystem::path temp_path(const std::filesystem::path& path) {
  return path.parent_path() / ("." + path.filename().string() + ".partial");
}

void commit(const std::filesystem::path& tmp, const std::filesystem::path& path) {
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::filesystem::remove(tmp, ec);
    throw std::runtime_error(path.string() + ": cannot write (" + ec.message() + ")");
  }
}

template <class T, class Encode>
void write_image(const std::filesystem::path& path, const Image<T>& image, Encode encode) {
  if (image.width <= 0 || image.height <= 0 || image.pixels.size() != static_cast<std::size_t>(image.width) * image.height * image.channels)
    throw std::runtime_error(path.string() + ": image has inconsistent size");
  const auto tmp = temp_path(path);
  try {
    encode(tmp, image);
  } catch (const std::exception& e) {
    std::error_code ec;
    std::filesystem::remove(tmp, ec);
    throw std::runtime_error(path.string() + ": cannot write: " + e.what());
  }
  commit(tmp, path);
}

}  // namespace

void write_png(const std::filesystem::path& path, const Image8& image) { write_image(path, image, codec::encode_png); }
void write_exr(const std::filesystem::path& path, const ImageF& image) { write_image(path, image, codec::encode_exr); }

void write_text(const std::filesystem::path& path, const std::string& text) {
  const auto tmp = temp_path(path);
  {
    std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
    f << text;
    f.flush();
    if (!f) {
      std::error_code ec;
      std::filesystem::remove(tmp, ec);
      throw std::runtime_error(path.string() + ": cannot write");
    }
  }
  commit(tmp, path);
}

Image8 read_image8(const std::filesystem::path& path) { return codec::read_image8(path); }
ImageF read_imagef(const std::filesystem::path& path) { return codec::read_imagef(path); }

Image8 montage(const std::vector<Image8>& images, const std::vector<std::string>& labels, int columns, int tile_width) {
  if (images.empty()) return {};
  return codec::montage(images, labels, columns, tile_width);
}

}  // namespace penumbra::io
