// Page marking of a virtual shadow map (shadows/virtual_shadow_map.h, PageMarker): each pixel's
// surface asks for the coarsest level whose texel still satisfies its rule and for the pages of
// that level its filter reaches, as adaptive::mark_pages does on the CPU:
//   rule       texel <= max(r / c, s · min_texel_px)   (r the filter's world radius, s the pixel's
//                                                       world footprint, c in texels)
//   footprint  texel <= s · min_texel_px
// A pixel outside its level's window takes the next coarser level that holds it; beyond the
// coarsest it is counted as unmarked. Installed for engines, its includes inlined, as
// share/penumbra/shaders/virtual_mark.comp: its bindings, buffer and uniforms are the contract of
// virtual_mark_contract.h (docs/virtual-pages-in-your-engine.md).
#include "virtual_mark_contract.h"
#include "virtual_pages.glsl"

layout(local_size_x = VIRTUAL_MARK_GROUP_SIZE, local_size_y = VIRTUAL_MARK_GROUP_SIZE) in;
layout(binding = VIRTUAL_MARK_IMAGE_SURFACE, rgba32f) uniform readonly image2D u_surface;  // world xyz; w > 0 where a surface is
layout(binding = VIRTUAL_MARK_IMAGE_LEVELS, r32f) uniform writeonly image2D u_levels;      // debug view: the level each pixel samples
uniform bool u_write_levels;                                                               // (-1: no surface, levels: beyond the coarsest)
// PCSS (VIRTUAL_MARK_PASS 2): each pixel's penumbra, the world radius its search found (0: nothing in
// front, lit; -1: no surface, or no level held its search), which the shading filters with.
layout(binding = VIRTUAL_MARK_IMAGE_RADII, r32f) uniform writeonly image2D u_radii;
uniform bool u_write_radii;

layout(std430, binding = VIRTUAL_MARK_BUFFER) buffer Marks {
  uint u_pixels_per_level[VIRTUAL_MARK_MAX_LEVELS];
  uint u_unmarked;
  uint u_page_bits[];  // bit virtual_mark_page_bit(level, x, y, pages_per_side), then the tile words
};

// The frame's layout, camera and constants are the VirtualFrame block (virtual_mark_contract.h); these
// differ between the dispatches of a frame.
uniform float u_radius_ws;  // the filter's world radius (0: none)
// VIRTUAL_MARK_PASS (a define: one program per pass, PageMarker) 0: the pages of a filter of
// u_radius_ws; PCSS: 1 the pages of each pixel's blocker search, 2 (the search's pages resident) the
// pages of the penumbra that search finds. Not a uniform: llvmpipe runs both sides of a branch on a
// uniform under an execution mask, and pass 2's search cost pass 0 two thirds of its time.
#if !defined(VIRTUAL_MARK_PASS) || VIRTUAL_MARK_PASS < 0 || VIRTUAL_MARK_PASS > 2
#error "virtual_mark.comp needs VIRTUAL_MARK_PASS 0, 1 or 2"
#endif

// Marks the pages of `level` (or the first coarser level whose window holds xy) under the square
// xy ± (r + reach_texels texels of the level), and their tiles under it a texel wider; returns the
// level, or u_virtual_levels when none holds xy.
int mark_square(int level, vec2 xy, float r, float reach_texels) {
  const int n = u_virtual_pages_per_side;
  for (; level < u_virtual_levels; ++level) {
    if (!virtual_in_window(level, xy)) continue;
    const float page_ws = float(u_virtual_page_texels) * virtual_texel_ws(level);
    const vec2 local = (xy - virtual_origin(level)) / page_ws;
    const float reach = (r + reach_texels * virtual_texel_ws(level)) / page_ws;  // the square's half-side, in pages
    const ivec2 lo = max(ivec2(0), ivec2(floor(local - reach)));
    const ivec2 hi = min(ivec2(n - 1), ivec2(floor(local + reach)));
    for (int y = lo.y; y <= hi.y; ++y)
      for (int x = lo.x; x <= hi.x; ++x) {
        const uint bit = virtual_mark_page_bit(level, x, y, n);
        // A bit already set is not set again: a load costs less than an atomic, and most of a
        // page's pixels find its bits set by their neighbours.
        if ((u_page_bits[bit >> 5u] & (1u << (bit & 31u))) == 0u) atomicOr(u_page_bits[bit >> 5u], 1u << (bit & 31u));
        const float tiles = float(VIRTUAL_MARK_TILES_PER_SIDE), texel = 1.0 / float(u_virtual_page_texels);
        const ivec2 a = ivec2(clamp(floor((local - reach - texel - vec2(x, y)) * tiles), 0.0, tiles - 1.0));
        const ivec2 b = ivec2(clamp(floor((local + reach + texel - vec2(x, y)) * tiles), 0.0, tiles - 1.0));
        const uint row = ((2u << uint(b.x - a.x)) - 1u) << uint(a.x);
        for (int ty = a.y; ty <= b.y; ++ty) {
          const uint word = virtual_mark_tile_word(bit, ty, u_virtual_levels, n), bits = row << uint(8 * (ty % 4));
          if ((u_page_bits[word] & bits) != bits) atomicOr(u_page_bits[word], bits);
        }
      }
    return level;
  }
  return u_virtual_levels;
}

// The receiver plane at pixel `p` (light-space point `l`) from its neighbours' surface points, the
// compute shader's dFdx and dFdy: per axis the neighbour whose light depth differs least (the side
// that does not cross an edge); zero where an axis has no neighbouring surface.
vec2 receiver_gradient(ivec2 p, vec3 l) {
  vec3 steps[2];
  for (int axis = 0; axis < 2; ++axis) {
    const ivec2 e = axis == 0 ? ivec2(1, 0) : ivec2(0, 1);
    bool have = false;
    for (int side = -1; side <= 1; side += 2) {
      const ivec2 q = p + side * e;
      if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, imageSize(u_surface)))) continue;
      const vec4 s = imageLoad(u_surface, q);
      if (s.w <= 0.0) continue;
      const vec3 d = (virtual_light_point(s.xyz) - l) * float(side);
      if (!have || abs(d.z) < abs(steps[axis].z)) steps[axis] = d;
      have = true;
    }
    if (!have) return vec2(0.0);
  }
  return virtual_plane_gradient(steps[0], steps[1]);
}

void main() {
  const ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (any(greaterThanEqual(p, imageSize(u_surface)))) return;
  const vec4 s = imageLoad(u_surface, p);
  if (s.w <= 0.0) {
    if (u_write_levels) imageStore(u_levels, p, vec4(-1.0));
    if (u_write_radii) imageStore(u_radii, p, vec4(-1.0));
    return;
  }
  const vec3 world = s.xyz;
  const vec3 light = virtual_light_point(world);
  const vec2 xy = light.xy;
  int level;
#if VIRTUAL_MARK_PASS == 1
  {
    const float search = virtual_search_ws(virtual_depth_ws(light.z));
    level = mark_square(virtual_search_level(world, search, xy), xy, search, 0.0);  // the search reads the point itself
  }
#elif VIRTUAL_MARK_PASS == 2
  {
    float radius;
    int blockers;
    const vec2 gradient = u_virtual_search_receiver_plane ? receiver_gradient(p, light) : vec2(0.0);
    const bool searched = virtual_pcss_radius(world, gradient, radius, blockers);
#if defined(COUNT_SHADOW_READS)
    {  // Renderer::count_shading_reads: the search's reads join the shading's (read_count.glsl), whose
       // pass counts the pixel itself; this pass runs again for the count alone (PageMarker).
      const uint slot = (uint(p.x) + 17u * uint(p.y)) % uint(SHADOW_READ_SLOTS);
      atomicAdd(read_instructions[slot], g_read_instructions);
      atomicAdd(read_texels[slot], g_read_texels);
      atomicAdd(read_bytes[slot], g_read_bytes);
    }
#endif
    if (u_write_radii) imageStore(u_radii, p, vec4(searched ? radius : -1.0));
    if (!searched || blockers == 0) {
      // No search (the pool held none of its levels) or nothing in front: no filter pages.
      if (u_write_levels) imageStore(u_levels, p, vec4(-1.0));
      return;
    }
    level = mark_square(virtual_level_for_texel(virtual_requested_texel_ws(world, radius)), xy, radius, u_mark_reach_texels);
  }
#else
  level = mark_square(virtual_level_for_texel(virtual_requested_texel_ws(world, u_radius_ws)), xy, max(u_radius_ws, 0.0), u_mark_reach_texels);
#endif
  if (level < u_virtual_levels) {
    atomicAdd(u_pixels_per_level[level], 1u);
  } else {
    atomicAdd(u_unmarked, 1u);
  }
  if (u_write_levels) imageStore(u_levels, p, vec4(float(level)));
}
