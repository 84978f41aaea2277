// A virtual shadow map's depths through its page tables (shadows/virtual_shadow_map.h): level k
// is a window of u_vsm_pages_per_side² pages of u_vsm_page_texels² texels, texel size
// u_vsm_texel0_ws·2^k, its lower corner at u_vsm_origin[k] in light space; the table of level k
// holds, per page of the window, its slot in the pool (-1: not resident). Depths are the light-
// space distance mapped linearly from [u_vsm_near_ws, u_vsm_far_ws] to [0, 1], as every page was
// drawn, so that depths of different levels compare.
#include "shadow_contract.h"

uniform mat4 u_vsm_light_view;
uniform vec2 u_vsm_origin[VSM_MAX_LEVELS];
uniform float u_vsm_texel0_ws;
uniform int u_vsm_page_texels;
uniform int u_vsm_pages_per_side;
uniform int u_vsm_levels;
uniform int u_vsm_pool_pages;  // slots per side of the pool
uniform float u_vsm_near_ws;
uniform float u_vsm_far_ws;
layout(binding = UNIT_VSM_POOL) uniform sampler2D u_vsm_pool;
layout(binding = UNIT_VSM_TABLE) uniform isampler2D u_vsm_table;

// A world point in light space: xy across the light, z the depth as the pages hold it.
vec3 vsm_light_point(vec3 world) {
  vec3 l = (u_vsm_light_view * vec4(world, 1.0)).xyz;
  return vec3(l.xy, (-l.z - u_vsm_near_ws) / (u_vsm_far_ws - u_vsm_near_ws));
}

float vsm_texel_ws(int level) { return u_vsm_texel0_ws * exp2(float(level)); }

// The texel of `level`'s window that holds light-space `xy` (it may lie outside the window).
ivec2 vsm_texel(int level, vec2 xy) { return ivec2(floor((xy - u_vsm_origin[level]) / vsm_texel_ws(level))); }

// The depth of texel `texel` of `level` through the page table: false when the texel lies outside
// the level's window or its page is not resident.
bool vsm_fetch(int level, ivec2 texel, out float depth) {
  depth = 1.0;
  const int n = u_vsm_page_texels;
  if (level < 0 || level >= u_vsm_levels || texel.x < 0 || texel.y < 0) return false;
  const ivec2 page = texel / n;
  if (page.x >= u_vsm_pages_per_side || page.y >= u_vsm_pages_per_side) return false;
  const int slot = texelFetch(u_vsm_table, ivec2(page.x, page.y + level * u_vsm_pages_per_side), 0).r;
  if (slot < 0) return false;
  const ivec2 origin = ivec2(slot % u_vsm_pool_pages, slot / u_vsm_pool_pages) * n;
  depth = texelFetch(u_vsm_pool, origin + texel - page * n, 0).r;
  return true;
}

// The finest level at or above `level` whose page holding `xy` is resident (the fallback when the
// pool could not hold a page), or -1 when none is.
int vsm_resident_level(int level, vec2 xy) {
  float depth;
  for (int k = max(level, 0); k < u_vsm_levels; ++k)
    if (vsm_fetch(k, vsm_texel(k, xy), depth)) return k;
  return -1;
}

// Box-filtered PCF at `level` through the tables: the mean of the nearest-texel depth test
// (`depth` <= the texel's depth: lit) over the square xy ± radius_ws, each texel weighted by the
// part of it the square covers, as pcf_grid on a single map of the level, so a square across
// page borders reads each texel from its own page: no seams. `found` is false (and the result 1)
// when a texel under the square is not resident or lies outside the level's window.
float vsm_pcf_box(int level, vec2 xy, float depth, float radius_ws, out bool found) {
  found = true;
  const float t = vsm_texel_ws(level);
  const vec2 p = (xy - u_vsm_origin[level]) / t;  // texel coordinates in the level's window
  const float r = max(radius_ws / t, 1e-4);
  const vec2 lo = p - r, hi = p + r;
  const ivec2 first = ivec2(floor(lo)), last = ivec2(ceil(hi)) - 1;
  float sum = 0.0;
  for (int j = first.y; j <= last.y; ++j) {
    const float wy = max(0.0, min(float(j + 1), hi.y) - max(float(j), lo.y));
    for (int i = first.x; i <= last.x; ++i) {
      const float wx = max(0.0, min(float(i + 1), hi.x) - max(float(i), lo.x));
      float d;
      if (!vsm_fetch(level, ivec2(i, j), d)) {
        found = false;
        return 1.0;
      }
      sum += wx * wy * (depth <= d ? 1.0 : 0.0);
    }
  }
  return sum / (4.0 * r * r);
}

// PCSS's blocker search at `level` through the tables: the mean depth of the texels under the
// square xy ± radius_ws nearer than `depth` (blockers), and their count. As vsm_pcf_box, every
// texel is read from its own page; `found` is false (count 0) when one is not resident or lies
// outside the level's window.
float vsm_blocker_search(int level, vec2 xy, float depth, float radius_ws, out int blockers, out bool found) {
  found = true;
  blockers = 0;
  const float t = vsm_texel_ws(level);
  const vec2 p = (xy - u_vsm_origin[level]) / t;
  const float r = max(radius_ws / t, 1e-4);
  const ivec2 first = ivec2(floor(p - r)), last = ivec2(ceil(p + r)) - 1;
  float sum = 0.0;
  for (int j = first.y; j <= last.y; ++j)
    for (int i = first.x; i <= last.x; ++i) {
      float d;
      if (!vsm_fetch(level, ivec2(i, j), d)) {
        found = false;
        blockers = 0;
        return 1.0;
      }
      if (d < depth) sum += d, ++blockers;
    }
  return blockers > 0 ? sum / float(blockers) : 1.0;
}
