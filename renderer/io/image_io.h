#pragma once
// Image files (PNG, EXR; the backend is io/image_codec.h) and montages of images. Rows are stored
// top row first.
#include <filesystem>
#include <string>
#include <vector>

#include <penumbra/image/image.h>

namespace penumbra::io {

// The image types live below gl/ (common/image/image.h); io:: names them for the files' users.
using image::flip_vertical;
using image::Image;
using image::Image8;
using image::ImageF;

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
