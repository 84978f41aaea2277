#include "shadows/moments.h"

namespace penumbra::shadows {

int channel_count(MomentsFormat format) {
  switch (format) {
    case MomentsFormat::r32f: return 1;
    case MomentsFormat::rg32f: return 2;
    case MomentsFormat::rgba16f:
    case MomentsFormat::rgba32f: return 4;
  }
  return 4;
}

int bytes_per_texel(MomentsFormat format) { return channel_count(format) * (format == MomentsFormat::rgba16f ? 2 : 4); }

const char* image_format_qualifier(MomentsFormat format) {
  switch (format) {
    case MomentsFormat::r32f: return "r32f";
    case MomentsFormat::rg32f: return "rg32f";
    case MomentsFormat::rgba16f: return "rgba16f";
    case MomentsFormat::rgba32f: return "rgba32f";
  }
  return "rgba32f";
}

}  // namespace penumbra::shadows
