#include "shadows/techniques/rbsm.h"

#include "gl/objects.h"
#include "shadows/settings.h"
#include "shadows/settings_rows.h"

namespace penumbra::shadows {
namespace {

const Setting<RbsmParams> kTable[] = {
    PENUMBRA_INT(RbsmParams, max_search_texels, "texels", 1, 256,
                 "texels walked along a silhouette step in each direction; longer steps are revectorized as if straight"),
};

}  // namespace

std::span<const Setting<RbsmParams>> settings_table(const RbsmParams*) { return kTable; }

void set_rbsm_uniforms(const gl::Program& program, const RbsmParams& p) { program.set("u_rbsm_max_search", p.max_search_texels); }

const TechniqueEntry& rbsm_technique() {
  static const TechniqueEntry entry{
      .name = "rbsm",
      .define = "TECHNIQUE_RBSM",
      .radius = RadiusReading::none,
      .pages = PageReading::none,
      .pad_texels = 1,  // the revectorization reads the neighbours of every receiver texel
      .set_uniforms = [](const gl::Program& p, const ShadowSettings& s) { set_rbsm_uniforms(p, s.rbsm); },
  };
  return entry;
}

}  // namespace penumbra::shadows
