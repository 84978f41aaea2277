// Erosion soft shadows (Klein, Nischwitz & Obermeier 2012), the shading-pass half: the post
// passes (erosion_minmax.comp, erosion_search.comp) leave per pixel the eroded penumbra width w in
// world units (0: outside every penumbra); the pixel is filtered by PCF over w / 2, or keeps the
// hard test.
#ifndef SHADOW_EROSION_GLSL
#define SHADOW_EROSION_GLSL
#include "shadow_pcf.glsl"

#if defined(TECHNIQUE_EROSION) && !defined(PENUMBRA_COMPUTE)
float technique_visibility(vec3 sc, vec2 gradient, float depth_ws, out float filter_uv) {
  filter_uv = 0.0;
  float eroded_ws = COUNTED(1, 8, texelFetch(u_screen_visibility, ivec2(gl_FragCoord.xy), 0)).r;
  return eroded_ws > 0.0 ? pcf_poisson(sc, gradient, 0.5 * eroded_ws * uv_per_ws(depth_ws), u_taps, poisson_rotation(u_rotate))
                         : shadow_hard(sc);
}
#endif
#endif
