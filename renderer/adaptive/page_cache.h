#pragma once
// The page cache of a virtual shadow map, GL-free: which page of light space each slot of a pool
// holds, which pages a frame keeps and in what order, which it must draw, which it evicts, which a
// moved caster or light invalidates, and the page tables the shaders read. The renderer's
// VirtualShadowMap (shadows/virtual_shadow_map.h) draws what update() returns into the slots it
// names and uploads table(); another engine can drive its own pool with it the same way.
//
// Pages are cached by their place in light space (level, page column and row counted from the
// light-space origin: PageKey), so a page stays valid while the camera moves and the level windows
// scroll over it. Within a frame a coarse floor is served first (the pages of the finest level that
// the pool holds under every requested page), then coarse levels, and within a level the pages
// nearest the camera: when the pool cannot hold every requested page, what is missing is fine pages
// far from the camera, and a pixel falls back to a coarser level that covers it, at worst the floor,
// never to none. A pool that cannot hold even the coarsest level's pages under the requested ones is
// refused (PoolTooSmall). Pages not asked for stay cached until their slot is needed: a free slot
// first, then the least recently asked-for page (ties: the lowest slot).
#include <cstdint>
#include <map>
#include <set>
#include <stdexcept>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include <penumbra/adaptive/virtual_pages.h>

namespace penumbra::adaptive {

// A page by its place in light space: level, then column and row of level-sized pages counted from
// the light-space origin (window-relative Pages move with the camera; keys do not).
struct PageKey {
  int level = 0;
  std::int64_t x = 0, y = 0;
  bool operator<(const PageKey& o) const { return std::tie(level, x, y) < std::tie(o.level, o.x, o.y); }
  bool operator==(const PageKey& o) const { return std::tie(level, x, y) == std::tie(o.level, o.x, o.y); }
};

// A pool too small for even the coarsest level under the requested pages: a pixel would find no
// page and be shaded lit. The message begins with --map.virtual_pool_pages (the renderer's option)
// and says the least pool side that holds that level; `pages` is how many pages it is.
class PoolTooSmall : public std::runtime_error {
 public:
  PoolTooSmall(const std::string& message, int pages) : std::runtime_error(message), pages_(pages) {}
  int pages() const { return pages_; }

 private:
  int pages_;
};

struct PageCacheStats {
  int requested = 0;    // pages the frame asked for
  int cached = 0;       // of those, already resident and valid: not drawn
  int drawn = 0;        // pages admitted this frame, to be drawn (floor pages included)
  int missing = 0;      // asked for, but the pool held the floor and coarser or nearer pages instead
  int floor = 0;        // pages of floor_level made resident though not asked for: what a missing page's pixels read
  int floor_level = -1; // the coarse floor's level (-1: nothing asked for); 0 when the pool holds every page asked for
  int evicted = 0;      // resident pages dropped to make room this frame
  int widened = 0;      // of the drawn, pages already resident drawn again for tiles they lacked
  int invalidated = 0;  // resident pages dropped since the last update (light or caster moved)
  int resident = 0;     // pages in the pool after the update (asked for or kept from earlier frames)
};

class PageCache {
 public:
  // A pool of `pool_slots` slots for `layout`'s pages. Throws std::invalid_argument for a layout
  // with non-positive sizes or levels, or fewer than one slot.
  PageCache(const VirtualMapLayout& layout, int pool_slots);

  const VirtualMapLayout& layout() const { return layout_; }
  int pool_slots() const { return static_cast<int>(slots_.size()); }
  // The world size of a page of `level`: page_texels · texel0_ws · 2^level.
  double page_ws(int level) const;

  struct Admitted {
    int slot = 0;
    PageKey key;
    TileMask tiles = kEveryTile;  // the tiles to draw (a page drawn again: those it had and those asked for)
  };
  struct Update {
    PageCacheStats stats;
    std::vector<Admitted> to_draw;  // pages admitted this frame, in residency order: draw each into its slot
  };
  // Moves the level windows to a camera at `camera_xy` and makes the `requested` pages
  // (window-relative, as mark_pages gives them for camera_xy) resident: the floor first, then the
  // rest, coarse levels first and nearest the camera first, as many as the pool holds. Cached pages
  // the frame keeps are kept first, so that none is evicted for another. Throws
  // std::invalid_argument for a page outside the layout (before anything changes) and PoolTooSmall.
  // `tiles`: the tiles each requested page's pixels read (MarkResult::tiles); a page not in it, and
  // every page without it, is whole. A page is drawn with the tiles asked for; a resident page asked
  // for a tile it was not drawn with is drawn again, with its tiles and the new ones (widened). When
  // pages are missing (a full pool) every page is drawn whole: their pixels read coarser pages
  // outside the tiles those were asked for.
  Update update(const std::set<Page>& requested, LightXY camera_xy, const PageTiles* tiles = nullptr);

  // Drops every page (the light, its depth range or the raster bias changed, or the frame is drawn
  // uncached); the next update takes the slots a fresh cache would.
  void invalidate_all();
  // Drops every page but those of `kept` (window-relative for a camera at `camera_xy`, as
  // region_floor_pages gives them): a frame that draws its pages anew keeps the coarse fallback an
  // engine keeps resident (the late marks' region floor). Counted as invalidated. Throws
  // std::invalid_argument for a kept page outside the layout (before anything changes).
  void invalidate_all_but(const std::set<Page>& kept, LightXY camera_xy);
  // Drops the resident pages whose light-space square meets the rectangle [lo, hi] (a caster's
  // light-space footprint, at any depth: call with a moved caster's old and new bounds). Returns how
  // many. An empty rectangle (lo > hi on an axis) drops none.
  int invalidate(LightXY lo, LightXY hi);

  // The slot of window-relative `page` in the last update's windows, or -1 when it is not resident
  // (or outside the layout).
  int slot_of(const Page& page) const;
  PageKey key_of(const Page& page) const;  // in the last update's windows
  Page page_of(const PageKey& key) const;  // window-relative in the last update's windows; for a key near them (int offsets)
  // Lower corner of level `level`'s window in light space, for the last update's windows.
  LightXY origin(int level) const;
  // The page tables: one pages_per_side² table per level, level-major, rows bottom-up (entry
  // (level · pages_per_side + y) · pages_per_side + x), each entry the slot holding that page of the
  // window or -1. What virtual_pages.glsl reads.
  std::vector<std::int32_t> table() const;

  enum class SlotState { free, drawn, cached };  // drawn: admitted by the last update
  std::vector<SlotState> slot_states() const;
  // The key each used slot holds, by slot (used: false for a free one).
  struct SlotContent {
    bool used = false;
    PageKey key;
  };
  std::vector<SlotContent> slots() const;
  int resident() const { return static_cast<int>(resident_.size()); }

 private:
  struct Slot {
    bool used = false;
    PageKey key;
    std::int64_t last_frame = -1;   // the last update that asked for it
    std::int64_t drawn_frame = -1;  // the update that admitted it
    TileMask tiles = kEveryTile;    // the tiles drawn into it
  };
  // The pages update() keeps, in the order it keeps them (the floor first); sets stats.floor and
  // stats.floor_level; throws PoolTooSmall.
  std::vector<PageKey> residency_order(const std::set<Page>& requested, PageCacheStats& stats) const;
  void free_slot(int slot);
  void reset_free_slots();  // every slot free, slot 0 on top (a fresh cache's order)

  VirtualMapLayout layout_;
  std::vector<Slot> slots_;
  std::vector<int> free_;  // unused slots, a stack (slot 0 on top at the start)
  std::map<PageKey, int> resident_;
  std::vector<std::int64_t> origin_pages_x_, origin_pages_y_;  // each level's window corner, in pages
  std::int64_t frame_ = 0;
  int invalidated_ = 0;
};

}  // namespace penumbra::adaptive
