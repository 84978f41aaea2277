// Exponential shadow maps (Annen et al. 2008): the moments pass stores exp(c t) of the occluder's
// normalized linear depth t, the blur averages it, and a receiver at depth t reads
// E[exp(c z)] * exp(-c t), clamped to [0, 1]: above 1 where the receiver lies in front of its
// filtered occluders (non-planar receivers), the paper's overflow case.
#ifndef SHADOW_ESM_GLSL
#define SHADOW_ESM_GLSL

uniform float u_esm_exponent;  // c, already clamped to the float32 range (esm_exponent)

// Visibility for a receiver at normalized linear depth t.
float shadow_esm(vec2 uv, float t) {
  float occluders = COUNTED(4, u_count_moment_bytes, textureLod(u_moments, atlas_uv(uv), 0.0)).r;  // E[exp(c z)] over the filter
  return clamp(occluders * exp(-u_esm_exponent * t), 0.0, 1.0);
}

#if defined(TECHNIQUE_ESM) && !defined(PENUMBRA_COMPUTE)
vec4 technique_moments(float t) { return vec4(exp(u_esm_exponent * t), 0.0, 0.0, 0.0); }

float technique_visibility(vec3 sc, vec2 gradient, float depth_ws, out float filter_uv) {
  filter_uv = 0.0;
  return shadow_esm(sc.xy, normalized_light_depth(depth_ws));
}
#endif
#endif  // SHADOW_ESM_GLSL
