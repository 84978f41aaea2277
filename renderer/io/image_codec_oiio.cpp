// Image files through OpenImageIO (the default backend).
#include <stdexcept>

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include "io/image_codec.h"

namespace penumbra::io::codec {
namespace {

template <class T>
std::vector<unsigned char> encode(const Image<T>& image, const char* format, const char* name, OIIO::TypeDesc type) {
  auto out = OIIO::ImageOutput::create(format);
  if (!out) {
    // create() fails for a missing plugin and as often for memory it could not get: say what
    // OpenImageIO says rather than guess.
    const std::string why = OIIO::geterror();
    throw std::runtime_error(std::string("cannot encode ") + name + ": OpenImageIO could not create its " + format + " writer" +
                             (why.empty() ? " (out of memory, or the plugin is missing)" : ": " + why));
  }
  if (!out->supports("ioproxy"))
    throw std::runtime_error(std::string("cannot encode ") + name + ": this OpenImageIO's " + format + " writer cannot write to memory");
  std::vector<unsigned char> bytes;
  OIIO::Filesystem::IOVecOutput proxy(bytes);
  OIIO::ImageSpec spec(image.width, image.height, image.channels, type);
  if (std::string(format) == "openexr") spec.attribute("compression", "zip");
  if (!out->set_ioproxy(&proxy) || !out->open(name, spec) || !out->write_image(type, image.pixels.data()) || !out->close())
    throw std::runtime_error(out->geterror());
  return bytes;
}

template <class T>
Image<T> read_image(const std::filesystem::path& path, OIIO::TypeDesc type) {
  auto in = OIIO::ImageInput::open(path.string());
  if (!in) throw std::runtime_error(path.string() + ": cannot read image: " + OIIO::geterror());
  const auto& spec = in->spec();
  Image<T> img{spec.width, spec.height, spec.nchannels, {}};
  img.pixels.resize(static_cast<std::size_t>(img.width) * img.height * img.channels);
  if (!in->read_image(0, 0, 0, img.channels, type, img.pixels.data()))
    throw std::runtime_error(path.string() + ": cannot read image: " + in->geterror());
  return img;
}

}  // namespace

std::vector<unsigned char> encode_png(const Image8& image) { return encode(image, "png", "image.png", OIIO::TypeDesc::UINT8); }
std::vector<unsigned char> encode_exr(const ImageF& image) {
  return encode(image, "openexr", "image.exr", OIIO::TypeDesc::FLOAT);
}

Image8 read_image8(const std::filesystem::path& path) { return read_image<std::uint8_t>(path, OIIO::TypeDesc::UINT8); }
ImageF read_imagef(const std::filesystem::path& path) { return read_image<float>(path, OIIO::TypeDesc::FLOAT); }

Image8 montage(const std::vector<Image8>& images, const std::vector<std::string>& labels, int columns, int tile_width) {
  const int rows = (static_cast<int>(images.size()) + columns - 1) / columns;
  const int tile_height = tile_width * images[0].height / images[0].width;
  OIIO::ImageBuf canvas(OIIO::ImageSpec(columns * tile_width, rows * tile_height, 3, OIIO::TypeDesc::UINT8));
  const float grey[3] = {0.1f, 0.1f, 0.1f};
  OIIO::ImageBufAlgo::fill(canvas, grey);
  for (std::size_t i = 0; i < images.size(); ++i) {
    const auto& img = images[i];
    OIIO::ImageBuf src(OIIO::ImageSpec(img.width, img.height, img.channels, OIIO::TypeDesc::UINT8),
                       const_cast<std::uint8_t*>(img.pixels.data()));
    OIIO::ImageBuf rgb = OIIO::ImageBufAlgo::channels(src, 3, {});
    OIIO::ImageBuf tile = OIIO::ImageBufAlgo::resize(rgb, "", 0, OIIO::ROI(0, tile_width, 0, tile_height, 0, 1, 0, 3));
    if (i < labels.size()) {
      const float white[3] = {1, 1, 1};
      OIIO::ImageBufAlgo::render_text(tile, 12, 30, labels[i], 24, "DejaVuSans", white);  // no-op without the font
    }
    const int x = static_cast<int>(i) % columns * tile_width, y = static_cast<int>(i) / columns * tile_height;
    OIIO::ImageBufAlgo::paste(canvas, x, y, 0, 0, tile);
  }
  Image8 out{canvas.spec().width, canvas.spec().height, 3, {}};
  out.pixels.resize(static_cast<std::size_t>(out.width) * out.height * 3);
  canvas.get_pixels(OIIO::ROI::All(), OIIO::TypeDesc::UINT8, out.pixels.data());
  return out;
}

}  // namespace penumbra::io::codec
