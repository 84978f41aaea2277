// Silhouette sites of the hard (input) shadows in screen space. A covered pixel is a site when a
// neighbour on the same surface has the other visibility: the 3x3 window (EDTSM, EDTSSM; Macedo
// & Apolinario) or, with LAPLACIAN, the 4-neighbour cross of the 3x3 Laplacian (erosion; Klein et
// al.). With BLOCKER_SEARCH a site also gets its penumbra width w_p (world units at the receiver)
// from a PCSS blocker search around its own shadow-map position; a site whose search finds no
// blocker is dropped.
layout(local_size_x = 8, local_size_y = 8) in;

#define PENUMBRA_COMPUTE 1
#include "common.glsl"
#include "shadow_hard.glsl"
#include "shadow_pcf.glsl"
#include "shadow_pcss.glsl"
#include "screen_space.glsl"

layout(binding = 0, r8ui) uniform writeonly uimage2D u_sites;
layout(binding = 1, r32f) uniform writeonly image2D u_site_width;  // w_p in world units, 0 off sites

void main() {
  ivec2 size = textureSize(u_gbuffer_position, 0);
  ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (any(greaterThanEqual(p, size))) return;
  use_cascade(0);  // screen-space techniques sample the one map

  bool site = false;
  vec4 here = gbuffer(p);
  if (covered(here)) {
    float z = eye_depth(here);
    for (int dy = -1; dy <= 1 && !site; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
#if defined(LAPLACIAN)
        if (dx != 0 && dy != 0) continue;
#endif
        ivec2 q = p + ivec2(dx, dy);
        if ((dx == 0 && dy == 0) || any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, size))) continue;
        vec4 there = gbuffer(q);
        if (covered(there) && (there.w > 0.0) != (here.w > 0.0) && same_surface(z, eye_depth(there))) {
          site = true;
          break;
        }
      }
    }
  }

  float width_ws = 0.0;
#if defined(BLOCKER_SEARCH)
  if (site) {
    vec4 l = texelFetch(u_gbuffer_light, p, 0);  // the reference depth is already biased
    float z_b;
    if (pcss_blocker_depth(l.xyz, vec2(0.0), l.w, u_blocker_taps, mat2(1.0), z_b)) {
      // Parallel planes: 2 * the PCSS filter radius is the full penumbra, converted to world units.
      width_ws = 2.0 * pcss_filter_uv(l.w, z_b) / uv_per_ws(l.w);
    } else {
      site = false;
    }
  }
#endif
  imageStore(u_sites, p, uvec4(site ? 1u : 0u));
  imageStore(u_site_width, p, vec4(width_ws));
}
