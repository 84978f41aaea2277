#pragma once
// The image file backend behind io/image_io.h: OpenImageIO (image_codec_oiio.cpp, the default) or
// libpng + OpenEXR alone (image_codec_minimal.cpp, PENUMBRA_IMAGE_IO=minimal: the GPU bundle,
// whose OpenImageIO would not fit the device tool's carry limit). Internal to io/.
#include <filesystem>
#include <string>
#include <vector>

#include "io/image_io.h"

namespace penumbra::io::codec {

// The encoded file, in memory (image_io.cpp writes it with io::write_file_atomic). Throw
// std::runtime_error with the reason; the caller prefixes the path.
std::vector<unsigned char> encode_png(const Image8& image);
std::vector<unsigned char> encode_exr(const ImageF& image);

// Throw std::runtime_error naming `path`.
Image8 read_image8(const std::filesystem::path& path);
ImageF read_imagef(const std::filesystem::path& path);

Image8 montage(const std::vector<Image8>& images, const std::vector<std::string>& labels, int columns, int tile_width);

}  // namespace penumbra::io::codec
