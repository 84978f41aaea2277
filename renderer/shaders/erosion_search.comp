// Erosion by the min-max mip-map (Klein, Nischwitz & Obermeier 2012, sec. 3): the widest
// penumbra any pixel can have bounds the search radius; the 2x2 texels around the pixel at the
// level that covers it say whether an edge is near and the largest width w among those edges;
// the level that covers w/2 then says whether this pixel lies inside that penumbra. Writes w in
// world units (0: outside every penumbra, the final pass keeps the hard test).
layout(local_size_x = 8, local_size_y = 8) in;

#define PENUMBRA_COMPUTE 1
#include "common.glsl"
#include "shadow_hard.glsl"
#include "shadow_pcf.glsl"
#include "shadow_pcss.glsl"
#include "screen_space.glsl"

layout(binding = UNIT_POST_INPUT) uniform sampler2D u_edges;  // min-max mip-map (erosion_minmax.comp)
layout(binding = 0, rg32f) uniform writeonly image2D u_eroded;

uniform float u_max_search_px;

// The smallest level whose 2x2 texels around a pixel reach `radius_px` on every side.
int level_for(float radius_px) {
  int top = textureQueryLevels(u_edges) - 1;
  return clamp(int(ceil(log2(max(2.0 * radius_px, 1.0)))), 0, top);
}

// (min edge flag, max width) over the 2x2 texels of `level` nearest to pixel centre `c`.
vec2 query(vec2 c, int level) {
  ivec2 size = textureSize(u_edges, level);
  vec2 block = vec2(float(1 << level));
  ivec2 i0 = clamp(ivec2(floor(c / block - 0.5)), ivec2(0), max(size - 2, ivec2(0)));
  ivec2 i1 = min(i0 + 1, size - 1);
  vec2 a = texelFetch(u_edges, i0, level).rg, b = texelFetch(u_edges, ivec2(i1.x, i0.y), level).rg;
  vec2 c2 = texelFetch(u_edges, ivec2(i0.x, i1.y), level).rg, d = texelFetch(u_edges, i1, level).rg;
  return vec2(min(min(a.x, b.x), min(c2.x, d.x)), max(max(a.y, b.y), max(c2.y, d.y)));
}

void main() {
  ivec2 size = textureSize(u_gbuffer_position, 0);
  ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (any(greaterThanEqual(p, size))) return;
  use_cascade(0);  // screen-space techniques sample the one map

  float width_ws = 0.0;
  vec4 here = gbuffer(p);
  if (covered(here)) {
    float scale = px_per_ws(eye_depth(here));
    float z_r = texelFetch(u_gbuffer_light, p, 0).w;
    // Half the widest penumbra at this receiver (a blocker at the light's near plane).
    float reach_ws = pcss_search_uv(z_r) * u_pcss_search_scale / uv_per_ws(z_r);
    vec2 c = vec2(p) + 0.5;
    vec2 e = query(c, level_for(min(reach_ws * scale, u_max_search_px)));
    if (e.x < 0.5 && e.y > 0.0 && query(c, level_for(0.5 * e.y)).x < 0.5) width_ws = e.y / scale;
  }
  imageStore(u_eroded, p, vec4(width_ws));
}
