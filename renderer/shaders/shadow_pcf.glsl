// Percentage-closer filtering kernels. Both return visibility in [0, 1].
#ifndef SHADOW_PCF_GLSL
#define SHADOW_PCF_GLSL
#include "shadow_hard.glsl"

uniform int u_taps;          // Poisson taps of the filter (PCF, PCSS, erosion)
uniform bool u_rotate;       // rotate the Poisson disk per pixel
uniform int u_max_grid_taps; // grid kernels: taps per axis before striding

// Length of [a0, a1] and [b0, b1].
float overlap(float a0, float a1, float b0, float b1) {
  return max(0.0, min(a1, b1) - max(a0, b0));
}

// The texels under the square p +- radius_texels (texel coordinates): its corners, the first and
// last texel it touches, their count per axis and 1 / its area (box-filtered PCF and RPCF).
struct BoxFootprint {
  vec2 lo, hi;
  ivec2 first, last;
  int span;
  float norm;
};
BoxFootprint box_footprint(vec2 p, float radius_texels) {
  BoxFootprint b;
  b.lo = p - radius_texels;
  b.hi = p + radius_texels;
  b.first = ivec2(floor(b.lo));
  b.last = ivec2(ceil(b.hi)) - 1;
  b.span = b.last.x - b.first.x + 1;
  b.norm = 1.0 / (4.0 * radius_texels * radius_texels);
  return b;
}

// Box-filtered PCF: the mean of the nearest-texel shadow test over the square sc.xy +- r (texels),
// each texel weighted by the area of it the square covers, so the result is exact for any
// fractional radius. Whole 2x2 blocks are compared at once with textureGather. Kernels wider than
// `max_taps` texels per axis are sampled with a stride (one comparison per stride^2 cell).
float pcf_grid(vec3 sc, vec2 gradient, float radius_texels, int max_taps) {
  if (radius_texels <= 0.0) return shadow_hard(sc);
  BoxFootprint box = box_footprint(sc.xy * g_shadow_res, radius_texels);
  float sum = 0.0;
  if (box.span <= max_taps) {
    for (int j = box.first.y; j <= box.last.y; j += 2) {
      vec2 wy = vec2(overlap(float(j), float(j + 1), box.lo.y, box.hi.y), overlap(float(j + 1), float(j + 2), box.lo.y, box.hi.y));
      for (int i = box.first.x; i <= box.last.x; i += 2) {
        vec2 wx = vec2(overlap(float(i), float(i + 1), box.lo.x, box.hi.x), overlap(float(i + 1), float(i + 2), box.lo.x, box.hi.x));
        vec2 corner = vec2(i + 1, j + 1) / g_shadow_res;
        // Gather order: (i, j+1), (i+1, j+1), (i+1, j), (i, j).
        vec4 t = textureGather(u_shadow_cmp_nearest, atlas_uv(corner), reference_depth(sc, corner - sc.xy, gradient));
        sum += dot(t, vec4(wx.x * wy.y, wx.y * wy.y, wx.y * wy.x, wx.x * wy.x));
      }
    }
    return sum * box.norm;
  }
  int stride = (box.span + max_taps - 1) / max_taps;
  for (int j = box.first.y; j <= box.last.y; j += stride) {
    float wy = overlap(float(j), float(j + stride), box.lo.y, box.hi.y);
    for (int i = box.first.x; i <= box.last.x; i += stride) {
      float wx = overlap(float(i), float(i + stride), box.lo.x, box.hi.x);
      vec2 centre = (vec2(i, j) + 0.5 * float(stride)) / g_shadow_res;
      sum += wx * wy * texture(u_shadow_cmp_nearest, vec3(atlas_uv(centre), reference_depth(sc, centre - sc.xy, gradient)));
    }
  }
  return sum * box.norm;
}

// Poisson-disk PCF over a disk of radius `radius_uv`; each tap is a hardware 2x2 comparison.
float pcf_poisson(vec3 sc, vec2 gradient, float radius_uv, int taps, mat2 rotation) {
  if (radius_uv <= 0.0) return texture(u_shadow_cmp, vec3(atlas_uv(sc.xy), reference_depth(sc, vec2(0.0), gradient)));
  float sum = 0.0;
  for (int i = 0; i < taps; ++i) {
    vec2 o = rotation * u_poisson[i] * radius_uv;
    sum += texture(u_shadow_cmp, vec3(atlas_uv(sc.xy + o), reference_depth(sc, o, gradient)));
  }
  return sum / float(taps);
}

#if defined(TECHNIQUE_PCF) && !defined(PENUMBRA_COMPUTE)
float technique_visibility(vec3 sc, vec2 gradient, float depth_ws, out float filter_uv) {
  filter_uv = 0.0;
  float radius_uv = filter_radius_uv(depth_ws);
#  if defined(KERNEL_GRID)
  return pcf_grid(sc, gradient, radius_uv * g_shadow_res, u_max_grid_taps);
#  else
  return pcf_poisson(sc, gradient, radius_uv, u_taps, poisson_rotation(u_rotate));
#  endif
}
#endif
#endif  // SHADOW_PCF_GLSL
