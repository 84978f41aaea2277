#include "adaptive/virtual_pages.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace penumbra::adaptive {

std::string_view to_string(Marking m) { return m == Marking::rule ? "rule" : "footprint"; }

double requested_texel_ws(const PixelRequest& p, const MarkOptions& options) {
  const double floor_ws = p.footprint_ws * options.min_texel_px;
  if (options.marking == Marking::footprint || p.radius_ws <= 0) return floor_ws;
  return std::max(p.radius_ws / options.c_texels, floor_ws);
}

int level_for_texel(double texel_ws, const VirtualMapLayout& layout) {
  if (!(texel_ws > 0)) return 0;
  const double k = std::floor(std::log2(texel_ws / layout.texel0_ws) + 1e-9);
  return static_cast<int>(std::clamp(k, 0.0, static_cast<double>(layout.levels - 1)));
}

std::vector<std::int64_t> MarkResult::pages_per_level() const {
  std::vector<std::int64_t> n(pixels_per_level.size(), 0);
  for (const Page& p : pages)
    if (p.level >= 0 && static_cast<std::size_t>(p.level) < n.size()) ++n[static_cast<std::size_t>(p.level)];
  return n;
}

LightXY level_origin(int level, LightXY camera_xy, const VirtualMapLayout& layout) {
  const double page_ws = layout.page_texels * layout.texel0_ws * std::ldexp(1.0, level);
  const double half = 0.5 * layout.pages_per_side * page_ws;
  return {std::floor((camera_xy.x - half) / page_ws) * page_ws, std::floor((camera_xy.y - half) / page_ws) * page_ws};
}

MarkResult mark_pages(const std::vector<PixelRequest>& pixels, LightXY camera_xy, const VirtualMapLayout& layout,
                      const MarkOptions& options) {
  if (layout.levels < 1 || layout.page_texels < 1 || layout.pages_per_side < 1 || !(layout.texel0_ws > 0))
    throw std::invalid_argument("virtual map: levels, page_texels, pages_per_side and texel0_ws must be positive");
  MarkResult out;
  out.pixels_per_level.assign(static_cast<std::size_t>(layout.levels), 0);
  std::vector<LightXY> origins;
  for (int k = 0; k < layout.levels; ++k) origins.push_back(level_origin(k, camera_xy, layout));
  for (const PixelRequest& p : pixels) {
    int level = level_for_texel(requested_texel_ws(p, options), layout);
    const double r = std::max(0.0, p.radius_ws);
    for (; level < layout.levels; ++level) {
      const double page_ws = layout.page_texels * layout.texel0_ws * std::ldexp(1.0, level);
      const LightXY& o = origins[static_cast<std::size_t>(level)];
      const LightXY local{(p.light_xy.x - o.x) / page_ws, (p.light_xy.y - o.y) / page_ws};
      if (local.x < 0 || local.y < 0 || local.x >= layout.pages_per_side || local.y >= layout.pages_per_side) continue;
      // The pages the filter reaches: [p - r, p + r] in light space, within the level.
      const double reach = r / page_ws;
      const int x0 = std::max(0, static_cast<int>(std::floor(local.x - reach)));
      const int x1 = std::min(layout.pages_per_side - 1, static_cast<int>(std::floor(local.x + reach)));
      const int y0 = std::max(0, static_cast<int>(std::floor(local.y - reach)));
      const int y1 = std::min(layout.pages_per_side - 1, static_cast<int>(std::floor(local.y + reach)));
      for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) out.pages.insert({level, x, y});
      ++out.pixels_per_level[static_cast<std::size_t>(level)];
      break;
    }
    if (level == layout.levels) ++out.unmarked;
  }
  return out;
}

}  // namespace penumbra::adaptive
