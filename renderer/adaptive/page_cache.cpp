#include "page_cache.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace penumbra::adaptive {

PageCache::PageCache(const VirtualMapLayout& layout, int pool_slots) : layout_(layout) {
  if (layout.levels < 1 || layout.page_texels < 1 || layout.pages_per_side < 1 || !(layout.texel0_ws > 0) || pool_slots < 1)
    throw std::invalid_argument("page cache: levels, page_texels, pages_per_side, texel0_ws and the pool's slots must be positive");
  slots_.resize(static_cast<std::size_t>(pool_slots));
  reset_free_slots();
  origin_pages_x_.assign(static_cast<std::size_t>(layout.levels), 0);
  origin_pages_y_.assign(static_cast<std::size_t>(layout.levels), 0);
}

double PageCache::page_ws(int level) const { return layout_.page_ws(level); }

PageKey PageCache::key_of(const Page& page) const {
  const auto k = static_cast<std::size_t>(page.level);
  return {page.level, origin_pages_x_[k] + page.x, origin_pages_y_[k] + page.y};
}

Page PageCache::page_of(const PageKey& key) const {
  const auto k = static_cast<std::size_t>(key.level);
  return {key.level, static_cast<int>(key.x - origin_pages_x_[k]), static_cast<int>(key.y - origin_pages_y_[k])};
}

LightXY PageCache::origin(int level) const {
  const auto k = static_cast<std::size_t>(level);
  return {static_cast<double>(origin_pages_x_[k]) * page_ws(level), static_cast<double>(origin_pages_y_[k]) * page_ws(level)};
}

void PageCache::free_slot(int slot) {
  Slot& s = slots_[static_cast<std::size_t>(slot)];
  if (!s.used) return;
  resident_.erase(s.key);
  s = Slot{};
  free_.push_back(slot);
}

void PageCache::reset_free_slots() {
  free_.clear();
  for (int i = pool_slots() - 1; i >= 0; --i) free_.push_back(i);  // slot 0 on top
}

void PageCache::invalidate_all() {
  invalidated_ += static_cast<int>(resident_.size());
  resident_.clear();
  std::fill(slots_.begin(), slots_.end(), Slot{});
  // Every slot free in a fresh cache's order, not in the order they were freed: a frame drawn anew
  // then puts each page where a first frame would, whatever came before it.
  reset_free_slots();
}

void PageCache::invalidate_all_but(const std::set<Page>& kept, LightXY camera_xy) {
  std::set<PageKey> keys;
  for (const Page& p : kept) {
    if (p.level < 0 || p.level >= layout_.levels || p.x < 0 || p.y < 0 || p.x >= layout_.pages_per_side || p.y >= layout_.pages_per_side)
      throw std::invalid_argument("page cache: kept page outside the layout (level " + std::to_string(p.level) + ", " +
                                  std::to_string(p.x) + ", " + std::to_string(p.y) + ")");
    const LightXY o = level_origin(p.level, camera_xy, layout_);  // page-snapped, as update() takes it
    keys.insert({p.level, std::llround(o.x / page_ws(p.level)) + p.x, std::llround(o.y / page_ws(p.level)) + p.y});
  }
  for (int i = 0; i < pool_slots(); ++i) {
    const Slot& s = slots_[static_cast<std::size_t>(i)];
    if (!s.used || keys.count(s.key)) continue;
    free_slot(i);
    ++invalidated_;
  }
}

int PageCache::invalidate(LightXY lo, LightXY hi) {
  if (!(lo.x <= hi.x && lo.y <= hi.y)) return 0;
  int dropped = 0;
  for (int i = 0; i < pool_slots(); ++i) {
    const Slot& s = slots_[static_cast<std::size_t>(i)];
    if (!s.used) continue;
    const double w = page_ws(s.key.level);
    const double x0 = static_cast<double>(s.key.x) * w, y0 = static_cast<double>(s.key.y) * w;
    if (x0 <= hi.x && lo.x <= x0 + w && y0 <= hi.y && lo.y <= y0 + w) {
      free_slot(i);
      ++dropped;
    }
  }
  invalidated_ += dropped;
  return dropped;
}

std::vector<PageKey> PageCache::residency_order(const std::set<Page>& requested, PageCacheStats& stats) const {
  const auto from_centre = [c = layout_.pages_per_side - 1](const Page& p) {
    return (2 * p.x - c) * (2 * p.x - c) + (2 * p.y - c) * (2 * p.y - c);
  };
  const auto coarse_first = [&](const Page& a, const Page& b) {
    return a.level != b.level ? a.level > b.level : from_centre(a) < from_centre(b);
  };
  // The floor at level f: the pages of level f under each requested page of level f or finer, and
  // the requested pages coarser than f; at f = 0, every requested page. A finer page's square is
  // widened by 4 texels of level f, which a filter's square read there may reach beyond it (the
  // normal offset, its 2 × 2 blocks). The windows share the camera's centre: what lies outside
  // level f's window no pixel reads there.
  const auto floor_at = [&](int f) {
    std::set<Page> floor;
    const auto k = static_cast<std::size_t>(f);
    const double wf = page_ws(f), margin = 4 * wf / layout_.page_texels;
    for (const Page& p : requested) {
      if (p.level >= f) {
        floor.insert(p);
        continue;
      }
      const PageKey key = key_of(p);
      const double w = page_ws(p.level);
      const auto first_page = [&](std::int64_t i) { return static_cast<std::int64_t>(std::floor((static_cast<double>(i) * w - margin) / wf)); };
      const auto last_page = [&](std::int64_t i) { return static_cast<std::int64_t>(std::floor((static_cast<double>(i + 1) * w + margin) / wf)); };
      for (std::int64_t x = first_page(key.x); x <= last_page(key.x); ++x)
        for (std::int64_t y = first_page(key.y); y <= last_page(key.y); ++y) {
          const std::int64_t wx = x - origin_pages_x_[k], wy = y - origin_pages_y_[k];
          if (wx >= 0 && wy >= 0 && wx < layout_.pages_per_side && wy < layout_.pages_per_side)
            floor.insert({f, static_cast<int>(wx), static_cast<int>(wy)});
        }
    }
    return floor;
  };
  std::set<Page> floor;
  int level = 0;
  for (; level < layout_.levels; ++level) {
    floor = floor_at(level);
    if (static_cast<int>(floor.size()) <= pool_slots()) break;
  }
  if (level == layout_.levels) {
    const int side = static_cast<int>(std::lround(std::sqrt(static_cast<double>(pool_slots()))));
    throw PoolTooSmall("--map.virtual_pool_pages " + std::to_string(side) + ": a pool of " + std::to_string(pool_slots()) +
                           (pool_slots() == 1 ? " page slot" : " page slots") + " cannot hold the " + std::to_string(floor.size()) +
                           " pages of the coarsest level this view needs under its pixels; give at least " +
                           std::to_string(static_cast<int>(std::ceil(std::sqrt(static_cast<double>(floor.size()))))),
                       static_cast<int>(floor.size()));
  }
  stats.floor_level = requested.empty() ? -1 : level;
  std::vector<Page> first(floor.begin(), floor.end()), rest;
  for (const Page& p : requested)
    if (!floor.count(p)) rest.push_back(p);
  std::stable_sort(first.begin(), first.end(), coarse_first);
  std::stable_sort(rest.begin(), rest.end(), coarse_first);
  std::vector<PageKey> order;
  for (const Page& p : first) {
    order.push_back(key_of(p));
    stats.floor += !requested.count(p);
  }
  for (const Page& p : rest) order.push_back(key_of(p));
  return order;
}

PageCache::Update PageCache::update(const std::set<Page>& requested, LightXY camera_xy, const PageTiles* tiles) {
  for (const Page& page : requested)  // before anything changes
    if (page.level < 0 || page.level >= layout_.levels || page.x < 0 || page.y < 0 || page.x >= layout_.pages_per_side ||
        page.y >= layout_.pages_per_side)
      throw std::invalid_argument("virtual shadow map: page outside the layout (level " + std::to_string(page.level) + ", " +
                                  std::to_string(page.x) + ", " + std::to_string(page.y) + ")");
  ++frame_;
  for (int k = 0; k < layout_.levels; ++k) {
    const LightXY o = level_origin(k, camera_xy, layout_);  // page-snapped: whole pages
    origin_pages_x_[static_cast<std::size_t>(k)] = std::llround(o.x / page_ws(k));
    origin_pages_y_[static_cast<std::size_t>(k)] = std::llround(o.y / page_ws(k));
  }

  Update out;
  PageCacheStats& stats = out.stats;
  stats.requested = static_cast<int>(requested.size());
  stats.invalidated = invalidated_;
  invalidated_ = 0;
  // What the pool holds this frame, in order: first a coarse floor, the pages of level
  // stats.floor_level under every requested page (the finest level whose floor fits the pool with
  // the requested pages coarser than it), so that each pixel has a level to fall back to; then the
  // other requested pages, coarse levels first and within a level those nearest the camera. What
  // does not fit is missing: fine pages far from the camera, whose pixels read the floor.
  const std::vector<PageKey> order = residency_order(requested, stats);
  const auto kept = std::min(order.size(), static_cast<std::size_t>(pool_slots()));
  for (std::size_t i = kept; i < order.size(); ++i) stats.missing += requested.count(page_of(order[i])) > 0;
  // First what is cached, so that no page this frame keeps is evicted for another.
  // The floor's pages, and pages without tiles, whole; every page whole when some are missing: their
  // pixels read the first coarser resident level, anywhere in its pages.
  const auto tiles_of = [&](const PageKey& key) {
    if (!tiles || stats.missing > 0) return kEveryTile;
    const auto it = tiles->find(page_of(key));
    return it == tiles->end() || it->second == 0 ? kEveryTile : it->second;
  };
  std::vector<PageKey> wanted;
  for (std::size_t i = 0; i < kept; ++i) {
    const PageKey& key = order[i];
    if (const auto it = resident_.find(key); it != resident_.end()) {
      Slot& slot = slots_[static_cast<std::size_t>(it->second)];
      slot.last_frame = frame_;
      if (const TileMask need = tiles_of(key); (need & ~slot.tiles) != 0) {
        slot.tiles |= need;
        slot.drawn_frame = frame_;
        out.to_draw.push_back({it->second, key, slot.tiles});
        ++stats.widened;
      } else {
        stats.cached += requested.count(page_of(key)) > 0;
      }
    } else {
      wanted.push_back(key);
    }
  }
  for (const PageKey& key : wanted) {
    // A free slot, else the least recently asked-for page this frame does not keep (there is one:
    // the frame keeps at most a slot per page).
    int chosen = -1;
    if (!free_.empty()) {
      chosen = free_.back();
      free_.pop_back();
    } else {
      std::int64_t oldest = frame_;
      for (int i = 0; i < pool_slots(); ++i)
        if (slots_[static_cast<std::size_t>(i)].last_frame < oldest) oldest = slots_[static_cast<std::size_t>(i)].last_frame, chosen = i;
      if (chosen < 0) throw std::logic_error("page cache: no slot left for a page the frame keeps");
      free_slot(chosen);  // back on the free list: take it again
      free_.pop_back();
      ++stats.evicted;
    }
    const TileMask drawn = tiles_of(key);
    slots_[static_cast<std::size_t>(chosen)] = {true, key, frame_, frame_, drawn};
    resident_[key] = chosen;
    out.to_draw.push_back({chosen, key, drawn});
  }
  stats.drawn = static_cast<int>(out.to_draw.size());
  stats.resident = static_cast<int>(resident_.size());
  return out;
}

std::vector<std::int32_t> PageCache::table() const {
  const int pps = layout_.pages_per_side;
  std::vector<std::int32_t> table(static_cast<std::size_t>(pps) * pps * layout_.levels, -1);
  for (const auto& [key, slot] : resident_) {
    const auto k = static_cast<std::size_t>(key.level);
    const std::int64_t x = key.x - origin_pages_x_[k], y = key.y - origin_pages_y_[k];  // 64-bit: a cached page may lie far away
    if (x < 0 || y < 0 || x >= pps || y >= pps) continue;  // cached, outside this frame's window
    table[(k * static_cast<std::size_t>(pps) + static_cast<std::size_t>(y)) * static_cast<std::size_t>(pps) + static_cast<std::size_t>(x)] = slot;
  }
  return table;
}

int PageCache::slot_of(const Page& page) const {
  if (page.level < 0 || page.level >= layout_.levels) return -1;
  const auto it = resident_.find(key_of(page));
  return it == resident_.end() ? -1 : it->second;
}

std::vector<PageCache::SlotState> PageCache::slot_states() const {
  std::vector<SlotState> states;
  for (const Slot& s : slots_) states.push_back(!s.used ? SlotState::free : s.drawn_frame == frame_ ? SlotState::drawn : SlotState::cached);
  return states;
}

std::vector<PageCache::SlotContent> PageCache::slots() const {
  std::vector<SlotContent> out;
  for (const Slot& s : slots_) out.push_back({s.used, s.key});
  return out;
}

}  // namespace penumbra::adaptive
