#pragma once
// Files compiled into a binary at build time (cmake/EmbedFiles.cmake).
#include <span>
#include <string_view>

namespace penumbra::embedded {

struct EmbeddedFile {
  std::string_view name;  // path relative to the embedded folder, e.g. "shading.frag"
  std::string_view text;
};

// The GLSL sources of renderer/shaders/.
std::span<const EmbeddedFile> shaders();

}  // namespace penumbra::embedded
