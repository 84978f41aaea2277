// Exponential variance shadow maps (Lauritzen & McCool 2008): Chebyshev's bound on the moments
// of two warps of depth x = 2t - 1, exp(c+ x) and -exp(-c- x); the smaller bound wins.
#ifndef SHADOW_EVSM_GLSL
#define SHADOW_EVSM_GLSL
#include "shadow_vsm.glsl"

uniform vec2 u_evsm_exponents;  // (c+, c-), already clamped to the storage format
uniform float u_evsm_min_variance;
uniform float u_evsm_bleed_reduction;

// The two warped depths of normalized linear depth t in [0, 1].
vec2 evsm_warp(float t) {
  float x = 2.0 * t - 1.0;
  return vec2(exp(u_evsm_exponents.x * x), -exp(-u_evsm_exponents.y * x));
}

// The moments of one depth (written by the moments pass): (w+, w+^2, w-, w-^2).
vec4 evsm_moments(float t) {
  vec2 w = evsm_warp(t);
  return vec4(w.x, w.x * w.x, w.y, w.y * w.y);
}

// Visibility for a receiver at normalized linear depth t. The variance floor, given in depth^2,
// is carried into each warp by its slope dw/dt = 2c|w| at the receiver.
float shadow_evsm(vec2 uv, float t) {
  vec4 m = COUNTED(4, u_count_moment_bytes, textureLod(u_moments, atlas_uv(uv), 0.0));
  vec2 w = evsm_warp(t);
  vec2 slope = 2.0 * u_evsm_exponents * abs(w);
  vec2 floor_variance = max(u_evsm_min_variance * slope * slope, vec2(1e-30));
  float positive = chebyshev_upper_bound(m.xy, w.x, floor_variance.x);
  float negative = chebyshev_upper_bound(m.zw, w.y, floor_variance.y);
  float v = min(positive, negative);
  return clamp((v - u_evsm_bleed_reduction) / (1.0 - u_evsm_bleed_reduction), 0.0, 1.0);
}

#if defined(TECHNIQUE_EVSM) && !defined(PENUMBRA_COMPUTE)
vec4 technique_moments(float t) { return evsm_moments(t); }

float technique_visibility(vec3 sc, vec2 gradient, float depth_ws, out float filter_uv) {
  filter_uv = 0.0;
  return shadow_evsm(sc.xy, normalized_light_depth(depth_ws));
}
#endif
#endif  // SHADOW_EVSM_GLSL
