#include "shadows/technique.h"

#include <stdexcept>

#include "shadows/settings.h"

namespace penumbra::shadows {

const TechniqueEntry& technique_entry(Technique t) {
#define PENUMBRA_ENTRY(name, P) \
  case Technique::name: return name##_technique();
  switch (t) { PENUMBRA_TECHNIQUES(PENUMBRA_ENTRY) }
#undef PENUMBRA_ENTRY
  throw std::invalid_argument("technique_entry: not a registered technique");
}

}  // namespace penumbra::shadows
