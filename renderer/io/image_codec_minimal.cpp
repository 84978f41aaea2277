// Image files through libpng and OpenEXR alone (PENUMBRA_IMAGE_IO=minimal). Writes what the
// OpenImageIO backend writes: 8-bit PNG; float EXR, zip compressed, channels named as OpenImageIO
// names them (Y; R G; R G B; R G B A; then channel4...). Reads PNG and scanline EXR into either
// pixel type. The montage scales by area averaging and draws no labels (no font engine).
#include <png.h>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfIO.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <ImfVersion.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <type_traits>

#include "io/image_codec.h"

namespace penumbra::io::codec {
namespace {

std::vector<std::string> channel_names(int channels) {
  if (channels == 1) return {"Y"};
  std::vector<std::string> names;
  const char* rgba[] = {"R", "G", "B", "A"};
  for (int c = 0; c < channels; ++c) names.push_back(c < 4 ? rgba[c] : "channel" + std::to_string(c));
  return names;
}

png_uint_32 png_format(int channels) {
  switch (channels) {
    case 1: return PNG_FORMAT_GRAY;
    case 2: return PNG_FORMAT_GA;
    case 3: return PNG_FORMAT_RGB;
    case 4: return PNG_FORMAT_RGBA;
    default: throw std::runtime_error("PNG holds 1 to 4 channels, not " + std::to_string(channels));
  }
}

// The file's first bytes (fewer where it is shorter; none where it cannot be opened).
std::string head(const std::filesystem::path& path, std::size_t n) {
  std::ifstream f(path, std::ios::binary);
  std::string bytes(n, '\0');
  f.read(bytes.data(), static_cast<std::streamsize>(n));
  bytes.resize(static_cast<std::size_t>(std::max<std::streamsize>(f.gcount(), 0)));
  return bytes;
}

bool is_png(const std::filesystem::path& path) {
  const std::string sig = head(path, 8);
  return sig.size() == 8 && png_sig_cmp(reinterpret_cast<png_const_bytep>(sig.data()), 0, 8) == 0;
}

bool is_exr(const std::filesystem::path& path) {
  const std::string magic = head(path, 4);
  return magic.size() == 4 && Imf::isImfMagic(magic.data());
}

Image8 read_png(const std::filesystem::path& path) {
  png_image png;
  std::memset(&png, 0, sizeof png);
  png.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_file(&png, path.c_str())) throw std::runtime_error(png.message);
  const int channels = static_cast<int>(PNG_IMAGE_PIXEL_CHANNELS(png.format));
  png.format = png_format(channels);  // 8 bits per channel, colour maps expanded
  Image8 img{static_cast<int>(png.width), static_cast<int>(png.height), channels, {}};
  img.pixels.resize(PNG_IMAGE_SIZE(png));
  if (!png_image_finish_read(&png, nullptr, img.pixels.data(), 0, nullptr)) throw std::runtime_error(png.message);
  return img;
}

ImageF read_exr(const std::filesystem::path& path) {
  Imf::InputFile file(path.c_str());
  const Imath::Box2i window = file.header().dataWindow();
  const int width = window.max.x - window.min.x + 1, height = window.max.y - window.min.y + 1;
  std::vector<std::string> names;
  for (auto it = file.header().channels().begin(); it != file.header().channels().end(); ++it) names.emplace_back(it.name());
  // OpenImageIO's order where the file has exactly its names, the file's (alphabetical) otherwise.
  std::vector<std::string> canonical = channel_names(static_cast<int>(names.size()));
  if (std::is_permutation(names.begin(), names.end(), canonical.begin(), canonical.end())) names = canonical;
  ImageF img{width, height, static_cast<int>(names.size()), {}};
  img.pixels.resize(static_cast<std::size_t>(width) * height * img.channels);
  Imf::FrameBuffer fb;
  const std::size_t xs = sizeof(float) * img.channels, ys = xs * width;
  // The slice base is where pixel (0, 0) would lie, which the data window may not contain.
  char* origin = reinterpret_cast<char*>(img.pixels.data()) - window.min.x * static_cast<std::ptrdiff_t>(xs) -
                 window.min.y * static_cast<std::ptrdiff_t>(ys);
  for (int c = 0; c < img.channels; ++c) fb.insert(names[c], Imf::Slice(Imf::FLOAT, origin + c * sizeof(float), xs, ys));
  file.setFrameBuffer(fb);
  file.readPixels(window.min.y, window.max.y);
  return img;
}

template <class T>
Image<T> read_any(const std::filesystem::path& path) {
  try {
    if (is_png(path)) {
      Image8 png = read_png(path);
      if constexpr (std::is_same_v<T, std::uint8_t>) {
        return png;
      } else {
        ImageF out{png.width, png.height, png.channels, std::vector<float>(png.pixels.size())};
        std::transform(png.pixels.begin(), png.pixels.end(), out.pixels.begin(), [](std::uint8_t v) { return v / 255.0f; });
        return out;
      }
    }
    if (!is_exr(path))
      throw std::runtime_error(std::filesystem::exists(path) ? "neither PNG nor OpenEXR" : "no such file");
    ImageF exr = read_exr(path);
    if constexpr (std::is_same_v<T, float>) {
      return exr;
    } else {
      Image8 out{exr.width, exr.height, exr.channels, std::vector<std::uint8_t>(exr.pixels.size())};
      std::transform(exr.pixels.begin(), exr.pixels.end(), out.pixels.begin(),
                     [](float v) { return static_cast<std::uint8_t>(std::lround(std::clamp(v, 0.0f, 1.0f) * 255.0f)); });
      return out;
    }
  } catch (const std::exception& e) {
    throw std::runtime_error(path.string() + ": cannot read image: " + e.what());
  }
}

// Area-averaging scale of one RGB(A) image to `w` × `h`, first three channels (grey repeated).
Image8 scale_rgb(const Image8& src, int w, int h) {
  Image8 out{w, h, 3, std::vector<std::uint8_t>(static_cast<std::size_t>(w) * h * 3)};
  const double sx = static_cast<double>(src.width) / w, sy = static_cast<double>(src.height) / h;
  for (int y = 0; y < h; ++y) {
    const int y0 = static_cast<int>(y * sy), y1 = std::max(y0 + 1, std::min(src.height, static_cast<int>(std::ceil((y + 1) * sy))));
    for (int x = 0; x < w; ++x) {
      const int x0 = static_cast<int>(x * sx), x1 = std::max(x0 + 1, std::min(src.width, static_cast<int>(std::ceil((x + 1) * sx))));
      for (int c = 0; c < 3; ++c) {
        const int sc = std::min(c, src.channels - 1);
        unsigned sum = 0;
        for (int yy = y0; yy < y1; ++yy)
          for (int xx = x0; xx < x1; ++xx) sum += src.at(xx, yy, sc);
        const unsigned n = static_cast<unsigned>((y1 - y0) * (x1 - x0));
        out.at(x, y, c) = static_cast<std::uint8_t>((sum + n / 2) / n);
      }
    }
  }
  return out;
}

}  // namespace

std::vector<unsigned char> encode_png(const Image8& image) {
  png_image png;
  std::memset(&png, 0, sizeof png);
  png.version = PNG_IMAGE_VERSION;
  png.width = static_cast<png_uint_32>(image.width);
  png.height = static_cast<png_uint_32>(image.height);
  png.format = png_format(image.channels);
  png_alloc_size_t size = 0;
  if (!png_image_write_to_memory(&png, nullptr, &size, 0, image.pixels.data(), 0, nullptr))
    throw std::runtime_error(png.message);
  std::vector<unsigned char> bytes(size);
  if (!png_image_write_to_memory(&png, bytes.data(), &size, 0, image.pixels.data(), 0, nullptr))
    throw std::runtime_error(png.message);
  bytes.resize(size);
  return bytes;
}

namespace {
// OpenEXR's output stream into a vector.
class MemoryStream : public Imf::OStream {
 public:
  explicit MemoryStream(std::vector<unsigned char>& bytes) : Imf::OStream("image.exr"), bytes_(bytes) {}
  void write(const char c[], int n) override {
    const std::size_t end = position_ + static_cast<std::size_t>(n);
    if (bytes_.size() < end) bytes_.resize(end);
    std::memcpy(bytes_.data() + position_, c, static_cast<std::size_t>(n));
    position_ = end;
  }
  std::uint64_t tellp() override { return position_; }
  void seekp(std::uint64_t pos) override { position_ = static_cast<std::size_t>(pos); }

 private:
  std::vector<unsigned char>& bytes_;
  std::size_t position_ = 0;
};
}  // namespace

std::vector<unsigned char> encode_exr(const ImageF& image) {
  Imf::Header header(image.width, image.height);
  header.compression() = Imf::ZIP_COMPRESSION;
  const std::vector<std::string> names = channel_names(image.channels);
  for (const auto& n : names) header.channels().insert(n, Imf::Channel(Imf::FLOAT));
  std::vector<unsigned char> bytes;
  {  // the file is complete when OutputFile is destroyed (it writes the offset table then)
    MemoryStream stream(bytes);
    Imf::OutputFile file(stream, header);
    Imf::FrameBuffer fb;
    const std::size_t xs = sizeof(float) * image.channels, ys = xs * image.width;
    char* base = reinterpret_cast<char*>(const_cast<float*>(image.pixels.data()));
    for (int c = 0; c < image.channels; ++c) fb.insert(names[c], Imf::Slice(Imf::FLOAT, base + c * sizeof(float), xs, ys));
    file.setFrameBuffer(fb);
    file.writePixels(image.height);
  }
  return bytes;
}

Image8 read_image8(const std::filesystem::path& path) { return read_any<std::uint8_t>(path); }
ImageF read_imagef(const std::filesystem::path& path) { return read_any<float>(path); }

Image8 montage(const std::vector<Image8>& images, const std::vector<std::string>&, int columns, int tile_width) {
  const int rows = (static_cast<int>(images.size()) + columns - 1) / columns;
  const int tile_height = tile_width * images[0].height / images[0].width;
  Image8 canvas{columns * tile_width, rows * tile_height, 3,
                std::vector<std::uint8_t>(static_cast<std::size_t>(columns) * tile_width * rows * tile_height * 3, 26)};  // 0.1 grey
  for (std::size_t i = 0; i < images.size(); ++i) {
    const Image8 tile = scale_rgb(images[i], tile_width, tile_height);
    const int x0 = static_cast<int>(i) % columns * tile_width, y0 = static_cast<int>(i) / columns * tile_height;
    for (int y = 0; y < tile_height; ++y)
      std::copy_n(&tile.pixels[static_cast<std::size_t>(y) * tile_width * 3], tile_width * 3, &canvas.at(x0, y0 + y));
  }
  return canvas;
}

}  // namespace penumbra::io::codec
