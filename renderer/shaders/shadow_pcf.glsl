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

// A box wider than `max_taps` texels per axis, strided: one test per stride^2 cell, weighted by
// the part of the cell the box covers, added to `sum`. TEST is an expression of `cell_centre`
// (texel coordinates). Shared by pcf_grid and RPCF (GLSL has no function parameters, hence the
// macro).
#define BOX_STRIDED_SUM(box, max_taps, sum, TEST)                                   \
  {                                                                                \
    int stride = (box.span + max_taps - 1) / max_taps;                             \
    for (int j = box.first.y; j <= box.last.y; j += stride) {                      \
      float wy = overlap(float(j), float(j + stride), box.lo.y, box.hi.y);         \
      for (int i = box.first.x; i <= box.last.x; i += stride) {                    \
        float wx = overlap(float(i), float(i + stride), box.lo.x, box.hi.x);       \
        vec2 cell_centre = vec2(i, j) + 0.5 * float(stride);                       \
        sum += wx * wy * (TEST);                                                   \
      }                                                                            \
    }                                                                              \
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
        vec4 t = COUNTED(4, 4, textureGather(u_shadow_cmp_nearest, atlas_uv(corner), reference_depth(sc, corner - sc.xy, gradient)));
        sum += dot(t, vec4(wx.x * wy.y, wx.y * wy.y, wx.y * wy.x, wx.x * wy.x));
      }
    }
    return sum * box.norm;
  }
  BOX_STRIDED_SUM(box, max_taps, sum,
                  COUNTED(1, 4, texture(u_shadow_cmp_nearest, vec3(atlas_uv(cell_centre / g_shadow_res),
                                                                   reference_depth(sc, cell_centre / g_shadow_res - sc.xy, gradient)))))
  return sum * box.norm;
}

// The exact disk: the area of the disk of radius r centred at the origin inside [0, X] x [0, Y],
// signed by the quadrant of (X, Y), so the area inside any rectangle is F(x1, y1) - F(x0, y1) -
// F(x1, y0) + F(x0, y0). chord: the integral of sqrt(r^2 - t^2) over [0, x], x in [0, r].
float disk_chord_integral(float x, float r) {
  return 0.5 * (x * sqrt(max(r * r - x * x, 0.0)) + r * r * asin(clamp(x / r, -1.0, 1.0)));
}
float disk_corner_area(float X, float Y, float r) {
  float x = min(abs(X), r), y = min(abs(Y), r);
  float area;
  if (x * x + y * y <= r * r) {
    area = x * y;
  } else {
    float xc = sqrt(max(r * r - y * y, 0.0));  // where the row y meets the circle
    area = xc * y + disk_chord_integral(x, r) - disk_chord_integral(xc, r);
  }
  return sign(X) * sign(Y) * area;
}

// Disk-filtered PCF, the ideal filter: the mean of the nearest-texel shadow test over the disk of
// radius r (texels) around sc.xy, each texel weighted by the area of it the disk covers. The
// limit of ever denser disk kernels: the result depends on r alone, not on a tap pattern, and is
// exact for any fractional radius. Whole 2x2 blocks are compared at once with textureGather;
// blocks outside the disk are skipped and blocks inside it weigh their texels whole, so only the
// blocks the circle crosses evaluate areas. Kernels wider than `max_taps` texels per axis are sampled
// with a stride (one comparison per stride^2 cell, weighted by the disk's area in the cell).
float pcf_disk(vec3 sc, vec2 gradient, float radius_texels, int max_taps) {
  if (radius_texels <= 0.0) return shadow_hard(sc);
  float r = radius_texels;
  vec2 p = sc.xy * g_shadow_res;
  BoxFootprint box = box_footprint(p, r);
  int stride = box.span <= max_taps ? 2 : 2 * ((box.span + max_taps - 1) / max_taps);
  float sum = 0.0, weight = 0.0;
  for (int j = box.first.y; j <= box.last.y; j += stride) {
    vec3 y = vec3(float(j), float(j) + 0.5 * float(stride), float(j + stride)) - p.y;
    if (y.x > r || y.z < -r) continue;
    for (int i = box.first.x; i <= box.last.x; i += stride) {
      vec3 x = vec3(float(i), float(i) + 0.5 * float(stride), float(i + stride)) - p.x;
      vec2 nearest = clamp(vec2(0.0), vec2(x.x, y.x), vec2(x.z, y.z));
      if (dot(nearest, nearest) >= r * r) continue;
      vec2 farthest = max(abs(vec2(x.x, y.x)), abs(vec2(x.z, y.z)));
      vec4 w;
      if (dot(farthest, farthest) <= r * r) {
        w = vec4(0.25 * float(stride * stride));  // inside the disk: each quarter whole
      } else {
        // Corner areas at the cell's 3 x 3 lattice (the two halves of each axis).
        vec3 f0 = vec3(disk_corner_area(x.x, y.x, r), disk_corner_area(x.y, y.x, r), disk_corner_area(x.z, y.x, r));
        vec3 f1 = vec3(disk_corner_area(x.x, y.y, r), disk_corner_area(x.y, y.y, r), disk_corner_area(x.z, y.y, r));
        vec3 f2 = vec3(disk_corner_area(x.x, y.z, r), disk_corner_area(x.y, y.z, r), disk_corner_area(x.z, y.z, r));
        // Gather order: (i, j+1), (i+1, j+1), (i+1, j), (i, j).
        w = vec4(f2.y - f2.x - f1.y + f1.x, f2.z - f2.y - f1.z + f1.y, f1.z - f1.y - f0.z + f0.y, f1.y - f1.x - f0.y + f0.x);
      }
      if (stride == 2) {
        vec2 corner = vec2(i + 1, j + 1) / g_shadow_res;
        vec4 t = COUNTED(4, 4, textureGather(u_shadow_cmp_nearest, atlas_uv(corner), reference_depth(sc, corner - sc.xy, gradient)));
        sum += dot(t, w);
      } else {
        // One comparison per quarter cell (stride / 2 texels a side), at its centre.
        vec2 h = vec2(0.25 * float(stride));
        vec2 c00 = (vec2(i, j) + h) / g_shadow_res, d = 2.0 * h / g_shadow_res;
        vec2 c[4] = vec2[4](c00 + vec2(0.0, d.y), c00 + d, c00 + vec2(d.x, 0.0), c00);
        for (int k = 0; k < 4; ++k)
          sum += w[k] * COUNTED(1, 4, texture(u_shadow_cmp_nearest, vec3(atlas_uv(c[k]), reference_depth(sc, c[k] - sc.xy, gradient))));
      }
      weight += w.x + w.y + w.z + w.w;
    }
  }
  return weight > 0.0 ? clamp(sum / weight, 0.0, 1.0) : shadow_hard(sc);
}

// Poisson-disk PCF over a disk of radius `radius_uv`; each tap is a hardware 2x2 comparison.
float pcf_poisson(vec3 sc, vec2 gradient, float radius_uv, int taps, mat2 rotation) {
  if (radius_uv <= 0.0) return COUNTED(4, 4, texture(u_shadow_cmp, vec3(atlas_uv(sc.xy), reference_depth(sc, vec2(0.0), gradient))));
  float sum = 0.0;
  for (int i = 0; i < taps; ++i) {
    vec2 o = rotation * u_poisson[i] * radius_uv;
    sum += COUNTED(4, 4, texture(u_shadow_cmp, vec3(atlas_uv(sc.xy + o), reference_depth(sc, o, gradient))));
  }
  return sum / float(taps);
}

#if defined(TECHNIQUE_PCF) && !defined(PENUMBRA_COMPUTE)
float technique_visibility(vec3 sc, vec2 gradient, float depth_ws, out float filter_uv) {
  filter_uv = 0.0;
  float radius_uv = filter_radius_uv(depth_ws);
#  if defined(KERNEL_GRID)
  return pcf_grid(sc, gradient, radius_uv * g_shadow_res, u_max_grid_taps);
#  elif defined(KERNEL_DISK)
  return pcf_disk(sc, gradient, radius_uv * g_shadow_res, u_max_grid_taps);
#  else
  return pcf_poisson(sc, gradient, radius_uv, u_taps, poisson_rotation(u_rotate));
#  endif
}
#endif
#endif  // SHADOW_PCF_GLSL
