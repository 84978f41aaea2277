// Page marking of a virtual shadow map (shadows/virtual_shadow_map.h, PageMarker): each pixel's
// surface asks for the coarsest level whose texel still satisfies its rule and for the pages of
// that level its filter reaches, as adaptive::mark_pages does on the CPU:
//   rule       texel <= max(r / c, s · min_texel_px)   (r the filter's world radius, s the pixel's
//                                                       world footprint, c in texels)
//   footprint  texel <= s · min_texel_px
// A pixel outside its level's window takes the next coarser level that holds it; beyond the
// coarsest it is counted as unmarked.
#include "virtual_pages.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(binding = 0, rgba32f) uniform readonly image2D u_surface;  // world xyz; w > 0 where a surface is
layout(binding = 1, r32f) uniform writeonly image2D u_levels;     // debug view: the level each pixel samples
uniform bool u_write_levels;                                       // (-1: no surface, levels: beyond the coarsest)

layout(std430, binding = 0) buffer Marks {
  uint u_pixels_per_level[VSM_MAX_LEVELS];
  uint u_unmarked;
  uint u_page_bits[];  // bit (level · pages_per_side + y) · pages_per_side + x
};

uniform float u_radius_ws;  // the filter's world radius (0: none)

void main() {
  const ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (any(greaterThanEqual(p, imageSize(u_surface)))) return;
  const vec4 s = imageLoad(u_surface, p);
  if (s.w <= 0.0) {
    if (u_write_levels) imageStore(u_levels, p, vec4(-1.0));
    return;
  }
  const vec3 world = s.xyz;
  int level = vsm_level_for_texel(vsm_requested_texel_ws(world, u_radius_ws));
  const vec2 xy = vsm_light_point(world).xy;
  const float r = max(u_radius_ws, 0.0);
  const int n = u_vsm_pages_per_side;
  for (; level < u_vsm_levels; ++level) {
    if (!vsm_in_window(level, xy)) continue;
    const float page_ws = float(u_vsm_page_texels) * vsm_texel_ws(level);
    const vec2 local = (xy - u_vsm_origin[level]) / page_ws;
    const float reach = r / page_ws;  // the filter's square [xy - r, xy + r], in pages
    const ivec2 lo = max(ivec2(0), ivec2(floor(local - reach)));
    const ivec2 hi = min(ivec2(n - 1), ivec2(floor(local + reach)));
    for (int y = lo.y; y <= hi.y; ++y)
      for (int x = lo.x; x <= hi.x; ++x) {
        const uint bit = uint((level * n + y) * n + x);
        atomicOr(u_page_bits[bit >> 5u], 1u << (bit & 31u));
      }
    atomicAdd(u_pixels_per_level[level], 1u);
    if (u_write_levels) imageStore(u_levels, p, vec4(float(level)));
    return;
  }
  atomicAdd(u_unmarked, 1u);
  if (u_write_levels) imageStore(u_levels, p, vec4(float(u_vsm_levels)));
}
