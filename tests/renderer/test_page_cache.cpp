// The virtual shadow map's page cache without GL (adaptive/page_cache.h): what a frame admits, keeps,
// evicts and invalidates, the coarse floor of a full pool, and the page tables, against references
// worked out by hand on a tiny layout.
#include <gtest/gtest.h>

#include <map>
#include <set>
#include <stdexcept>
#include <vector>

#include "adaptive/page_cache.h"

namespace {

using namespace penumbra::adaptive;

// Three levels of 4 × 4 pages of 4 texels of 1 world unit at level 0: a level-0 page is 4 units
// wide, level 1's 8, level 2's 16. A camera at the origin puts every level's window corner at
// minus two pages.
VirtualMapLayout tiny() {
  VirtualMapLayout l;
  l.levels = 3;
  l.texel0_ws = 1.0;
  l.page_texels = 4;
  l.pages_per_side = 4;
  return l;
}

std::vector<int> slots_of(const PageCache::Update& u) {
  std::vector<int> s;
  for (const auto& a : u.to_draw) s.push_back(a.slot);
  return s;
}

TEST(PageCache, AdmitsWhatIsAskedForOnceAndKeepsItCached) {
  PageCache cache(tiny(), 16);
  const std::set<Page> asked = {{0, 1, 1}, {0, 2, 1}, {1, 0, 3}};
  const PageCache::Update first = cache.update(asked, {0, 0});
  EXPECT_EQ(first.stats.requested, 3);
  EXPECT_EQ(first.stats.drawn, 3);
  EXPECT_EQ(first.stats.cached, 0);
  EXPECT_EQ(first.stats.resident, 3);
  EXPECT_EQ(first.stats.floor_level, 0);  // the pool holds every page: no floor needed
  EXPECT_EQ(first.stats.missing, 0);
  // Coarse levels first; the slots taken from the bottom of the pool.
  ASSERT_EQ(first.to_draw.size(), 3u);
  EXPECT_EQ(first.to_draw[0].key, (PageKey{1, -2 + 0, -2 + 3}));
  EXPECT_EQ(slots_of(first), (std::vector<int>{0, 1, 2}));
  for (const Page& p : asked) EXPECT_GE(cache.slot_of(p), 0);
  EXPECT_EQ(cache.slot_of({0, 0, 0}), -1);
  EXPECT_EQ(cache.slot_of({7, 0, 0}), -1);  // outside the layout

  const PageCache::Update again = cache.update(asked, {0, 0});
  EXPECT_EQ(again.stats.drawn, 0);
  EXPECT_EQ(again.stats.cached, 3);
  EXPECT_TRUE(again.to_draw.empty());
  for (PageCache::SlotState s : cache.slot_states()) EXPECT_NE(s, PageCache::SlotState::drawn);
}

// A frame drawn anew (map.virtual_cache off: every page invalidated before the frame) puts its pages
// in the slots a fresh cache would: where a page lands in the pool moves its raster by the slot's
// offset, which llvmpipe rounds (about 1e-5 of visibility, a few pixels more), so an uncached frame's
// image would otherwise depend on the frames before it.
// Pages drawn with the tiles their pixels read (MarkResult::tiles): a page is admitted with the
// tiles asked for; asked again for tiles within them it stays cached; asked for a tile it lacks it is
// drawn again in its slot with both (widened, counted drawn, not cached); a page without tiles, and
// the floor, is whole, and a whole page covers any tiles.
TEST(PageCache, APageIsDrawnWithItsTilesAndAgainForATileItLacks) {
  PageCache cache(tiny(), 16);
  const Page a{0, 1, 1}, b{0, 2, 1}, c{1, 0, 3};
  const std::set<Page> asked = {a, b, c};
  PageTiles tiles = {{a, 0x3}, {b, TileMask{1} << 63}};  // c: not said, whole
  const PageCache::Update first = cache.update(asked, {0, 0}, &tiles);
  ASSERT_EQ(first.to_draw.size(), 3u);
  std::map<PageKey, PageCache::Admitted> drawn;
  for (const auto& d : first.to_draw) drawn[d.key] = d;
  EXPECT_EQ(drawn.at(cache.key_of(a)).tiles, TileMask{0x3});
  EXPECT_EQ(drawn.at(cache.key_of(b)).tiles, TileMask{1} << 63);
  EXPECT_EQ(drawn.at(cache.key_of(c)).tiles, kEveryTile);
  EXPECT_EQ(first.stats.widened, 0);

  tiles = {{a, 0x1}, {b, TileMask{1} << 63}, {c, 0x10}};  // within what each was drawn with
  const PageCache::Update same = cache.update(asked, {0, 0}, &tiles);
  EXPECT_TRUE(same.to_draw.empty());
  EXPECT_EQ(same.stats.cached, 3);
  EXPECT_EQ(same.stats.widened, 0);

  tiles = {{a, 0x4}, {b, TileMask{1} << 63}};  // a lacks tile 2
  const int slot_a = cache.slot_of(a);
  const PageCache::Update wider = cache.update(asked, {0, 0}, &tiles);
  ASSERT_EQ(wider.to_draw.size(), 1u);
  EXPECT_EQ(wider.to_draw[0].slot, slot_a) << "drawn again in its own slot";
  EXPECT_EQ(wider.to_draw[0].tiles, TileMask{0x7}) << "the tiles it had and the new one";
  EXPECT_EQ(wider.stats.widened, 1);
  EXPECT_EQ(wider.stats.drawn, 1);
  EXPECT_EQ(wider.stats.cached, 2);
  EXPECT_EQ(cache.slot_states()[static_cast<std::size_t>(slot_a)], PageCache::SlotState::drawn);

  // A full pool (AFullPoolKeepsACoarseFloorAndMissesTheFarFinePages' layout and pages, each asked for
  // with one tile): six pages missing, whose pixels read the floor level anywhere; every page drawn
  // whole, the two asked-for ones resident too.
  VirtualMapLayout fine = tiny();
  fine.page_texels = 64;
  fine.texel0_ws = 1.0 / 16;
  PageCache small(fine, 6);
  std::set<Page> eight;
  PageTiles one_tile;
  for (int x = 0; x < 4; ++x)
    for (int y = 1; y < 3; ++y) eight.insert({0, x, y}), one_tile[{0, x, y}] = 0x1;
  const PageCache::Update full = small.update(eight, {0, 0}, &one_tile);
  EXPECT_EQ(full.stats.missing, 6);
  ASSERT_EQ(full.to_draw.size(), 6u);
  for (const auto& d : full.to_draw) EXPECT_EQ(d.tiles, kEveryTile) << "level " << d.key.level;

  const PageCache::Update whole = cache.update(asked, {0, 0});  // no tiles: whole pages
  ASSERT_EQ(whole.to_draw.size(), 2u) << "a and b lack tiles; c was drawn whole";
  for (const auto& d : whole.to_draw) EXPECT_EQ(d.tiles, kEveryTile);
  EXPECT_TRUE(cache.update(asked, {0, 0}, &tiles).to_draw.empty()) << "whole pages hold any tiles";
}

TEST(PageCache, InvalidatingAllGivesTheSlotsOfAFreshCache) {
  const std::set<Page> first = {{0, 1, 1}, {0, 2, 1}, {1, 0, 3}, {2, 1, 1}};
  const std::set<Page> second = {{0, 0, 0}, {0, 3, 2}, {1, 1, 1}};
  for (const std::set<Page>& asked : {first, second}) {
    PageCache fresh(tiny(), 16);
    const PageCache::Update expected = fresh.update(asked, {0, 0});
    PageCache used(tiny(), 16);
    used.update(first, {0, 0});
    used.update(second, {4, -4});  // a moved camera: pages in other slots beside the first frame's
    used.invalidate_all();
    const PageCache::Update got = used.update(asked, {0, 0});
    EXPECT_EQ(slots_of(got), slots_of(expected));
    EXPECT_EQ(used.table(), fresh.table());
  }
}

TEST(PageCache, AMovingCameraKeepsPagesByTheirPlaceInLightSpace) {
  PageCache cache(tiny(), 16);
  cache.update({{0, 2, 2}}, {0, 0});  // key (0, 0, 0): light space [0, 4)²
  const int slot = cache.slot_of({0, 2, 2});
  // One level-0 page to the right: the window's corner moves a page, the page is now window (1, 2).
  const PageCache::Update moved = cache.update({{0, 1, 2}}, {4, 0});
  EXPECT_EQ(moved.stats.cached, 1);
  EXPECT_EQ(moved.stats.drawn, 0);
  EXPECT_EQ(cache.slot_of({0, 1, 2}), slot);
  EXPECT_EQ(cache.slot_of({0, 2, 2}), -1);
  EXPECT_EQ(cache.key_of({0, 1, 2}), (PageKey{0, 0, 0}));
  EXPECT_DOUBLE_EQ(cache.origin(0).x, -4.0);
  EXPECT_DOUBLE_EQ(cache.origin(1).x, -16.0);  // level 1's window has not moved (a page there is 8 wide)
}

// An uncached frame of late marks draws its pages anew but keeps the region floor: the kept pages
// are found by their place in light space for the camera given (here moved by one level-0 page,
// so that the kept level-0 page is window (1, 2) now), everything else is dropped and counted.
TEST(PageCache, InvalidatingAllButTheFloorKeepsExactlyTheFloor) {
  PageCache cache(tiny(), 16);
  const std::set<Page> floor = {{2, 1, 1}, {2, 2, 1}};
  std::set<Page> asked = floor;
  asked.insert({{0, 2, 2}, {1, 0, 0}});
  EXPECT_EQ(cache.update(asked, {0, 0}).stats.drawn, 4);
  const int floor_slot = cache.slot_of({2, 1, 1});
  const std::set<Page> kept = {{2, 1, 1}, {2, 2, 1}, {0, 1, 2}};  // level 2's window has not moved; (0, 1, 2) is the old (0, 2, 2)
  cache.invalidate_all_but(kept, {4, 0});
  const PageCache::Update next = cache.update(asked, {0, 0});  // the camera back: the same windows as the first frame
  EXPECT_EQ(next.stats.invalidated, 1) << "only (1, 0, 0) was dropped";
  EXPECT_EQ(next.stats.cached, 3);
  EXPECT_EQ(next.stats.drawn, 1);
  ASSERT_EQ(next.to_draw.size(), 1u);
  EXPECT_EQ(next.to_draw[0].key, (PageKey{1, -2, -2}));
  EXPECT_EQ(cache.slot_of({2, 1, 1}), floor_slot) << "a kept page stays in its slot";
  cache.invalidate_all_but({}, {0, 0});
  EXPECT_EQ(cache.resident(), 0) << "nothing kept: everything dropped";
  EXPECT_THROW(cache.invalidate_all_but({{3, 0, 0}}, {0, 0}), std::invalid_argument);
  EXPECT_THROW(cache.invalidate_all_but({{0, 4, 0}}, {0, 0}), std::invalid_argument);
}

TEST(PageCache, EvictsTheLeastRecentlyAskedForPageAndNeverOneTheFrameKeeps) {
  VirtualMapLayout one = tiny();
  one.levels = 1;  // no coarser floor to make room for
  PageCache cache(one, 4);
  cache.update({{0, 0, 0}, {0, 1, 0}, {0, 2, 0}, {0, 3, 0}}, {0, 0});  // frame 1: slots 0..3 in centre order
  const int a = cache.slot_of({0, 1, 0}), b = cache.slot_of({0, 2, 0});
  const int c = cache.slot_of({0, 0, 0}), d = cache.slot_of({0, 3, 0});
  cache.update({{0, 1, 0}, {0, 2, 0}}, {0, 0});  // frame 2 asks for two of them again
  const PageCache::Update third = cache.update({{0, 1, 0}, {0, 0, 1}}, {0, 0});  // frame 3: one kept, one new
  EXPECT_EQ(third.stats.evicted, 1);
  EXPECT_EQ(third.stats.cached, 1);
  ASSERT_EQ(third.to_draw.size(), 1u);
  // The new page takes the slot of a page last asked for in frame 1 (c or d; of those the lowest
  // slot), never a's (asked for now) nor b's (asked for in frame 2).
  EXPECT_EQ(third.to_draw[0].slot, std::min(c, d));
  EXPECT_EQ(cache.slot_of({0, 1, 0}), a);
  EXPECT_EQ(cache.slot_of({0, 2, 0}), b);
  // Frame 4 needs two new pages: the other frame-1 page goes first, then b (frame 2), never a.
  const PageCache::Update fourth = cache.update({{0, 1, 0}, {0, 0, 1}, {0, 1, 1}, {0, 2, 1}}, {0, 0});
  EXPECT_EQ(fourth.stats.evicted, 2);
  const std::vector<int> drawn = slots_of(fourth);
  const std::set<int> taken(drawn.begin(), drawn.end());
  EXPECT_EQ(taken, (std::set<int>{std::max(c, d), b}));
  EXPECT_EQ(cache.slot_of({0, 1, 0}), a);
  EXPECT_EQ(cache.resident(), 4);
}

TEST(PageCache, AFullPoolKeepsACoarseFloorAndMissesTheFarFinePages) {
  // Pages of the tiny layout's sizes but 64 texels each (the floor's margin of 4 texels is then a
  // sixteenth of a page). Eight level-0 pages asked for, a pool of 6: level 0 cannot hold them,
  // level 1's pages under them are 8 (4 across, 2 down), level 2's 4: the floor is level 2, and the
  // two slots left take the asked-for pages nearest the window's centre.
  VirtualMapLayout fine = tiny();
  fine.page_texels = 64;
  fine.texel0_ws = 1.0 / 16;
  PageCache cache(fine, 6);
  std::set<Page> asked;
  for (int x = 0; x < 4; ++x)
    for (int y = 1; y < 3; ++y) asked.insert({0, x, y});
  const PageCache::Update u = cache.update(asked, {0, 0});
  ASSERT_EQ(u.stats.floor_level, 2);
  EXPECT_EQ(u.stats.floor, 4);
  EXPECT_EQ(u.stats.missing, 6);
  EXPECT_EQ(u.stats.drawn, 6);
  EXPECT_EQ(u.stats.resident, 6);
  EXPECT_EQ(u.stats.missing + (u.stats.drawn - u.stats.floor), 8);  // every asked-for page is resident or missing
  // The floor comes first: every asked-for page is resident, or a page of the floor level covers
  // its square.
  for (const Page& p : asked) {
    if (cache.slot_of(p) >= 0) continue;
    const PageKey k = cache.key_of(p);
    const int f = u.stats.floor_level;
    const PageKey under{f, k.x >> f, k.y >> f};  // level f's page holding this page's corner (squares nest)
    EXPECT_GE(cache.slot_of(cache.page_of(under)), 0) << "level " << p.level << " page " << p.x << ", " << p.y;
  }
  // What is resident of the asked-for level 0 is nearest the window's centre.
  for (const Page& p : asked) {
    if (cache.slot_of(p) < 0) continue;
    EXPECT_TRUE(p.x == 1 || p.x == 2) << p.x;
  }
}

TEST(PageCache, APoolBelowTheCoarsestLevelsNeedIsRefused) {
  PageCache cache(tiny(), 1);
  // Two level-2 pages: not even the coarsest level fits one slot.
  const std::set<Page> asked = {{2, 0, 0}, {2, 3, 3}};
  try {
    cache.update(asked, {0, 0});
    FAIL() << "a pool of one slot took two coarsest pages";
  } catch (const PoolTooSmall& e) {
    EXPECT_EQ(e.pages(), 2);
    EXPECT_NE(std::string(e.what()).find("--map.virtual_pool_pages 1: a pool of 1 page slot cannot hold the 2 pages"), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("give at least 2"), std::string::npos) << e.what();
  }
  EXPECT_EQ(cache.resident(), 0);
  EXPECT_THROW(cache.update({{0, 4, 0}}, {0, 0}), std::invalid_argument);  // outside the layout
  EXPECT_THROW(PageCache(tiny(), 0), std::invalid_argument);
}

TEST(PageCache, AMovedCastersOldAndNewBoundsDropOnlyThePagesOverThem) {
  PageCache cache(tiny(), 16);
  // Keys of level 0 span [4x, 4x + 4); level 1's [8x, 8x + 8).
  const std::set<Page> asked = {{0, 0, 0}, {0, 3, 3}, {1, 1, 1}, {1, 3, 0}};
  cache.update(asked, {0, 0});
  // A caster moved from around (-7, -7) (level-0 key (-2, -2); level-1 key (-1, -1)) to (13, -13)
  // (level-1 key (1, -2)).
  int dropped = cache.invalidate({-7.5, -7.5}, {-6.5, -6.5});
  dropped += cache.invalidate({12.5, -13.5}, {13.5, -12.5});
  EXPECT_EQ(dropped, 3);
  EXPECT_EQ(cache.slot_of({0, 0, 0}), -1);
  EXPECT_EQ(cache.slot_of({1, 1, 1}), -1);
  EXPECT_EQ(cache.slot_of({1, 3, 0}), -1);
  EXPECT_GE(cache.slot_of({0, 3, 3}), 0);
  EXPECT_EQ(cache.invalidate({1, 1}, {0, 0}), 0);  // empty rectangle
  const PageCache::Update next = cache.update(asked, {0, 0});
  EXPECT_EQ(next.stats.invalidated, 3);
  EXPECT_EQ(next.stats.drawn, 3);
  EXPECT_EQ(next.stats.cached, 1);
  cache.invalidate_all();
  EXPECT_EQ(cache.resident(), 0);
  EXPECT_EQ(cache.update(asked, {0, 0}).stats.invalidated, 4);
}

TEST(PageCache, TheTablesHoldEachResidentPageOfTheWindowsAndNothingElse) {
  PageCache cache(tiny(), 16);
  const std::set<Page> asked = {{0, 0, 0}, {0, 3, 2}, {1, 2, 1}, {2, 1, 3}};
  cache.update(asked, {0, 0});
  // Move the camera two level-0 pages right: level 0's window moves two pages, level 1's one; the
  // cached pages stay where they are in light space.
  cache.update({{0, 1, 2}}, {8, 0});
  const std::vector<std::int32_t> table = cache.table();
  ASSERT_EQ(table.size(), 3u * 4 * 4);
  std::map<PageKey, int> expected;  // by key, from the pool's contents
  for (std::size_t s = 0; s < cache.slots().size(); ++s)
    if (cache.slots()[s].used) expected[cache.slots()[s].key] = static_cast<int>(s);
  int entries = 0;
  for (int level = 0; level < 3; ++level)
    for (int y = 0; y < 4; ++y)
      for (int x = 0; x < 4; ++x) {
        const auto it = expected.find(cache.key_of({level, x, y}));
        const int want = it == expected.end() ? -1 : it->second;
        EXPECT_EQ(table[static_cast<std::size_t>((level * 4 + y) * 4 + x)], want) << level << " " << x << " " << y;
        entries += want >= 0;
      }
  // Level 0's page (0, 0) of the first frame has scrolled out of the window (it is cached, not in
  // the table); the others are in it.
  EXPECT_EQ(cache.resident(), 4);
  EXPECT_EQ(entries, 3);
  EXPECT_EQ(table[static_cast<std::size_t>((0 * 4 + 2) * 4 + 1)], cache.slot_of({0, 1, 2}));
}

}  // namespace
