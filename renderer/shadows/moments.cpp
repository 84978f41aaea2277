#include "shadows/moments.h"

#include <stdexcept>

namespace penumbra::shadows {

int channel_count(GLenum format) {
  switch (format) {
    case GL_R32F: return 1;
    case GL_RG32F: return 2;
    case GL_RGBA32F:
    case GL_RGBA16F: return 4;
    default: throw std::logic_error("moments: unsupported texture format");
  }
}

const char* image_format_qualifier(GLenum format) {
  switch (format) {
    case GL_R32F: return "r32f";
    case GL_RG32F: return "rg32f";
    case GL_RGBA32F: return "rgba32f";
    case GL_RGBA16F: return "rgba16f";
    default: throw std::logic_error("moments: unsupported texture format");
  }
}

}  // namespace penumbra::shadows
