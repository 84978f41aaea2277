#include "shadows/techniques/hard.h"

#include "shadows/settings.h"

namespace penumbra::shadows {

const TechniqueEntry& hard_technique() {
  static const TechniqueEntry entry{.name = "hard", .define = "TECHNIQUE_HARD", .radius = RadiusReading::none, .pages = PageReading::none};
  return entry;
}

}  // namespace penumbra::shadows
