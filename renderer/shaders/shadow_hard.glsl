// Hard shadow: one nearest-texel comparison. Returns visibility in {0, 1}.
float shadow_hard(vec3 sc) {
  return texture(u_shadow_cmp_nearest, vec3(atlas_uv(sc.xy), reference_depth(sc, vec2(0.0), vec2(0.0))));
}
