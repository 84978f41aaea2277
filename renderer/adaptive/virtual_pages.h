#pragma once
// Page marking for a virtual shadow map of the sun, GL-free: clipmap
// levels around the camera, level k's texel t0·2^k, each level a virtual texture of
// pages_per_side² pages of page_texels² texels centred (page-snapped) on the camera in light
// space. Each pixel asks for the coarsest level whose texel still satisfies its rule, and for
// the pages of that level its filter reaches:
//
//   rule       texel <= max(r / c, s · min_texel_px): the filter-to-resolution rule with the
//              pixel floor (r the filter's world radius at the pixel, s the pixel's world
//              footprint, c in texels);
//   footprint  texel <= s · min_texel_px: the pixel's footprint alone (what engines' virtual
//              shadow maps use).
//
// A pixel whose level does not reach it (outside the level's extent) takes the next coarser one
// that does; beyond the coarsest it is not marked (counted). Pages are counted once per frame.
//
// This is the CPU reference of the marking: it walks every pixel on one core, far too slow for
// every frame; test a GPU marking with it. Penumbra::adaptive also holds the page cache
// (adaptive/page_cache.h: which slot holds which page, what a frame admits and evicts, the tables). The GPU side is the renderer's (Penumbra::renderer): shaders/virtual_mark.comp marks the same
// pages on the GPU, and is installed for another engine as share/penumbra/shaders/virtual_mark.comp
// with its contract <penumbra/shaders/virtual_mark_contract.h> (docs/virtual-pages-in-your-engine.md);
// shadows/virtual_shadow_map.h has the page pool and the tables on the GPU, drawing the pages the
// cache admits, and PageMarker; shaders/virtual_pages.glsl reads and filters depths through
// the tables.
#include <cmath>
#include <cstdint>
#include <map>
#include <set>
#include <string_view>
#include <tuple>
#include <vector>

#include <penumbra/published.h>

namespace penumbra::adaptive {

// A point in light space (orthographic: across the light), world units. No GLM here: adaptive/ stays
// free of it (docs/architecture.md).
struct LightXY {
  double x = 0, y = 0;
};

struct VirtualMapLayout {
  int levels = 12;            // clipmap levels
  double texel0_ws = 0.005;   // level 0's texel, world units
  int page_texels = 128;
  int pages_per_side = 64;    // each level: (page_texels · pages_per_side)² virtual texels
  double texel_ws(int level) const { return texel0_ws * std::ldexp(1.0, level); }  // level k's texel: texel0_ws · 2^k
  double page_ws(int level) const { return page_texels * texel_ws(level); }        // level k's page side
};

enum class Marking { rule, footprint };
std::string_view to_string(Marking m);

// One pixel's request.
struct PixelRequest {
  LightXY light_xy;          // the surface point in light space
  double footprint_ws = 0;   // the pixel's world footprint s
  double radius_ws = 0;      // the filter's world radius r at the pixel (0: none)
};

struct MarkOptions {
  Marking marking = Marking::rule;
  double c_texels = kPublishedC;  // the rule's constant (the published value until a calibration says otherwise)
  // The pixel floor (texels no finer than this many footprints): 2^-0.5, so that a level's power of
  // two gives texels of 0.35 to 0.71 footprints where the floor sets it (shadows::ShadowMapParams::
  // virtual_min_texel_px says why and is this default).
  double min_texel_px = 0.7071;
  // How far past the filter's square the shading reads, in texels of the level it reads: the
  // lookup moved along the surface normal (shadows::ShadowMapParams::normal_offset_texels). A pixel
  // marks its square that much wider, so that the pages (and tiles) its moved square reads are
  // its own, not a coarser level's it falls back to.
  double reach_texels = 0;
};

// The finest texel the pixel needs (rule or footprint), world units.
double requested_texel_ws(const PixelRequest& p, const MarkOptions& options);
// The coarsest level whose texel is at most `texel_ws` (0 when even level 0 is coarser), at most
// layout.levels - 1.
int level_for_texel(double texel_ws, const VirtualMapLayout& layout);

struct Page {
  int level = 0, x = 0, y = 0;
  // Ordered by level, then x, then y (C++17: the installed headers compile there too).
  bool operator<(const Page& o) const { return std::tie(level, x, y) < std::tie(o.level, o.x, o.y); }
  bool operator==(const Page& o) const { return std::tie(level, x, y) == std::tie(o.level, o.x, o.y); }
};

// The tiles of a page some pixel reads: the page cut into 8 × 8 tiles, tile (tx, ty) (ty from the
// page's lower edge) bit ty · 8 + tx. kEveryTile: the whole page.
using TileMask = std::uint64_t;
inline constexpr int kTilesPerSide = 8;  // the marking's VIRTUAL_MARK_TILES_PER_SIDE
inline constexpr TileMask kEveryTile = ~TileMask{0};
using PageTiles = std::map<Page, TileMask>;

// The texels of a page of `page_texels`² to draw for `tiles`: the bounding rectangle of the marked
// tiles, `margin_texels` wider on each side (the renderer's one texel: the marking's and the
// shading's float arithmetic may disagree at a tile's edge), clipped to the page; [x0, x1) × [y0, y1) in the page's texels, y from its
// lower edge. The whole page for kEveryTile and for an empty mask (no tile known).
struct TexelRect {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  bool operator==(const TexelRect& o) const { return std::tie(x0, y0, x1, y1) == std::tie(o.x0, o.y0, o.x1, o.y1); }
};
TexelRect tiles_rect(TileMask tiles, int page_texels, int margin_texels);

struct MarkResult {
  std::set<Page> pages;               // every page some pixel asked for
  // Per page, the tiles the squares that marked it reach, a texel wider (as the GPU marking's,
  // PageMarker, records them); a page without an entry is whole.
  PageTiles tiles;
  std::vector<std::int64_t> pixels_per_level;  // pixels that sample each level
  std::int64_t unmarked = 0;          // pixels beyond the coarsest level's extent
  std::vector<std::int64_t> pages_per_level() const;
};

// The level-k window's lower corner in light space for a camera at `camera_xy` (page-snapped, the
// camera at the window's centre).
LightXY level_origin(int level, LightXY camera_xy, const VirtualMapLayout& layout);

MarkResult mark_pages(const std::vector<PixelRequest>& pixels, LightXY camera_xy, const VirtualMapLayout& layout,
                      const MarkOptions& options);

// Marks read a frame late (no read-back waited for within a frame): the window-relative `pages`
// marked for a camera at `from` as pages of the windows of a camera at `to`, the same places in
// light space; those now outside their level's window are dropped.
std::set<Page> rebase_pages(const std::set<Page>& pages, LightXY from, LightXY to, const VirtualMapLayout& layout);

// What a frame asks for besides the marks it has, so that every pixel of a view whose light-space
// footprint lies in [lo, hi] finds a page even where its own marks are not read yet (the first
// frame after a cut; a pixel newly in view): the pages over [lo, hi] of the finest level whose
// window holds the whole rectangle in at most `max_pages` pages; if none does, the coarsest
// level's pages over it (clipped to its window). Empty for an empty or non-finite rectangle.
std::set<Page> region_floor_pages(LightXY lo, LightXY hi, LightXY camera_xy, const VirtualMapLayout& layout, int max_pages);

}  // namespace penumbra::adaptive
