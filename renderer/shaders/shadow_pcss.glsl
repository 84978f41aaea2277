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
    float d = textureLod(u_shadow_depth, atlas_uv(sc.xy + o), 0.0).r;
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

// Returns visibility; `filter_uv` receives the filter radius used (0 when no blocker was found).
// kernel: 0 Poisson, 1 grid (box), 2 disk.
float shadow_pcss(vec3 sc, vec2 gradient, float z_r, int blocker_taps, int filter_taps, int kernel,
                  int max_grid_taps, mat2 rotation, out float filter_uv) {
  filter_uv = 0.0;
  g_pcss_clamped = false;
  float z_b;
  if (!pcss_blocker_depth(sc, gradient, z_r, blocker_taps, rotation, z_b)) return 1.0;  // no blocker: fully lit
  float min_uv = u_pcss_min_penumbra_ws * uv_per_ws(z_r);
  filter_uv = pcss_filter_uv(z_r, z_b);
  g_pcss_clamped = filter_uv < min_uv;
  filter_uv = max(filter_uv, min_uv);
  if (kernel == 1) return pcf_grid(sc, gradient, filter_uv * g_shadow_res, max_grid_taps);
  if (kernel == 2) return pcf_disk(sc, gradient, filter_uv * g_shadow_res, max_grid_taps);
  return pcf_poisson(sc, gradient, filter_uv, filter_taps, rotation);
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
