// Variance shadow maps (Donnelly & Lauritzen 2006): Chebyshev's one-sided bound on the
// pre-filtered moments of linear depth, with a variance floor and light-bleeding reduction.
#ifndef SHADOW_VSM_GLSL
#define SHADOW_VSM_GLSL
uniform float u_vsm_min_variance;
uniform float u_vsm_bleed_reduction;

// Upper bound on P(depth >= t) for moments (m1, m2); 1 where t <= m1. Finite for every input.
float chebyshev_upper_bound(vec2 moments, float t, float min_variance) {
  if (t <= moments.x) return 1.0;
  float variance = max(moments.y - moments.x * moments.x, min_variance);
  float d = t - moments.x;
  return variance / (variance + d * d);
}

// Visibility for a receiver at normalized linear depth t behind filtered `moments`: Chebyshev's
// bound with the variance floor, then the light-bleeding reduction.
float vsm_visibility(vec2 moments, float t) {
  float p = chebyshev_upper_bound(moments, t, max(u_vsm_min_variance, 1e-12));
  return clamp((p - u_vsm_bleed_reduction) / (1.0 - u_vsm_bleed_reduction), 0.0, 1.0);
}

// Visibility for a receiver at normalized linear depth t.
float shadow_vsm(vec2 uv, float t) { return vsm_visibility(COUNTED(4, u_count_moment_bytes, textureLod(u_moments, atlas_uv(uv), 0.0)).rg, t); }

#if defined(TECHNIQUE_VSM) && !defined(PENUMBRA_COMPUTE)
// Moments of one depth (moments pass): t and t^2 plus the variance of t over the texel, estimated
// from its screen derivatives as Donnelly & Lauritzen suggest.
vec4 technique_moments(float t) {
  float dx = dFdx(t), dy = dFdy(t);
  return vec4(t, t * t + 0.25 * (dx * dx + dy * dy), 0.0, 0.0);
}

float technique_visibility(vec3 sc, vec2 gradient, float depth_ws, out float filter_uv) {
  filter_uv = 0.0;
  return shadow_vsm(sc.xy, normalized_light_depth(depth_ws));
}
#endif
#endif  // SHADOW_VSM_GLSL
