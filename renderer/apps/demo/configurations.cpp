#include "apps/demo/configurations.h"

#include "shadows/frame_plan.h"

#include <algorithm>
#include <utility>

namespace penumbra::demo {

std::string engine_name(int cascades, int resolution_texels) {
  return cascades <= 1 ? "fixed-" + std::to_string(resolution_texels)
                       : std::to_string(cascades) + "x" + std::to_string(resolution_texels) + "-cascades";
}

std::vector<Configuration> configurations(const shadows::ShadowSettings& fixed, const ConfigurationOptions& options) {
  const int f = fixed.map.resolution_texels;
  std::vector<Configuration> out;

  shadows::ShadowSettings adapt = fixed;
  adapt.adaptive.enabled = true;
  if (options.auto_cascades) adapt.map.cascades = 0;  // as many rule-sized cascades as the view needs (adaptive/cascades.h)
  out.push_back({"adaptive", Role::adaptive, adapt});
  shadows::ShadowSettings one = fixed;
  one.adaptive.enabled = false;
  one.map.cascades = 1;
  out.push_back({engine_name(1, f), Role::fixed, one});

  // The family as (cascades, texels), the fixed map left out (it is already there).
  std::vector<std::pair<int, int>> family;
  if (options.family == Family::default_) {
    family = {{1, 2 * f}, {4, f}, {1, std::max(f / 2, 1)}, {1, 4 * f}, {2, f}, {2, 2 * f}};
  } else if (options.family == Family::sweep) {
    family.push_back({4, f});  // the engine baseline first, as in the default family
    for (const int r : {1024, 2048, 4096, 8192}) family.push_back({1, r});
    for (const int k : {2, 3, 4})
      for (const int r : {1024, 2048, 4096}) family.push_back({k, r});
  }
  for (const auto& [cascades, texels] : family) {
    const std::string name = engine_name(cascades, texels);
    if (std::any_of(out.begin(), out.end(), [&](const Configuration& c) { return c.name == name; })) continue;
    shadows::ShadowSettings s = one;
    s.map.cascades = cascades;
    s.map.resolution_texels = texels;
    out.push_back({name, Role::engine, s});
  }

  if (options.flicker_only) {
    // The same rule without quantization or hysteresis: every frame the rule's exact answer.
    shadows::ShadowSettings raw = adapt;
    raw.adaptive.quantum_texels = 1;
    raw.adaptive.shrink_delay_frames = 0;
    out.push_back({"adaptive, no hysteresis", Role::no_hysteresis, raw});
    // The flicker measure's floor: one map of the fixed size, not fitted (fixed in the world).
    shadows::ShadowSettings world_fixed = one;
    world_fixed.map.fit = false;
    out.push_back({"floor (world-fixed map)", Role::floor, world_fixed});
  }
  if (options.virtual_pages && shadows::virtual_pages_unsupported(fixed).empty()) {
    const std::pair<const char*, shadows::VirtualPages> kinds[] = {{"virtual rule", shadows::VirtualPages::rule},
                                                                    {"virtual footprint", shadows::VirtualPages::footprint}};
    for (const auto& [name, marking] : kinds) {
      shadows::ShadowSettings v = one;
      v.map.virtual_pages = marking;
      v.map.virtual_cache = false;  // every marked page drawn every frame: the frame's whole work
      out.push_back({name, Role::virtual_pages, v});
    }
    shadows::ShadowSettings cached = one;
    cached.map.virtual_pages = shadows::VirtualPages::rule;
    out.push_back({"virtual rule, cached", Role::virtual_pages, cached});
  }
  return out;
}

std::size_t engine_baseline(const std::vector<Configuration>& configs) {
  for (std::size_t k = 0; k < configs.size(); ++k)
    if (configs[k].role == Role::fixed) {
      const std::string baseline = engine_name(4, configs[k].settings.map.resolution_texels);
      for (std::size_t j = 0; j < configs.size(); ++j)
        if (configs[j].name == baseline) return j;
      return k;
    }
  return 0;
}

}  // namespace penumbra::demo
