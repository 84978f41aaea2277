// Depth bounds per tile of VIRTUAL_BOUNDS_TILE² texels of the pages the virtual shadow map drew
// (shadows/virtual_shadow_map.cpp), which the filters read to skip squares that are surely lit or
// surely in umbra (virtual_pages.glsl, virtual_tile_gap). A tile's bounds are two parallel planes
// around its depths: a plane through three of them, moved down to the lowest depth and up to the
// highest. Planes, not a minimum and a maximum: a receiver tilted in light space (the
// ground under a low sun) crosses any constant bound within its tile, but lies on its plane.
// Texel (i, j) of the tile (centre at i + 0.5, j + 0.5) lies between
//   lower + a (i + 0.5 - T/2) + b (j + 0.5 - T/2)  and  upper + a (...) + b (...),  T the tile's side,
// stored as (lower, upper, a, b) at the tile's place in the pool, divided by T.
// The pool's layout (u_virtual_pool_pages, u_virtual_page_texels) is the VirtualFrame block's.
#include "shadow_contract.h"
#include "virtual_mark_contract.h"

// One invocation per tile; one work group layer of z per drawn page.
layout(local_size_x = VIRTUAL_BOUNDS_GROUP, local_size_y = VIRTUAL_BOUNDS_GROUP) in;
layout(binding = UNIT_VIRTUAL_POOL) uniform sampler2D u_virtual_pool;
layout(binding = IMAGE_VIRTUAL_BOUNDS, rgba32f) uniform writeonly image2D u_bounds;
layout(std430, binding = BUFFER_VIRTUAL_BOUNDS_SLOTS) readonly buffer DrawnSlots { int u_slots[]; };

const int T = VIRTUAL_BOUNDS_TILE;
#if VIRTUAL_BOUNDS_TILE % 2 != 0
#error "virtual_bounds.comp reads a tile in 2 x 2 blocks: VIRTUAL_BOUNDS_TILE must be even"
#endif

void main() {
  const int tiles = u_virtual_page_texels / T;  // per side of a page
  const ivec2 tile = ivec2(gl_GlobalInvocationID.xy);
  if (any(greaterThanEqual(tile, ivec2(tiles)))) return;
  const int slot = u_slots[gl_WorkGroupID.z];
  const ivec2 corner = ivec2(slot % u_virtual_pool_pages, slot / u_virtual_pool_pages) * u_virtual_page_texels + tile * T;
  // The plane through three corners: exact where the tile's depths are one plane (a planar surface,
  // rasterized). Where they are not (an edge, a caster over the ground), the step between the
  // surfaces widens the bounds whatever the plane.
  const float origin = texelFetch(u_virtual_pool, corner, 0).r;
  const float a = (texelFetch(u_virtual_pool, corner + ivec2(T - 1, 0), 0).r - origin) / float(T - 1);
  const float b = (texelFetch(u_virtual_pool, corner + ivec2(0, T - 1), 0).r - origin) / float(T - 1);
  const float half_side = 0.5 * float(T);
  // The tile's texels a 2 × 2 block at a time, one gather each (a quarter of the fetches of one
  // texel each). A gather at the shared corner of texels (i, j) to (i + 1, j + 1) returns them in
  // the order (i, j + 1), (i + 1, j + 1), (i + 1, j), (i, j); a corner at an integer texel coordinate
  // lies half a texel from the rounding that picks the block, so the pool's size need not divide it.
  const vec2 pool_size = vec2(textureSize(u_virtual_pool, 0));
  float lower = 1e30, upper = -1e30;
  for (int j = 0; j < T; j += 2)
    for (int i = 0; i < T; i += 2) {
      const vec4 d = textureGather(u_virtual_pool, vec2(corner + ivec2(i + 1, j + 1)) / pool_size, 0);
      const vec2 x = vec2(float(i) + 0.5 - half_side, float(i) + 1.5 - half_side);
      const vec2 y = vec2(float(j) + 0.5 - half_side, float(j) + 1.5 - half_side);
      const vec4 residual = d - vec4(a * x.x + b * y.y, a * x.y + b * y.y, a * x.y + b * y.x, a * x.x + b * y.x);
      lower = min(lower, min(min(residual.x, residual.y), min(residual.z, residual.w)));
      upper = max(upper, max(max(residual.x, residual.y), max(residual.z, residual.w)));
    }
  imageStore(u_bounds, corner / T, vec4(lower, upper, a, b));
}
