// A virtual shadow map's depths through its page tables (shadows/virtual_shadow_map.h): level k
// is a window of u_virtual_pages_per_side² pages of u_virtual_page_texels² texels, texel size
// u_virtual_texel0_ws·2^k, its lower corner at virtual_origin(k) in light space; the table of level k
// holds, per page of the window, its slot in the pool (-1: not resident). Depths are the light-
// space distance mapped linearly from [u_virtual_near_ws, u_virtual_far_ws] to [0, 1], as every page was
// drawn, so that depths of different levels compare. The frame's layout, light view, marking and
// PCSS constants are the VirtualFrame block (virtual_mark_contract.h), one uniform buffer a frame;
// only the samplers are plain uniforms here (GLSL keeps opaque types out of blocks).
#include "shadow_contract.h"
#include "virtual_mark_contract.h"
#include "read_count.glsl"

layout(binding = UNIT_VIRTUAL_POOL) uniform sampler2D u_virtual_pool;
layout(binding = UNIT_VIRTUAL_TABLE) uniform isampler2D u_virtual_table;
layout(binding = UNIT_VIRTUAL_POOL_CMP) uniform sampler2DShadow u_virtual_pool_cmp;  // the pool, LEQUAL comparison (lit)
layout(binding = UNIT_VIRTUAL_MOMENTS) uniform sampler2D u_virtual_moments;  // variance shadow maps: (t, t² + texel variance)
// Per tile of VIRTUAL_BOUNDS_TILE² pool texels: (lower, upper, a, b), planes around its depths
// (virtual_bounds.comp); read only when u_virtual_bounds.
layout(binding = UNIT_VIRTUAL_BOUNDS) uniform sampler2D u_virtual_tile_bounds;

// Level `level`'s window's lower corner in light space.
vec2 virtual_origin(int level) { return u_virtual_origin[level].xy; }

// The finest texel `world` needs, with a filter of world radius `radius_ws` (0: none), by the
// block's u_mark_* (set_virtual_marking): the page marking (virtual_mark.comp) and the shading pass
// ask it the same way, so a pixel samples the level its pages were marked on.
//   rule       max(r / c, s · min_texel_px)   (s the pixel's world footprint)
//   footprint  s · min_texel_px
float virtual_requested_texel_ws(vec3 world, float radius_ws) {
  const float depth = u_mark_perspective ? dot(world - u_mark_camera_position, u_mark_camera_forward) : 1.0;
  const float floor_ws = max(depth, 0.0) * u_mark_footprint_per_depth * u_mark_min_texel_px;
  return u_mark_footprint_only || radius_ws <= 0.0 ? floor_ws : max(radius_ws / u_mark_c_texels, floor_ws);
}

// The coarsest level whose texel is at most `texel_ws` (0 when even level 0 is coarser).
int virtual_level_for_texel(float texel_ws) {
  return texel_ws > 0.0 ? int(clamp(floor(log2(texel_ws / u_virtual_texel0_ws) + 1e-6), 0.0, float(u_virtual_levels - 1))) : 0;
}

// A world point in light space: xy across the light, z the depth as the pages hold it.
vec3 virtual_light_point(vec3 world) {
  vec3 l = (u_virtual_light_view * vec4(world, 1.0)).xyz;
  return vec3(l.xy, (-l.z - u_virtual_near_ws) / (u_virtual_far_ws - u_virtual_near_ws));
}

float virtual_texel_ws(int level) { return u_virtual_texel0_ws * exp2(float(level)); }

// The texel of `level`'s window that holds light-space `xy` (it may lie outside the window).
ivec2 virtual_texel(int level, vec2 xy) { return ivec2(floor((xy - virtual_origin(level)) / virtual_texel_ws(level))); }

// Whether level `level`'s window holds light-space `xy`.
bool virtual_in_window(int level, vec2 xy) {
  const vec2 local = (xy - virtual_origin(level)) / (float(u_virtual_page_texels) * virtual_texel_ws(level));
  return all(greaterThanEqual(local, vec2(0.0))) && all(lessThan(local, vec2(u_virtual_pages_per_side)));
}

// The slot holding page `page` of `level` (-1: not resident), and the pool texel of window texel
// (0, 0) of that page: window texel t of the page lies at virtual_slot_shift(...) + t.
int virtual_slot(int level, ivec2 page) { return COUNTED(1, 4, texelFetch(u_virtual_table, ivec2(page.x, page.y + level * u_virtual_pages_per_side), 0)).r; }
ivec2 virtual_slot_shift(int slot, ivec2 page) {
  return (ivec2(slot % u_virtual_pool_pages, slot / u_virtual_pool_pages) - page) * u_virtual_page_texels;
}

// The depth of texel `texel` of `level` through the page table: false when the texel lies outside
// the level's window or its page is not resident.
bool virtual_fetch(int level, ivec2 texel, out float depth) {
  depth = 1.0;
  const int n = u_virtual_page_texels;
  if (level < 0 || level >= u_virtual_levels || texel.x < 0 || texel.y < 0) return false;
  const ivec2 page = texel / n;
  if (page.x >= u_virtual_pages_per_side || page.y >= u_virtual_pages_per_side) return false;
  const int slot = virtual_slot(level, page);
  if (slot < 0) return false;
  depth = COUNTED(1, 4, texelFetch(u_virtual_pool, virtual_slot_shift(slot, page) + texel, 0)).r;
  return true;
}

// The finest level at or above `level` whose page holding `xy` is resident (the fallback when the
// pool could not hold a page), or -1 when none is.
int virtual_resident_level(int level, vec2 xy) {
  float depth;
  for (int k = max(level, 0); k < u_virtual_levels; ++k)
    if (virtual_fetch(k, virtual_texel(k, xy), depth)) return k;
  return -1;
}

// The pages under a square of texels of `level` from `first` (even) to `last`, in 2 × 2 blocks:
// a page's side is even, so no block straddles a page border. With at most two pages per axis
// (a square under a page wide) the table is read once per page, not per block.
struct VirtualSquare {
  int level;
  ivec2 page0, split;  // the first page; the first texel of the second page, per axis
  bool few;
  ivec2 shift[4];      // pool texel = window texel + shift, per page page0 + (k & 1, k >> 1)
};

// false when a page under the square is not resident or the square leaves the level's window.
bool virtual_square(int level, ivec2 first, ivec2 last, out VirtualSquare sq) {
  const int n = u_virtual_page_texels;
  sq.level = level;
  sq.page0 = first / n;
  sq.split = (sq.page0 + 1) * n;
  sq.few = false;
  if (any(lessThan(first, ivec2(0))) || any(greaterThanEqual(last / n, ivec2(u_virtual_pages_per_side)))) return false;
  const ivec2 pages = last / n - sq.page0 + 1;
  sq.few = all(lessThanEqual(pages, ivec2(2)));
  for (int k = 0; k < 4; ++k) {
    sq.shift[k] = ivec2(0);
    const ivec2 page = sq.page0 + ivec2(k & 1, k >> 1);
    if (!sq.few || any(greaterThanEqual(page - sq.page0, pages))) continue;
    const int slot = virtual_slot(level, page);
    if (slot < 0) return false;
    sq.shift[k] = virtual_slot_shift(slot, page);
  }
  return true;
}

// Where the blocks of a region of window texels lie in the pool: pool texel = window texel +
// shift[(x >= split.x) + 2 (y >= split.y)], the region spanning at most 2 × 2 pages split at
// window texel `split` (virtual_square's). The walks below choose a block's shift with two selects
// instead of walking page by page: on llvmpipe, where each pixel's square splits elsewhere, four
// page walks cost about 8 % more of the shading than one walk of the square.
struct VirtualShifts {
  ivec2 split;
  ivec2 shift[4];
};
// One block's (or one page's) shift: a split no texel reaches.
VirtualShifts virtual_one_shift(ivec2 shift) { return VirtualShifts(ivec2(0x3fffffff), ivec2[4](shift, shift, shift, shift)); }

// The shifts of the blocks in row `j` left of the split and right of it.
void virtual_row_shifts(const VirtualShifts sh, int j, out ivec2 left_shift, out ivec2 right_shift) {
  const bool upper = j >= sh.split.y;
  left_shift = upper ? sh.shift[2] : sh.shift[0];
  right_shift = upper ? sh.shift[3] : sh.shift[1];
}

// Bounds of (texel depth - receiver) over the texel centres of window texels `first` to `last` of
// square `sq`, the receiver `depth` at window texel coordinates `p` plus `step` per texel: x no
// more than the least difference, y no less than the greatest, from the tiles' planes
// (virtual_bounds.comp). Without bounds (u_virtual_bounds false, or a square over more than 2 × 2 pages or
// tiles): (-inf, +inf), which decides nothing.
vec2 virtual_tile_gap(const VirtualSquare sq, ivec2 first, ivec2 last, vec2 p, float depth, vec2 step) {
  const ivec2 t0 = first / VIRTUAL_BOUNDS_TILE, t1 = last / VIRTUAL_BOUNDS_TILE;
  const bool bounded = u_virtual_bounds && sq.few && all(lessThanEqual(t1 - t0, ivec2(1)));
  vec2 gap = bounded ? vec2(1e30, -1e30) : vec2(-1e30, 1e30);
  // A loop, not a branch, so that llvmpipe skips it where no pixel is bounded (it runs both sides
  // of a branch under a mask).
  for (int k = 0; k < (bounded ? 4 : 0); ++k) {
    const ivec2 tile = t0 + ivec2(k & 1, k >> 1);
    if (any(greaterThan(tile, t1))) continue;
    const ivec2 corner = tile * VIRTUAL_BOUNDS_TILE;  // window texel; a tile lies in one page
    const ivec2 shift = sq.shift[int(corner.x >= sq.split.x) + 2 * int(corner.y >= sq.split.y)];
    const vec4 b = COUNTED(1, 16, texelFetch(u_virtual_tile_bounds, (corner + shift) / VIRTUAL_BOUNDS_TILE, 0));
    // plane - receiver = offset + g · (x - centre) over the centres x of the tile's part of the square
    const vec2 centre = vec2(corner) + 0.5 * float(VIRTUAL_BOUNDS_TILE);
    const vec2 lo = vec2(max(first, corner)) + 0.5, hi = vec2(min(last, corner + VIRTUAL_BOUNDS_TILE - 1)) + 0.5;
    const vec2 g = b.zw - step;
    const float offset = dot(g, 0.5 * (lo + hi) - centre) - (depth + dot(centre - p, step));
    const float spread = dot(abs(g), 0.5 * (hi - lo));
    gap = vec2(min(gap.x, b.x + offset - spread), max(gap.y, b.y + offset + spread));
  }
  return gap;
}
// Slack for the float arithmetic of the bounds against that of the texel tests (depths in [0, 1]).
const float VIRTUAL_GAP_EPSILON = 1e-6;

// The pool texel of the block whose lower corner is window texel (i, j); false when its page is
// not resident (only asked of squares wider than two pages).
bool virtual_block(const VirtualSquare sq, int i, int j, out ivec2 corner) {
  const int n = u_virtual_page_texels;
  const ivec2 page = ivec2(i, j) / n;
  const int slot = virtual_slot(sq.level, page);
  corner = virtual_slot_shift(slot, page) + ivec2(i, j);
  return slot >= 0;
}

// The weighted depth tests of the 2 × 2 blocks from window texel `from` (even) to `to`, whose pool
// texels `sh` gives (virtual_pcf_box's inner loop): each texel weighs the part of it the square
// [lo, hi] covers, and each block is tested against the receiver's depth at its shared corner,
// `depth` at window texel coordinates `p` plus `step` per texel.
float virtual_pcf_blocks(ivec2 from, ivec2 to, const VirtualShifts sh, vec2 lo, vec2 hi, vec2 p, float depth, vec2 step) {
  const vec2 inv_pool = 1.0 / vec2(u_virtual_pool_pages * u_virtual_page_texels);
  float sum = 0.0;
  for (int j = from.y; j <= to.y; j += 2) {
    const vec2 wy = max(vec2(0.0), min(vec2(j + 1, j + 2), vec2(hi.y)) - max(vec2(j, j + 1), vec2(lo.y)));
    const float row_reference = depth + (float(j + 1) - p.y) * step.y;
    ivec2 left_shift, right_shift;
    virtual_row_shifts(sh, j, left_shift, right_shift);
    float upper = 0.0, lower = 0.0;  // rows j + 1 and j
    for (int i = from.x; i <= to.x; i += 2) {
      const ivec2 shift = i >= sh.split.x ? right_shift : left_shift;
      const vec2 wx = max(vec2(0.0), min(vec2(i + 1, i + 2), vec2(hi.x)) - max(vec2(i, i + 1), vec2(lo.x)));
      // Four comparisons in one gather, order: x (i, j + 1), y (i + 1, j + 1), z (i + 1, j), w (i, j).
      const vec4 lit = COUNTED(4, 4, textureGather(u_virtual_pool_cmp, vec2(ivec2(i, j) + shift + 1) * inv_pool, row_reference + (float(i + 1) - p.x) * step.x));
      upper += dot(lit.xy, wx);
      lower += dot(lit.wz, wx);
    }
    sum += upper * wy.y + lower * wy.x;
  }
  return sum;
}

// Runs the statement BLOCKS over square `sq` (virtual_square's, its blocks from window texel `first`
// to `last`), with `from`, `to` (the first and last window texel of the region its blocks cover)
// and `shifts` (where the region lies in the pool) in scope: once over the whole square when it
// spans at most 2 × 2 pages (a page's side is even, so the split falls between blocks), else block
// by block, where `found` turns false, and the walk ends, at a block whose page is not resident.
// (GLSL has no function parameters, hence the macro.)
#define VIRTUAL_FOR_EACH_REGION(sq, first, last, found, BLOCKS)                                                \
  if (sq.few) {                                                                                            \
    const ivec2 from = first, to = last;                                                                   \
    const VirtualShifts shifts = VirtualShifts(sq.split, sq.shift);                                                \
    BLOCKS;                                                                                                \
  } else {                                                                                                 \
    for (int block_j = first.y; found && block_j <= last.y; block_j += 2)                                  \
      for (int block_i = first.x; found && block_i <= last.x; block_i += 2) {                              \
        ivec2 corner;                                                                                      \
        found = virtual_block(sq, block_i, block_j, corner);                                                   \
        const ivec2 from = ivec2(block_i, block_j), to = from;                                             \
        const VirtualShifts shifts = virtual_one_shift(corner - from);                                             \
        if (found) { BLOCKS; }                                                                             \
      }                                                                                                    \
  }

// Box-filtered PCF at `level` through the tables: the mean of the nearest-texel depth test
// (`depth` <= the texel's depth: lit) over the square xy ± radius_ws, each texel weighted by the
// part of it the square covers, as pcf_grid on a single map of the level, so a square across
// page borders reads each texel from its own page: no seams. `gradient`: the receiver's depth
// change per world unit across the light (receiver-plane bias: each 2 × 2 block is tested against
// the receiver's depth at its shared corner, as pcf_grid on a map; zero: one depth for the square).
// `found` is false (and the result 1) when a texel under the square is not resident or lies
// outside the level's window.
float virtual_pcf_box(int level, vec2 xy, float depth, vec2 gradient, float radius_ws, out bool found) {
  const float t = virtual_texel_ws(level);
  const vec2 p = (xy - virtual_origin(level)) / t;  // texel coordinates in the level's window
  const float r = max(radius_ws / t, 1e-4);
  const vec2 lo = p - r, hi = p + r;
  const ivec2 first = ivec2(floor(lo)) & ~1, last = ivec2(ceil(hi)) - 1;  // blocks from an even texel
  VirtualSquare sq;
  found = virtual_square(level, first, last, sq);
  if (!found) return 1.0;
  const vec2 step = t * gradient;  // the receiver's depth change per texel
  // Surely lit or surely in umbra: each block is tested at its centre, half a texel per axis from
  // its texels' centres, so the receiver there differs from the plane at a texel's centre by at
  // most `corner`. The walk then runs over no block (a loop llvmpipe skips, not a branch).
  const vec2 gap = virtual_tile_gap(sq, first, last, p, depth, step);
  const float corner = 0.5 * (abs(step.x) + abs(step.y)) + VIRTUAL_GAP_EPSILON;
  const float decided = gap.x >= corner ? 1.0 : gap.y < -corner ? 0.0 : -1.0;
  const ivec2 walk_last = decided >= 0.0 ? first - 2 : last;
  float sum = 0.0;
  VIRTUAL_FOR_EACH_REGION(sq, first, walk_last, found, sum += virtual_pcf_blocks(from, to, shifts, lo, hi, p, depth, step))
  // The weights sum to the square's area as lo and hi hold it: far from a window's origin they
  // round (a texel coordinate near 8192 to 1e-3 texels), and 4 r² would miss a lit square's 1 by
  // as much as 1e-3 for a square of two texels.
  return decided >= 0.0 ? decided : found ? sum / ((hi.x - lo.x) * (hi.y - lo.y)) : 1.0;
}
float virtual_pcf_box(int level, vec2 xy, float depth, float radius_ws, out bool found) {
  return virtual_pcf_box(level, xy, depth, vec2(0.0), radius_ws, found);
}

// The moments of the blocks from window texel `from` (even) to `to` (pool texels: `sh`), each
// texel weighted by the part of it the square [lo, hi] covers.
vec2 virtual_moments_blocks(ivec2 from, ivec2 to, const VirtualShifts sh, vec2 lo, vec2 hi) {
  const vec2 inv_pool = 1.0 / vec2(u_virtual_pool_pages * u_virtual_page_texels);
  vec2 sum = vec2(0.0);
  for (int j = from.y; j <= to.y; j += 2) {
    const vec2 wy = max(vec2(0.0), min(vec2(j + 1, j + 2), vec2(hi.y)) - max(vec2(j, j + 1), vec2(lo.y)));
    ivec2 left_shift, right_shift;
    virtual_row_shifts(sh, j, left_shift, right_shift);
    vec2 upper = vec2(0.0), lower = vec2(0.0);  // rows j + 1 and j: (first, second moment)
    for (int i = from.x; i <= to.x; i += 2) {
      const ivec2 shift = i >= sh.split.x ? right_shift : left_shift;
      const vec2 wx = max(vec2(0.0), min(vec2(i + 1, i + 2), vec2(hi.x)) - max(vec2(i, i + 1), vec2(lo.x)));
      // Order: x (i, j + 1), y (i + 1, j + 1), z (i + 1, j), w (i, j).
      const vec2 uv = vec2(ivec2(i, j) + shift + 1) * inv_pool;
      const vec4 m1 = COUNTED(4, 4, textureGather(u_virtual_moments, uv, 0)), m2 = COUNTED(4, 4, textureGather(u_virtual_moments, uv, 1));
      upper += vec2(dot(m1.xy, wx), dot(m2.xy, wx));
      lower += vec2(dot(m1.wz, wx), dot(m2.wz, wx));
    }
    sum += upper * wy.y + lower * wy.x;
  }
  return sum;
}

// Variance shadow maps through the tables: the mean moments (t, t² + texel variance) over the
// square xy ± radius_ws of `level`, each texel weighted by the part of it the square covers (a box
// filter at lookup: the pages hold unfiltered moments, so a square across page borders reads each
// texel from its own page, as virtual_pcf_box). `found` false (and the far plane's moments) when a
// texel under the square is not resident or lies outside the level's window.
vec2 virtual_moments_box(int level, vec2 xy, float radius_ws, out bool found) {
  const float t = virtual_texel_ws(level);
  const vec2 p = (xy - virtual_origin(level)) / t;
  const float r = max(radius_ws / t, 1e-4);
  const vec2 lo = p - r, hi = p + r;
  const ivec2 first = ivec2(floor(lo)) & ~1, last = ivec2(ceil(hi)) - 1;
  VirtualSquare sq;
  found = virtual_square(level, first, last, sq);
  if (!found) return vec2(1.0);
  vec2 sum = vec2(0.0);
  VIRTUAL_FOR_EACH_REGION(sq, first, last, found, sum += virtual_moments_blocks(from, to, shifts, lo, hi))
  return found ? sum / ((hi.x - lo.x) * (hi.y - lo.y)) : vec2(1.0);  // the weights' sum (virtual_pcf_box)
}

// The blocker search's blocks from window texel `from` (even) to `to` (pool texels: `sh`): adds
// the depths nearer than the receiver of the square's texels (`inside` to `last`; a block may
// reach one texel past either) to `sum`, and their count to `blockers`. The receiver at a texel is its plane there: `depth` at window texel coordinates `p`
// plus `step` per texel, taken at the texel's centre.
void virtual_blocker_blocks(ivec2 from, ivec2 to, const VirtualShifts sh, ivec2 inside, ivec2 last, vec2 p, float depth, vec2 step, inout float sum,
                        inout int blockers) {
  const vec2 inv_pool = 1.0 / vec2(u_virtual_pool_pages * u_virtual_page_texels);
  for (int j = from.y; j <= to.y; j += 2) {
    // Order: x (i, j + 1), y (i + 1, j + 1), z (i + 1, j), w (i, j); a texel outside the square
    // is compared against -1 (never a blocker).
    const float upper = depth + (float(j) + 1.5 - p.y) * step.y, lower = depth + (float(j) + 0.5 - p.y) * step.y;  // rows j + 1, j
    const vec4 row_depth = vec4(j + 1 <= last.y ? upper : -1.0, j + 1 <= last.y ? upper : -1.0, j >= inside.y ? lower : -1.0,
                                j >= inside.y ? lower : -1.0);
    ivec2 left_shift, right_shift;
    virtual_row_shifts(sh, j, left_shift, right_shift);
    for (int i = from.x; i <= to.x; i += 2) {
      const ivec2 shift = i >= sh.split.x ? right_shift : left_shift;
      const vec4 d = COUNTED(4, 4, textureGather(u_virtual_pool, vec2(ivec2(i, j) + shift + 1) * inv_pool, 0));
      const float left = (float(i) + 0.5 - p.x) * step.x, right = (float(i) + 1.5 - p.x) * step.x;  // columns i, i + 1
      const vec4 tested = vec4(i >= inside.x ? row_depth.x + left : -1.0, i + 1 <= last.x ? row_depth.y + right : -1.0,
                               i + 1 <= last.x ? row_depth.z + right : -1.0, i >= inside.x ? row_depth.w + left : -1.0);
      const vec4 is_blocker = vec4(lessThan(d, tested));
      sum += dot(d, is_blocker);
      blockers += int(dot(is_blocker, vec4(1.0)));
    }
  }
}

// PCSS's blocker search at `level` through the tables: the mean depth of the texels under the
// square xy ± radius_ws nearer than the receiver (blockers), and their count. The receiver is
// `depth` at xy, on its plane of `gradient` (normalized depth per world unit across the light; zero:
// one depth for the square). As virtual_pcf_box, every texel is read from its own page (four a
// gather); `found` is false (count 0) when one is not resident or lies outside the level's window.
float virtual_blocker_search(int level, vec2 xy, float depth, vec2 gradient, float radius_ws, out int blockers, out bool found) {
  blockers = 0;
  const float t = virtual_texel_ws(level);
  const vec2 p = (xy - virtual_origin(level)) / t;
  const float r = max(radius_ws / t, 1e-4);
  const ivec2 inside = ivec2(floor(p - r)), last = ivec2(ceil(p + r)) - 1;
  const ivec2 first = inside & ~1;  // blocks from an even texel; texels before `inside` are not the square's
  VirtualSquare sq;
  found = all(greaterThanEqual(inside, ivec2(0))) && virtual_square(level, first, last, sq);
  if (!found) return 1.0;
  const vec2 step = t * gradient;
  // No texel nearer than the receiver (the search compares at texel centres): no blocker, and the
  // walk runs over no block.
  const bool clear = virtual_tile_gap(sq, inside, last, p, depth, step).x >= VIRTUAL_GAP_EPSILON;
  const ivec2 walk_last = clear ? first - 2 : last;
  float sum = 0.0;
  VIRTUAL_FOR_EACH_REGION(sq, first, walk_last, found, virtual_blocker_blocks(from, to, shifts, inside, last, p, depth, step, sum, blockers))
  if (!found) blockers = 0;
  return blockers > 0 ? sum / float(blockers) : 1.0;
}

// The receiver plane in the map's light space, d(normalized depth) / d(light xy), from the light-
// space steps `dx`, `dy` (xy world, z normalized depth) of two neighbouring image samples of the
// surface: the shading's screen derivatives, or the marker's neighbouring pixels. Clamped to
// slopes within 85° of the light; zero when the two steps do not span the plane.
vec2 virtual_plane_gradient(vec3 dx, vec3 dy) {
  const float det = dx.x * dy.y - dx.y * dy.x;
  if (abs(det) < 1e-20) return vec2(0.0);
  const vec2 g = vec2(dy.y * dx.z - dx.y * dy.z, dx.x * dy.z - dy.x * dx.z) / det;
  const float limit = tan(radians(85.0)) / (u_virtual_far_ws - u_virtual_near_ws);
  const float len = length(g);
  return len > limit ? g * (limit / len) : g;
}

// PCSS through the pages, for a sun of angular radius atan(u_virtual_tan_half_angle)
// (the block's PCSS constants, set_virtual_pcss). The marking (virtual_mark.comp) runs the blocker search once a frame
// and writes the penumbra it finds, which the shading filters with. The search reads the surface
// point itself (no normal offset), each texel against the receiver's plane there (the marker's
// gradient) less a constant bias of u_virtual_search_bias_texels of its level.
// The blocker search's square spans this many texels of its level per radius: a mean blocker depth
// needs no finer texels than that (its level is far coarser than a contact shadow's filter).
const float VIRTUAL_SEARCH_TEXELS = 4.0;

// Light-space distance (world units) of a depth as the pages hold it.
float virtual_depth_ws(float d) { return mix(u_virtual_near_ws, u_virtual_far_ws, d); }

// The blocker search's world radius for a receiver at light distance z_r.
float virtual_search_ws(float z_r) { return u_virtual_tan_half_angle * max(z_r - u_virtual_near_ws, 0.0) * u_virtual_search_scale; }

// The level the search of `world` runs on: texels of search / VIRTUAL_SEARCH_TEXELS, never finer
// than the pixel floor, the first at or above it whose window holds the point.
int virtual_search_level(vec3 world, float search_ws, vec2 xy) {
  int k = virtual_level_for_texel(max(search_ws / VIRTUAL_SEARCH_TEXELS, virtual_requested_texel_ws(world, 0.0)));
  while (k < u_virtual_levels - 1 && !virtual_in_window(k, xy)) ++k;
  return k;
}

// PCSS's penumbra at `world` through the pages: the blocker search on the search level (or the
// next coarser resident one) against the receiver plane of `gradient` (virtual_plane_gradient's), then
// the filter's world radius tan(half angle) · (z_r - z_b), at least u_virtual_min_penumbra_ws. Returns
// false when no level holds the search (`radius_ws` 0); `blockers` 0: nothing in front, lit.
bool virtual_pcss_radius(vec3 world, vec2 gradient, out float radius_ws, out int blockers) {
  radius_ws = 0.0;
  blockers = 0;
  const vec3 l = virtual_light_point(world);
  const float z_r = virtual_depth_ws(l.z);
  const float search = virtual_search_ws(z_r);
  for (int k = virtual_search_level(world, search, l.xy); k < u_virtual_levels; ++k) {
    const float bias = u_virtual_search_bias_texels * virtual_texel_ws(k) / (u_virtual_far_ws - u_virtual_near_ws);
    bool found;
    const float mean = virtual_blocker_search(k, l.xy, l.z - bias, gradient, search, blockers, found);
    if (!found) continue;
    radius_ws = blockers > 0 ? max(u_virtual_tan_half_angle * (z_r - virtual_depth_ws(mean)), u_virtual_min_penumbra_ws) : 0.0;
    return true;
  }
  return false;
}

