// Percentage-closer soft shadows (Fernando 2005; Kreuzer 2017 eq. 5.8-5.11).
// Spot light: emitter of radius u_pcss_light_radius_uv (near-plane uv); directional light: angular
// radius with tangent u_pcss_tan_half_angle.
#ifndef SHADOW_PCSS_GLSL
#define SHADOW_PCSS_GLSL
#include "shadow_pcf.glsl"

uniform float u_pcss_light_radius_uv;
uniform float u_pcss_tan_half_angle;
uniform float u_pcss_min_penumbra_ws;
uniform float u_pcss_search_scale;
uniform int u_blocker_taps;

// Search radius (uv) of the blocker search for a receiver at light-view depth z_r.
float pcss_search_uv(float z_r) {
  if (u_light_perspective) return u_pcss_light_radius_uv * (z_r - u_light_near_ws) / z_r;
  return u_pcss_tan_half_angle * (z_r - u_light_near_ws) / g_light_extent_ws;
}

// Filter radius (uv) for receiver depth z_r and mean blocker depth z_b, before the clamp.
float pcss_filter_uv(float z_r, float z_b) {
  if (u_light_perspective) return u_pcss_light_radius_uv * (z_r - z_b) / z_b * u_light_near_ws / z_r;
  return u_pcss_tan_half_angle * (z_r - z_b) / g_light_extent_ws;
}

// Blocker search: true when a blocker was found, with `z_b` their mean light-view depth (world units).
bool pcss_blocker_depth(vec3 sc, vec2 gradient, float z_r, int blocker_taps, mat2 rotation, out float z_b) {
  float search = pcss_search_uv(z_r) * u_pcss_search_scale;
  float blocker_sum = 0.0;
  int blockers = 0;
  for (int i = 0; i < blocker_taps; ++i) {
    vec2 o = rotation * u_poisson[i] * search;
    float d = COUNTED(1, 4, textureLod(u_shadow_depth, atlas_uv(sc.xy + o), 0.0)).r;
    if (d < reference_depth(sc, o, gradient)) {
      blocker_sum += linear_depth_ws(d);
      ++blockers;
    }
  }
  z_b = blockers > 0 ? blocker_sum / float(blockers) : 0.0;
  return blockers > 0;
}

// Whether the last shadow_pcss call's filter radius was raised to the minimum penumbra.
bool g_pcss_clamped = false;

// The filtering step of radius `filter_uv`. kernel: 0 Poisson, 1 grid (box), 2 disk.
float pcss_filter(vec3 sc, vec2 gradient, float filter_uv, int filter_taps, int kernel, int max_grid_taps, mat2 rotation) {
  if (kernel == 1) return pcf_grid(sc, gradient, filter_uv * g_shadow_res, max_grid_taps);
  if (kernel == 2) return pcf_disk(sc, gradient, filter_uv * g_shadow_res, max_grid_taps);
  return pcf_poisson(sc, gradient, filter_uv, filter_taps, rotation);
}

#if defined(PCSS_HIERARCHICAL)
layout(binding = UNIT_DEPTH_MINMAX) uniform sampler2D u_depth_minmax;  // the depth_minmax pass's pyramid

// The min (x) and max (y) stored depth over every atlas texel that a lookup within `radius_uv` of
// map uv `uv` can read (a superset may be covered): the 2x2 pyramid texels at the level whose
// blocks are at least as wide as the footprint. (0, 1) where the pyramid does not know; beyond the
// atlas the sampler's border (the far depth) raises the max to 1.
vec2 depth_range(vec2 uv, float radius_uv) {
  ivec2 atlas = textureSize(u_shadow_depth, 0);
  // Nearest lookups read the texel under their point; gathers and linear comparisons one beyond.
  ivec2 lo = ivec2(floor(atlas_uv(uv - radius_uv) * vec2(atlas))) - 1;
  ivec2 hi = ivec2(floor(atlas_uv(uv + radius_uv) * vec2(atlas))) + 1;
  bool beyond = any(lessThan(lo, ivec2(0))) || any(greaterThanEqual(hi, atlas));
  lo = max(lo, ivec2(0));
  hi = min(hi, atlas - 1);
  int span = max(hi.x - lo.x, hi.y - lo.y) + 1;
  int level = max(0, findMSB(max(span - 1, 1)));  // blocks of 2^(level + 1) >= span texels: <= 2 per axis
  if (level >= textureQueryLevels(u_depth_minmax)) return vec2(0.0, 1.0);
  ivec2 b0 = lo >> (level + 1), b1 = hi >> (level + 1);
  if (any(greaterThanEqual(b1, textureSize(u_depth_minmax, level)))) return vec2(0.0, 1.0);
  vec2 a = COUNTED(1, 8, texelFetch(u_depth_minmax, b0, level)).rg;
  vec2 b = COUNTED(1, 8, texelFetch(u_depth_minmax, ivec2(b1.x, b0.y), level)).rg;
  vec2 c = COUNTED(1, 8, texelFetch(u_depth_minmax, ivec2(b0.x, b1.y), level)).rg;
  vec2 d = COUNTED(1, 8, texelFetch(u_depth_minmax, b1, level)).rg;
  vec2 range = vec2(min(min(a.x, b.x), min(c.x, d.x)), max(max(a.y, b.y), max(c.y, d.y)));
  return beyond ? vec2(range.x, 1.0) : range;
}

// The receiver depth a lookup within `radius_uv` compares against, at its lowest (side -1) or
// highest (+1): reference_depth over the footprint, two texels wider for gathers.
float reference_bound(vec3 sc, vec2 gradient, float radius_uv, float side) {
  float reach = (abs(gradient.x) + abs(gradient.y)) * (radius_uv + 2.0 / g_shadow_res);
  return clamp(sc.z + side * reach - g_constant_bias, 0.0, 1.0);
}
#endif

// Returns visibility; `filter_uv` receives the filter radius used (0 when no filter was evaluated:
// no blocker, or, with PCSS_HIERARCHICAL, a certain umbra). kernel: 0 Poisson, 1 grid (box), 2 disk.
float shadow_pcss(vec3 sc, vec2 gradient, float z_r, int blocker_taps, int filter_taps, int kernel,
                  int max_grid_taps, mat2 rotation, out float filter_uv) {
  filter_uv = 0.0;
  g_pcss_clamped = false;
  float min_uv = u_pcss_min_penumbra_ws * uv_per_ws(z_r);
#if defined(PCSS_HIERARCHICAL)
  // Bounds before the search. With the nearest depth in the search region, z_min, every blocker
  // average satisfies z_b >= z_min, so the filter is at most pcss_filter_uv(z_r, z_min):
  // - z_min at or behind every reference depth of the search: no blocker can be found: lit, as
  //   the search would say;
  // - every texel the search and the widest filter can read in front of every reference depth:
  //   umbra, 0, as search and filter would give;
  // - the widest filter no wider than the minimum penumbra: the clamp is certain, so the filter
  //   runs at the minimum without a search, when that filter reads no further than the search
  //   would (where the sparse search would have missed blockers inside it, the filter sees them
  //   instead of calling the pixel lit; a wider filter would darken pixels the search calls lit),
  //   and when that filter costs no more fetches than the search (which, on a lit receiver,
  //   is all the full path pays): so the shortcut follows the map's size.
  float search = pcss_search_uv(z_r) * u_pcss_search_scale;
  vec2 near = depth_range(sc.xy, search);
  if (near.x >= reference_bound(sc, gradient, search, 1.0)) return 1.0;
  float widest = pcss_filter_uv(z_r, linear_depth_ws(near.x));
  float reach = max(search, max(widest, min_uv));
  vec2 all_range = reach > search ? depth_range(sc.xy, reach) : near;
  if (all_range.y < reference_bound(sc, gradient, reach, -1.0)) return 0.0;
  float side = 2.0 * min_uv * g_shadow_res + 2.0;  // texels per axis a box or disk filter reads
  float filter_fetches = kernel == 0 ? float(filter_taps) : 0.25 * side * side;
  if (widest <= min_uv && min_uv <= search && filter_fetches <= float(blocker_taps)) {
    filter_uv = min_uv;
    g_pcss_clamped = true;
    return pcss_filter(sc, gradient, filter_uv, filter_taps, kernel, max_grid_taps, rotation);
  }
#endif
  float z_b;
  if (!pcss_blocker_depth(sc, gradient, z_r, blocker_taps, rotation, z_b)) return 1.0;  // no blocker: fully lit
  filter_uv = pcss_filter_uv(z_r, z_b);
  g_pcss_clamped = filter_uv < min_uv;
  filter_uv = max(filter_uv, min_uv);
  return pcss_filter(sc, gradient, filter_uv, filter_taps, kernel, max_grid_taps, rotation);
}

#if defined(TECHNIQUE_PCSS) && !defined(PENUMBRA_COMPUTE)
float technique_visibility(vec3 sc, vec2 gradient, float depth_ws, out float filter_uv) {
#  if defined(KERNEL_GRID)
  const int kernel = 1;
#  elif defined(KERNEL_DISK)
  const int kernel = 2;
#  else
  const int kernel = 0;
#  endif
  return shadow_pcss(sc, gradient, depth_ws, u_blocker_taps, u_taps, kernel, u_max_grid_taps, poisson_rotation(true), filter_uv);
}
#endif
#endif  // SHADOW_PCSS_GLSL
