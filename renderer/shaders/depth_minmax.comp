// One level of the atlas's min-max depth pyramid (the depth_minmax pass, for PCSS's bounds in
// shadow_pcss.glsl): pyramid level L (mip L - 1 of u_out) holds per texel the min (r) and max (g)
// stored depth over the 2^L x 2^L atlas texels under it, from the four children one level down
// (the depth atlas itself for L = 1). A child is known only when its block of atlas texels lies
// inside one map's region with its guard band, which the shadow-map pass drew or cleared this
// frame; any other child counts as (0, 1), which bounds every depth, so a lookup that reaches
// stale or unused atlas texels only loses its shortcut, never gets a wrong bound.
layout(local_size_x = 8, local_size_y = 8) in;

layout(binding = 0) uniform sampler2D u_depth;   // the depth atlas (L = 1)
layout(binding = 1) uniform sampler2D u_minmax;  // the pyramid (L > 1 reads mip L - 2)
layout(rg32f, binding = 0) uniform writeonly image2D u_out;

uniform int u_level;       // pyramid level written, L >= 1
uniform ivec2 u_origin;    // first texel of level L this dispatch covers
uniform ivec2 u_extent;    // texels of level L it covers
uniform int u_regions;
uniform ivec4 u_region[4];  // each map's region with its guard band, atlas texels [x0, x1) x [y0, y1)

bool known(ivec2 lo, ivec2 hi) {
  for (int i = 0; i < u_regions; ++i)
    if (all(greaterThanEqual(lo, u_region[i].xy)) && all(lessThanEqual(hi, u_region[i].zw))) return true;
  return false;
}

void main() {
  ivec2 id = ivec2(gl_GlobalInvocationID.xy);
  if (any(greaterThanEqual(id, u_extent))) return;
  ivec2 p = u_origin + id;
  int child = 1 << (u_level - 1);  // atlas texels per side of a child block
  ivec2 children = u_level == 1 ? textureSize(u_depth, 0) : textureSize(u_minmax, u_level - 2);
  vec2 range = vec2(1.0, 0.0);
  if (all(lessThan(2 * p + 1, children)) && known(2 * p * child, (2 * p + 2) * child)) {
    // The whole block inside one map (most of them): one gather (L = 1) or four fetches.
    vec4 x, y;
    if (u_level == 1) {
      x = y = textureGather(u_depth, vec2(2 * p + 1) / vec2(children), 0);
    } else {
      vec2 a = texelFetch(u_minmax, 2 * p, u_level - 2).rg, b = texelFetch(u_minmax, 2 * p + ivec2(1, 0), u_level - 2).rg;
      vec2 c = texelFetch(u_minmax, 2 * p + ivec2(0, 1), u_level - 2).rg, d = texelFetch(u_minmax, 2 * p + 1, u_level - 2).rg;
      x = vec4(a.x, b.x, c.x, d.x);
      y = vec4(a.y, b.y, c.y, d.y);
    }
    imageStore(u_out, p, vec4(min(min(x.x, x.y), min(x.z, x.w)), max(max(y.x, y.y), max(y.z, y.w)), 0.0, 0.0));
    return;
  }
  for (int j = 0; j < 2; ++j)
    for (int i = 0; i < 2; ++i) {
      ivec2 c = 2 * p + ivec2(i, j);
      vec2 v = vec2(0.0, 1.0);
      if (all(lessThan(c, children)) && known(c * child, (c + 1) * child))
        v = u_level == 1 ? vec2(texelFetch(u_depth, c, 0).r) : texelFetch(u_minmax, c, u_level - 2).rg;
      range = vec2(min(range.x, v.x), max(range.y, v.y));
    }
  imageStore(u_out, p, vec4(range, 0.0, 0.0));
}
