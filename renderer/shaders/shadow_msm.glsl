// Moment shadow mapping (Peters & Klein 2015): Hamburger 4MSM on the box-filtered moments of
// depth z in [-1, 1]. u_moments holds (z, z^2, z^3, z^4) as plain float32.
#ifndef SHADOW_MSM_GLSL
#define SHADOW_MSM_GLSL
uniform float u_msm_moment_bias;
uniform float u_msm_depth_bias;
uniform float u_msm_bleed_reduction;

// The four moments of one depth z in [-1, 1] (written by the moments pass).
vec4 msm_moments(float z) {
  float z2 = z * z;
  return vec4(z, z2, z2 * z, z2 * z2);
}

// Hamburger 4MSM: the sharpest lower bound on the fraction of depths in front of z_f among all
// distributions with the (biased) moments b; returns that shadow intensity in [0, 1]. Solves
// B c = (1, z_f, z_f^2) for the Hankel matrix B = [1 b1 b2; b1 b2 b3; b2 b3 b4] by an LDL^T
// factorization, takes the roots z2 <= z3 of c1 + c2 z + c3 z^2 and weighs the three-point
// distribution on {z_f, z2, z3} that has the moments b.
float msm_shadow_intensity(vec4 b, float z_f) {
  float d2 = max(b.y - b.x * b.x, 1e-12);
  float l32 = (b.z - b.x * b.y) / d2;
  float d3 = max(b.w - b.y * b.y - l32 * l32 * d2, 1e-12);
  float y2 = z_f - b.x;
  float y3 = z_f * z_f - b.y - l32 * y2;
  float c3 = y3 / d3;
  float c2 = y2 / d2 - l32 * c3;
  float c1 = 1.0 - b.x * c2 - b.y * c3;
  if (abs(c3) < 1e-30) return z_f > b.x ? 1.0 : 0.0;  // no quadratic: only the mean is known
  float p = c2 / c3;
  float q = c1 / c3;
  float r = sqrt(max(0.25 * p * p - q, 0.0));
  float z2 = -0.5 * p - r;
  float z3 = -0.5 * p + r;
  float g;
  if (z_f <= z2) {
    g = 0.0;
  } else if (z_f <= z3) {
    g = (z_f * z3 - b.x * (z_f + z3) + b.y) / ((z3 - z2) * (z_f - z2));
  } else {
    g = 1.0 - (z2 * z3 - b.x * (z2 + z3) + b.y) / ((z_f - z2) * (z_f - z3));
  }
  // Overflowing roots (p or q beyond float range) leave no bound: fall back to the mean.
  if (isnan(g) || isinf(g)) return z_f > b.x ? 1.0 : 0.0;
  return clamp(g, 0.0, 1.0);
}

// Visibility for a receiver at normalized linear depth t in [0, 1].
float shadow_msm(vec2 uv, float t) {
  vec4 b = mix(COUNTED(4, u_count_moment_bytes, textureLod(u_moments, atlas_uv(uv), 0.0)), vec4(0.0, 0.63, 0.0, 0.63), u_msm_moment_bias);
  float v = 1.0 - msm_shadow_intensity(b, 2.0 * t - 1.0 - u_msm_depth_bias);
  return clamp((v - u_msm_bleed_reduction) / (1.0 - u_msm_bleed_reduction), 0.0, 1.0);
}

#if defined(TECHNIQUE_MSM) && !defined(PENUMBRA_COMPUTE)
vec4 technique_moments(float t) { return msm_moments(2.0 * t - 1.0); }

float technique_visibility(vec3 sc, vec2 gradient, float depth_ws, out float filter_uv) {
  filter_uv = 0.0;
  return shadow_msm(sc.xy, normalized_light_depth(depth_ws));
}
#endif
#endif  // SHADOW_MSM_GLSL
