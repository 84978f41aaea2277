#pragma once
// The image file backend behind io/image_io.h: OpenImageIO (image_codec_oiio.cpp, the default) or
// libpng + OpenEXR alone (image_codec_minimal.cpp, PENUMBRA_IMAGE_IO=minimal: the GPU bundle,
// whose OpenImageIO would not fit the device tool's carry limit). Internal to io/.
#include <filesystem>
#include <string>
#include <vector>

#include "io/image_io.h"

namespace penumbra::io::codec {

// Encode into `path` (a temporary file: image_io.cpp renames it). Throw std::runtime_error with
// the reason; the caller prefixes the final path.
void encode_png(const std::filesystem::path& path, const Image8& image);
void encode_exr(const std::filesystem::path& path, const ImageF& image);

// Throw std::runtime_error naming `path`.
Image8 read_image8(const std::filesystem::path& path);
ImageF read_imagef(const std::filesystem::path& path);

Image8 montage(const std::vector<Image8>& images, const std::vector<std::string>& labels, int columns, int tile_width);

}  // namespace penumbra::io::codec
