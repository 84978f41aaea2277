// Hard shadow: one nearest-texel comparison. Returns visibility in {0, 1}.
#ifndef SHADOW_HARD_GLSL
#define SHADOW_HARD_GLSL
float shadow_hard(vec3 sc) {
  return COUNTED(1, 4, texture(u_shadow_cmp_nearest, vec3(atlas_uv(sc.xy), reference_depth(sc, vec2(0.0), vec2(0.0)))));
}

#if defined(TECHNIQUE_HARD)
float technique_visibility(vec3 sc, vec2 gradient, float depth_ws, out float filter_uv) {
  filter_uv = 0.0;
  return shadow_hard(sc);
}
#endif
#endif  // SHADOW_HARD_GLSL
