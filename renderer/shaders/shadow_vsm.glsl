// Variance shadow maps (Donnelly & Lauritzen 2006): Chebyshev's one-sided bound on the
// pre-filtered moments of linear depth, with a variance floor and light-bleeding reduction.
uniform float u_vsm_min_variance;
uniform float u_vsm_bleed_reduction;

// Upper bound on P(depth >= t) for moments (m1, m2); 1 where t <= m1. Finite for every input.
float chebyshev_upper_bound(vec2 moments, float t, float min_variance) {
  if (t <= moments.x) return 1.0;
  float variance = max(moments.y - moments.x * moments.x, min_variance);
  float d = t - moments.x;
  return variance / (variance + d * d);
}

// Visibility for a receiver at normalized linear depth t.
float shadow_vsm(vec2 uv, float t) {
  vec2 moments = textureLod(u_moments, atlas_uv(uv), 0.0).rg;
  float p = chebyshev_upper_bound(moments, t, max(u_vsm_min_variance, 1e-12));
  return clamp((p - u_vsm_bleed_reduction) / (1.0 - u_vsm_bleed_reduction), 0.0, 1.0);
}
