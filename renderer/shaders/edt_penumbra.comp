// Normalized-EDT penumbra. EDTSM (Macedo & Apolinario 2016, eq. 1): I = 1/2 - D/P in shadow,
// 1/2 + D/P lit, for D <= P/2, with D the world distance between the pixel's and its nearest
// site's G-buffer positions. EDTSSM (PROPAGATED_WIDTH; Macedo & Apolinario 2017, eq. 2-3): the same
// with P = beta * w_p of the nearest site. Pixels whose nearest site lies on another surface, or
// farther than P/2, keep their hard visibility.
layout(local_size_x = 8, local_size_y = 8) in;

#include "screen_space.glsl"

layout(binding = UNIT_POST_INPUT) uniform isampler2D u_nearest;  // EDT: nearest site, (-1, -1) when none
layout(binding = UNIT_POST_INPUT_2) uniform sampler2D u_site_width;
layout(binding = 0, rg32f) uniform writeonly image2D u_penumbra;  // intensity, the G-buffer's signed depth

uniform float u_penumbra_ws;  // EDTSM: P
uniform float u_beta;         // EDTSSM: P = beta * w_p(site)
// Measure D from the silhouette between the two site pixels rather than from the site's centre
// (the paper): D + half a pixel, so penumbrae narrower than a pixel stay hard.
uniform bool u_edge_between_pixels;

void main() {
  ivec2 size = textureSize(u_gbuffer_position, 0);
  ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (any(greaterThanEqual(p, size))) return;

  vec4 here = gbuffer(p);
  float hard = input_visibility(here);
  float intensity = covered(here) ? hard : 1.0;
  ivec2 site = texelFetch(u_nearest, p, 0).xy;
  if (covered(here) && site.x >= 0) {
    vec4 there = gbuffer(site);
#if defined(PROPAGATED_WIDTH)
    float width = u_beta * texelFetch(u_site_width, site, 0).r;
#else
    float width = u_penumbra_ws;
#endif
    float d = distance(here.xyz, there.xyz);
    if (u_edge_between_pixels) d += 0.5 / px_per_ws(eye_depth(here));
    if (width > 0.0 && d < 0.5 * width && same_surface(eye_depth(here), eye_depth(there)))
      intensity = hard > 0.5 ? 0.5 + d / width : 0.5 - d / width;
  }
  imageStore(u_penumbra, p, vec4(intensity, here.w, 0.0, 0.0));
}
