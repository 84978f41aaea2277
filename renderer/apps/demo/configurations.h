#pragma once
// What penumbra-demo draws along the path for one technique: the adaptive rule, one fixed map,
// the engine family (the configurations an engine would choose from: single fitted maps and
// cascades, practical split, stabilized, blended: the map.* defaults), and two configurations
// that only measure flicker (the rule without hysteresis, a world-fixed map).
#include <string>
#include <vector>

#include "shadows/settings.h"

namespace penumbra::demo {

enum class Role {
  adaptive,       // the rule: res = c L / r per cascade, as many cascades as it needs
  fixed,          // one fitted map of --fixed-resolution (the single-map comparison)
  engine,         // a member of the engine family (the fixed map is one too)
  no_hysteresis,  // the rule's exact answer every frame (flicker only)
  floor,          // one map fixed in the world, not fitted (flicker only)
  virtual_pages,  // the sun's virtual shadow map (map.virtual_pages): by the rule or the footprint, cached or not
};

struct Configuration {
  std::string name;
  Role role = Role::engine;
  shadows::ShadowSettings settings;
  // In the tables and on the front: the adaptive rule, the fixed map and the engine family.
  bool timed() const { return role == Role::adaptive || role == Role::fixed || role == Role::engine || role == Role::virtual_pages; }
  // A point of the engine family (the fixed map included).
  bool engine_family() const { return role == Role::fixed || role == Role::engine; }
};

// "fixed-2048" (one fitted map) or "4x2048-cascades".
std::string engine_name(int cascades, int resolution_texels);

enum class Family {
  none,     // --no-baselines: adaptive and fixed only
  default_, // the points the sweep found on the outdoor town's fronts, relative to the fixed size F:
            // single maps of F/2, 2F and 4F, two cascades of F and 2F, four cascades of F (the baseline)
  sweep,    // --sweep: single maps 1024²..8192², 2-4 cascades × 1024²..4096²
};

struct ConfigurationOptions {
  Family family = Family::default_;
  bool auto_cascades = true;  // adaptive: as many cascades as the rule needs
  bool flicker_only = true;   // add the rule without hysteresis and the world-fixed floor
  // The sun's virtual shadow map, where the technique reads it (shadows::virtual_pages_unsupported):
  // by the rule and by the footprint, each page drawn every frame (the per-frame work), and the
  // rule with its cache. Only for a directional light.
  bool virtual_pages = false;
};

// `fixed`: the technique's settings (calibrated, adaptive off) with map.resolution_texels = F.
// Order: adaptive, fixed, the engine family (four cascades of F, the engine baseline, second when
// the family has it), then the flicker-only configurations, then the virtual maps.
std::vector<Configuration> configurations(const shadows::ShadowSettings& fixed, const ConfigurationOptions& options);

// The index of the engine baseline (four cascades of F) in `configs`, or of the fixed map when
// the family has none.
std::size_t engine_baseline(const std::vector<Configuration>& configs);

}  // namespace penumbra::demo
