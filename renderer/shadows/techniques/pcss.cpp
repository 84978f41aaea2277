#include "shadows/techniques/pcss.h"

#include <algorithm>

#include "gl/objects.h"
#include "gl/shader_library.h"
#include "shadows/settings.h"
#include "shadows/settings_rows.h"

namespace penumbra::shadows {
namespace {

const Setting<PcssParams> kTable[] = {
    PENUMBRA_CHOICE(PcssParams, kernel, Kernel, rows::kKernels, "kernel of the filtering step"),
    PENUMBRA_INT(PcssParams, blocker_taps, "taps", 1, 64, "Poisson taps of the blocker search"),
    PENUMBRA_INT(PcssParams, filter_taps, "taps", 1, 64, "Poisson taps of the filtering step"),
    PENUMBRA_REAL(PcssParams, min_penumbra_ws, "world", 0, 1e6, "minimum filter radius at the receiver"),
    PENUMBRA_REAL(PcssParams, search_scale, "", 1, 8,
                  "blocker-search radius over its geometric bound; > 1 lets sparse taps find blockers near the penumbra's outer rim"),
    PENUMBRA_INT(PcssParams, max_grid_taps, "taps", 2, 256, "grid and disk taps per axis before the kernel is strided"),
    PENUMBRA_BOOL(PcssParams, hierarchical,
                  "min-max depth bounds skip the blocker search where a pixel is surely lit, in umbra or at the minimum penumbra"),
};

}  // namespace

std::span<const Setting<PcssParams>> settings_table(const PcssParams*) { return kTable; }

const TechniqueEntry& pcss_technique() {
  static const TechniqueEntry entry{
      .name = "pcss",
      .define = "TECHNIQUE_PCSS",
      .radius = RadiusReading::penumbra,
      .pages = PageReading::blocker_search,
      .pages_need = [](const ShadowSettings& s) { return s.pcss.kernel == Kernel::grid ? std::string_view() : std::string_view("--pcss.kernel grid"); },
      .reference = ReferenceKind::area_light,
      // The filter is never narrower than the minimum penumbra: the rule's bound without a
      // per-pixel measurement (adaptive.pcss = per_pixel lowers it to what the frame needed).
      .rule_radius_ws = [](const ShadowSettings& s) { return s.pcss.min_penumbra_ws; },
      .search_scale = [](const ShadowSettings& s) { return s.pcss.search_scale; },
      .pad_texels = 1,
      .per_pixel_requirement = true,
      .depth_minmax = [](const ShadowSettings& s) { return s.pcss.hierarchical; },
      .variant_defines =
          [](const ShadowSettings& s, std::vector<gl::ShaderDefine>& d) {
            if (s.pcss.kernel == Kernel::grid) d.push_back({"KERNEL_GRID", "1"});
            if (s.pcss.kernel == Kernel::disk) d.push_back({"KERNEL_DISK", "1"});
            if (s.pcss.hierarchical) d.push_back({"PCSS_HIERARCHICAL", "1"});
          },
      // One disk for both steps, sized for the larger tap count; the filter step takes its own
      // count from the front (the best-candidate order spreads any prefix).
      .poisson_taps = [](const ShadowSettings& s) { return std::max(s.pcss.filter_taps, s.pcss.blocker_taps); },
      .set_uniforms =
          [](const gl::Program& p, const ShadowSettings& s) {
            p.set("u_blocker_taps", s.pcss.blocker_taps);
            p.set("u_max_grid_taps", s.pcss.max_grid_taps);
            p.set("u_pcss_search_scale", s.pcss.search_scale);
            p.set("u_taps", s.pcss.filter_taps);
          },
  };
  return entry;
}

}  // namespace penumbra::shadows
