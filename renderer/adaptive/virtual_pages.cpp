#include "adaptive/virtual_pages.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

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
  const double page_ws = layout.page_ws(level);
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
      const double page_ws = layout.page_ws(level);
      const LightXY& o = origins[static_cast<std::size_t>(level)];
      const LightXY local{(p.light_xy.x - o.x) / page_ws, (p.light_xy.y - o.y) / page_ws};
      if (local.x < 0 || local.y < 0 || local.x >= layout.pages_per_side || local.y >= layout.pages_per_side) continue;
      // The pages the filter reaches: [p - r, p + r] in light space, the normal offset wider, within the level.
      const double reach = (r + options.reach_texels * layout.texel_ws(level)) / page_ws;
      const int x0 = std::max(0, static_cast<int>(std::floor(local.x - reach)));
      const int x1 = std::min(layout.pages_per_side - 1, static_cast<int>(std::floor(local.x + reach)));
      const int y0 = std::max(0, static_cast<int>(std::floor(local.y - reach)));
      const int y1 = std::min(layout.pages_per_side - 1, static_cast<int>(std::floor(local.y + reach)));
      // Each page's tiles under the square, a texel wider (the filters gather 2 × 2 blocks from even
      // texels), as virtual_mark.comp's mark_square takes them.
      const double texel = 1.0 / layout.page_texels;  // in pages
      const auto tile = [](double pages) {
        return static_cast<int>(std::clamp(std::floor(pages * kTilesPerSide), 0.0, static_cast<double>(kTilesPerSide - 1)));
      };
      for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) {
          const Page page{level, x, y};
          out.pages.insert(page);
          const int tx0 = tile(local.x - reach - texel - x), tx1 = tile(local.x + reach + texel - x);
          const int ty0 = tile(local.y - reach - texel - y), ty1 = tile(local.y + reach + texel - y);
          TileMask mask = 0;
          for (int ty = ty0; ty <= ty1; ++ty)
            for (int tx = tx0; tx <= tx1; ++tx) mask |= TileMask{1} << (ty * kTilesPerSide + tx);
          out.tiles[page] |= mask;
        }
      ++out.pixels_per_level[static_cast<std::size_t>(level)];
      break;
    }
    if (level == layout.levels) ++out.unmarked;
  }
  return out;
}

std::set<Page> rebase_pages(const std::set<Page>& pages, LightXY from, LightXY to, const VirtualMapLayout& layout) {
  std::set<Page> out;
  for (const Page& p : pages) {
    if (p.level < 0 || p.level >= layout.levels) continue;
    const double page_ws = layout.page_ws(p.level);
    const LightXY a = level_origin(p.level, from, layout), b = level_origin(p.level, to, layout);
    // Both corners are whole pages: the shift is a whole number of pages.
    const auto dx = static_cast<std::int64_t>(std::llround((a.x - b.x) / page_ws));
    const auto dy = static_cast<std::int64_t>(std::llround((a.y - b.y) / page_ws));
    const std::int64_t x = p.x + dx, y = p.y + dy;
    if (x < 0 || y < 0 || x >= layout.pages_per_side || y >= layout.pages_per_side) continue;
    out.insert({p.level, static_cast<int>(x), static_cast<int>(y)});
  }
  return out;
}

std::set<Page> region_floor_pages(LightXY lo, LightXY hi, LightXY camera_xy, const VirtualMapLayout& layout, int max_pages) {
  std::set<Page> out;
  if (!(std::isfinite(lo.x) && std::isfinite(lo.y) && std::isfinite(hi.x) && std::isfinite(hi.y)) || lo.x > hi.x || lo.y > hi.y)
    return out;
  for (int level = 0; level < layout.levels; ++level) {
    const bool coarsest = level == layout.levels - 1;
    const double page_ws = layout.page_ws(level);
    const LightXY o = level_origin(level, camera_xy, layout);
    // The rectangle in the window's pages (floating: beyond the window where it reaches out).
    const double x0 = std::floor((lo.x - o.x) / page_ws), x1 = std::floor((hi.x - o.x) / page_ws);
    const double y0 = std::floor((lo.y - o.y) / page_ws), y1 = std::floor((hi.y - o.y) / page_ws);
    const double n = layout.pages_per_side;
    const bool inside = x0 >= 0 && y0 >= 0 && x1 < n && y1 < n;
    const double count = (std::min(x1, n - 1) - std::max(x0, 0.0) + 1) * (std::min(y1, n - 1) - std::max(y0, 0.0) + 1);
    if (!coarsest && !(inside && count <= max_pages)) continue;
    for (auto y = static_cast<int>(std::max(y0, 0.0)); y <= static_cast<int>(std::min(y1, n - 1)); ++y)
      for (auto x = static_cast<int>(std::max(x0, 0.0)); x <= static_cast<int>(std::min(x1, n - 1)); ++x) out.insert({level, x, y});
    break;
  }
  return out;
}

TexelRect tiles_rect(TileMask tiles, int page_texels, int margin_texels) {
  if (page_texels <= 0 || page_texels % kTilesPerSide != 0)
    throw std::invalid_argument("tiles_rect: a page of " + std::to_string(page_texels) + " texels is not cut into " +
                                std::to_string(kTilesPerSide) + " tiles a side");
  if (margin_texels < 0) throw std::invalid_argument("tiles_rect: negative margin " + std::to_string(margin_texels));
  const TexelRect page{0, 0, page_texels, page_texels};
  if (tiles == kEveryTile || tiles == 0) return page;
  int tx0 = kTilesPerSide, ty0 = kTilesPerSide, tx1 = -1, ty1 = -1;  // the marked tiles' bounds, inclusive
  for (int b = 0; b < kTilesPerSide * kTilesPerSide; ++b)
    if ((tiles >> b) & 1u) {
      tx0 = std::min(tx0, b % kTilesPerSide), tx1 = std::max(tx1, b % kTilesPerSide);
      ty0 = std::min(ty0, b / kTilesPerSide), ty1 = std::max(ty1, b / kTilesPerSide);
    }
  const int t = page_texels / kTilesPerSide;
  return {std::max(tx0 * t - margin_texels, 0), std::max(ty0 * t - margin_texels, 0), std::min((tx1 + 1) * t + margin_texels, page_texels),
          std::min((ty1 + 1) * t + margin_texels, page_texels)};
}

}  // namespace penumbra::adaptive
