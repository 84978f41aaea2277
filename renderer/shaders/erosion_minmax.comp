// Min-max mip-map of the erosion's edge image (Klein, Nischwitz & Obermeier 2012): channel r is 0
// where an edge pixel lies inside the texel's footprint and 1 elsewhere (min-reduced), channel g
// the largest penumbra width of those edges in pixels (max-reduced). u_level 0 builds the base
// from the edge sites; level l reduces level l - 1 (the last row/column of an odd-sized level
// also takes the texel that halving would drop, so every pixel stays covered).
layout(local_size_x = 8, local_size_y = 8) in;

#include "screen_space.glsl"

layout(binding = UNIT_POST_INPUT) uniform usampler2D u_sites;
layout(binding = UNIT_POST_INPUT_2) uniform sampler2D u_site_width;  // world units
layout(binding = 0, rg32f) uniform readonly image2D u_finer;
layout(binding = 1, rg32f) uniform writeonly image2D u_coarser;

uniform int u_level;

void main() {
  ivec2 size = imageSize(u_coarser);
  ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (any(greaterThanEqual(p, size))) return;
  if (u_level == 0) {
    bool edge = texelFetch(u_sites, p, 0).r != 0u;
    float width_px = 0.0;
    if (edge) width_px = texelFetch(u_site_width, p, 0).r * px_per_ws(eye_depth(gbuffer(p)));
    imageStore(u_coarser, p, vec4(edge ? 0.0 : 1.0, width_px, 0.0, 0.0));
    return;
  }
  ivec2 finer = imageSize(u_finer);
  ivec2 lo = 2 * p;
  ivec2 hi = min(2 * p + 1, finer - 1);
  if (p.x == size.x - 1) hi.x = finer.x - 1;
  if (p.y == size.y - 1) hi.y = finer.y - 1;
  vec2 r = vec2(1.0, 0.0);
  for (int y = lo.y; y <= hi.y; ++y)
    for (int x = lo.x; x <= hi.x; ++x) {
      vec2 v = imageLoad(u_finer, ivec2(x, y)).rg;
      r = vec2(min(r.x, v.x), max(r.y, v.y));
    }
  imageStore(u_coarser, p, vec4(r, 0.0, 0.0));
}
