// Revectorization-based shadow mapping (Macedo & Apolinario 2016) and RPCF, the box PCF of the
// revectorized shadow. Texel space: p = sc.xy * g_shadow_res; texel t = floor(p) covers
// [t, t + 1). Every test is the nearest-texel comparison of a texel centre against the receiver
// plane through the fragment, so all tests of one fragment agree on what "own side" means.
// Procedure and the choices the paper leaves open: docs/alternatives.md.
#ifndef SHADOW_RBSM_GLSL
#define SHADOW_RBSM_GLSL
#include "shadow_pcf.glsl"

uniform int u_rbsm_max_search;       // texels walked along a silhouette step in each direction
uniform int u_rpcf_max_grid_taps;

// Shadow test of texel t (1 lit, 0 shadowed) for the receiver plane through sc.
float rbsm_test(vec3 sc, vec2 gradient, ivec2 t) {
  vec2 centre = (vec2(t) + 0.5) / g_shadow_res;
  return COUNTED(1, 4, textureLod(u_shadow_cmp_nearest, vec3(atlas_uv(centre), reference_depth(sc, centre - sc.xy, gradient)), 0.0));
}

// Walks from texel t along e over the step whose edge faces n (t and t + n differ). Returns
// (texels walked beyond t, height of the revectorized silhouette where the step ends), heights
// measured along n in texels with t's row at [0, 1] and the step's edge at 1: 0.5 where the
// silhouette steps one texel into the own side, 1.5 where it steps one texel away, 1 where the
// step ends in a corner (a riser longer than one texel) or the walk found no end.
vec2 rbsm_walk(vec3 sc, vec2 gradient, ivec2 t, ivec2 n, ivec2 e, float own) {
  for (int k = 1; k <= u_rbsm_max_search; ++k) {
    ivec2 a = t + k * e;  // next texel on the own row
    if (rbsm_test(sc, gradient, a) != own) {
      return vec2(float(k - 1), rbsm_test(sc, gradient, a - n) == own ? 0.5 : 1.0);
    }
    ivec2 b = a + n;  // its neighbour across the edge
    if (rbsm_test(sc, gradient, b) == own) {
      return vec2(float(k - 1), rbsm_test(sc, gradient, b + n) == own ? 1.0 : 1.5);
    }
  }
  return vec2(float(u_rbsm_max_search), 1.0);
}

// The revectorized line of the silhouette edge between texel t and t + n, as an affine function
// g(f) = dot(g.xy, f) + g.z of the position f in [0, 1]^2 inside t: g > 0 on t's side. The line
// joins the heights at both ends of the step (rbsm_walk), linear in the normalized position
// along the step.
vec3 rbsm_edge_line(vec3 sc, vec2 gradient, ivec2 t, ivec2 n, float own) {
  ivec2 e = ivec2(abs(n.y), abs(n.x));
  vec2 ahead = rbsm_walk(sc, gradient, t, n, e, own);
  vec2 behind = rbsm_walk(sc, gradient, t, n, -e, own);
  // A one-texel step next to a longer perpendicular one is the riser of a staircase running the
  // other way: that staircase's lines pass through its midpoint, it keeps its border.
  if (ahead.x + behind.x == 0.0 && (ahead.y == 1.0 || behind.y == 1.0)) ahead.y = behind.y = 1.0;
  // height(along) = behind.y + slope * (along + behind.x); g = height - across.
  float slope = (ahead.y - behind.y) / (behind.x + ahead.x + 1.0);
  bool positive = n.x + n.y > 0;
  vec3 g = vec3(0.0, 0.0, behind.y + slope * behind.x - (positive ? 0.0 : 1.0));
  float across_sign = positive ? -1.0 : 1.0;  // across = f (toward +n) or 1 - f (toward -n)
  if (e.x != 0) g.xy = vec2(slope, across_sign);
  else g.xy = vec2(across_sign, slope);
  return g;
}

const ivec2 kRbsmNormals[4] = ivec2[4](ivec2(1, 0), ivec2(-1, 0), ivec2(0, 1), ivec2(0, -1));

// Revectorized hard visibility (0 or 1) at texel-space point p, tested against the receiver
// plane through sc. A point keeps its texel's test unless the line of one of the texel's
// silhouette edges puts it on the other side.
float rbsm_visibility_at(vec3 sc, vec2 gradient, vec2 p) {
  ivec2 t = ivec2(floor(p));
  vec2 f = p - vec2(t);
  float own = rbsm_test(sc, gradient, t);
  for (int i = 0; i < 4; ++i) {
    ivec2 n = kRbsmNormals[i];
    if (rbsm_test(sc, gradient, t + n) == own) continue;
    vec3 g = rbsm_edge_line(sc, gradient, t, n, own);
    if (dot(g.xy, f) + g.z <= 0.0) return 1.0 - own;
  }
  return own;
}

// RBSM: revectorized hard visibility at the fragment (0 or 1).
float shadow_rbsm(vec3 sc, vec2 gradient) {
  return rbsm_visibility_at(sc, gradient, sc.xy * g_shadow_res);
}

// Integral over x in [x0, x1] of clamp(a + b x, lo, hi).
float rbsm_clamped_integral(float a, float b, float x0, float x1, float lo, float hi) {
  if (abs(b) < 1e-6) return clamp(a + b * 0.5 * (x0 + x1), lo, hi) * (x1 - x0);
  // G' = clamp(u, lo, hi), continuous: lo u below lo, (lo^2 + u^2) / 2 between, then linear.
  vec2 u = vec2(a + b * x0, a + b * x1);
  vec2 c = clamp(u, lo, hi);
  vec2 g = 0.5 * (lo * lo + c * c) + lo * min(u - lo, 0.0) + hi * max(u - hi, 0.0);
  return (g.y - g.x) / b;
}

// Area of the part of the rectangle [lo, hi] (texel-local) where dot(g.xy, f) + g.z > 0.
float rbsm_halfplane_area(vec2 lo, vec2 hi, vec3 g) {
  bool along_x = abs(g.y) >= abs(g.x);  // integrate over x the extent in y, or the converse
  vec2 w = along_x ? g.xy : g.yx;
  vec2 l = along_x ? lo : lo.yx;
  vec2 h = along_x ? hi : hi.yx;
  if (w.y == 0.0) return g.z > 0.0 ? (hi.x - lo.x) * (hi.y - lo.y) : 0.0;
  // Boundary v*(u) = a + b u; the positive side lies above it when w.y > 0.
  float below = rbsm_clamped_integral(-g.z / w.y, -w.x / w.y, l.x, h.x, l.y, h.y) - l.y * (h.x - l.x);
  return w.y > 0.0 ? (h.x - l.x) * (h.y - l.y) - below : below;
}

// Area of the part of the rectangle [lo, hi] (texel-local) on the positive side of every line
// `use_line` marks. The region is the intersection of up to 8 half-planes n.p + c >= 0 (the
// rectangle's 4 and the lines); by Green's theorem its area is half the sum, over each
// half-plane's boundary line clipped to all the others, of the cross product of the clipped
// segment's ends, traversed with the inside on the left. No polygon is built (no arrays indexed
// at run time, which software rasterizers handle slowly); a boundary that coincides exactly with
// an earlier one is counted once.
float rbsm_clipped_area(vec2 lo, vec2 hi, vec3 lines[4], bool use_line[4]) {
  vec3 planes[8] = vec3[8](vec3(1.0, 0.0, -lo.x), vec3(-1.0, 0.0, hi.x), vec3(0.0, 1.0, -lo.y), vec3(0.0, -1.0, hi.y),
                           lines[0], lines[1], lines[2], lines[3]);
  bool used[8] = bool[8](true, true, true, true, use_line[0], use_line[1], use_line[2], use_line[3]);
  float twice_area = 0.0;
  for (int i = 0; i < 8; ++i) {
    if (!used[i]) continue;
    vec2 n = planes[i].xy;
    float nn = dot(n, n);
    if (nn == 0.0) continue;
    vec2 origin = -planes[i].z * n / nn;
    vec2 dir = vec2(n.y, -n.x);  // inside (along n) lies on the left
    float t0 = -1e30, t1 = 1e30;
    for (int j = 0; j < 8; ++j) {
      if (j == i || !used[j]) continue;
      float a = dot(planes[j].xy, origin) + planes[j].z;
      float b = dot(planes[j].xy, dir);
      if (b > 0.0) t0 = max(t0, -a / b);
      else if (b < 0.0) t1 = min(t1, -a / b);
      else if (a < 0.0 || (a == 0.0 && j < i)) t1 = t0;  // outside, or the same boundary again
    }
    if (t1 > t0) {
      vec2 p0 = origin + t0 * dir, p1 = origin + t1 * dir;
      twice_area += p0.x * p1.y - p1.x * p0.y;
    }
  }
  return max(0.5 * twice_area, 0.0);
}

// Integral of the revectorized visibility over the part [lo, hi] of texel t (texel-local): the
// area on the texel's own side of all its silhouette lines, in closed form for one line and by
// polygon clipping where several cross the texel.
float rbsm_texel_integral(vec3 sc, vec2 gradient, ivec2 t, vec2 lo, vec2 hi) {
  float own = rbsm_test(sc, gradient, t);
  float area = (hi.x - lo.x) * (hi.y - lo.y);
  vec3 lines[4];
  bool cuts[4];  // the line passes through the rectangle (lines that leave it whole are dropped)
  int count = 0;
  bool empty = false;
  vec3 last_line = vec3(0.0);
  for (int i = 0; i < 4; ++i) {
    cuts[i] = false;
    lines[i] = vec3(0.0, 0.0, 1.0);
    if (rbsm_test(sc, gradient, t + kRbsmNormals[i]) == own) continue;
    vec3 g = rbsm_edge_line(sc, gradient, t, kRbsmNormals[i], own);
    vec4 at_corners = g.x * vec4(lo.x, hi.x, hi.x, lo.x) + g.y * vec4(lo.y, lo.y, hi.y, hi.y) + g.z;
    float g_min = min(min(at_corners.x, at_corners.y), min(at_corners.z, at_corners.w));
    float g_max = max(max(at_corners.x, at_corners.y), max(at_corners.z, at_corners.w));
    if (g_max <= 0.0) empty = true;
    if (g_min >= 0.0) continue;
    lines[i] = g;
    cuts[i] = true;
    ++count;
    last_line = g;
  }
  float own_area;
  if (empty) own_area = 0.0;
  else if (count == 0) own_area = area;
  else if (count == 1) own_area = rbsm_halfplane_area(lo, hi, last_line);
  else own_area = rbsm_clipped_area(lo, hi, lines, cuts);
  return own > 0.5 ? own_area : area - own_area;
}

// Whether the tests of every texel in [first, last] (2x2 gathers; an odd span reads one more
// column or row) equal `value`.
bool rbsm_uniform(vec3 sc, vec2 gradient, ivec2 first, ivec2 last, float value) {
  for (int j = first.y; j <= last.y; j += 2) {
    for (int i = first.x; i <= last.x; i += 2) {
      vec2 corner = vec2(i + 1, j + 1) / g_shadow_res;
      vec4 t = COUNTED(4, 4, textureGather(u_shadow_cmp_nearest, atlas_uv(corner), reference_depth(sc, corner - sc.xy, gradient)));
      if (any(notEqual(t, vec4(value)))) return false;
    }
  }
  return true;
}

// RPCF: the mean of the revectorized visibility over the square p +- radius (texels), each texel
// integrated over the part the square covers (rbsm_texel_integral). Kernels wider than
// `max_taps` texels per axis take one revectorized test per stride^2 cell, weighted by the
// cell's coverage, as pcf_grid does; radius 0 is RBSM.
float shadow_rpcf(vec3 sc, vec2 gradient, float radius_texels, int max_taps) {
  vec2 p = sc.xy * g_shadow_res;
  if (radius_texels <= 0.0) return rbsm_visibility_at(sc, gradient, p);
  BoxFootprint box = box_footprint(p, radius_texels);
  float sum = 0.0;
  if (box.span <= max_taps) {
    // No silhouette under the box or next to it: every texel keeps its test.
    float centre = rbsm_test(sc, gradient, ivec2(floor(p)));
    if (rbsm_uniform(sc, gradient, box.first - 1, box.last + 1, centre)) return centre;
    for (int j = box.first.y; j <= box.last.y; ++j) {
      for (int i = box.first.x; i <= box.last.x; ++i) {
        vec2 t = vec2(i, j);
        vec2 a = clamp(box.lo - t, 0.0, 1.0), b = clamp(box.hi - t, 0.0, 1.0);
        if (b.x > a.x && b.y > a.y) sum += rbsm_texel_integral(sc, gradient, ivec2(i, j), a, b);
      }
    }
    return sum * box.norm;
  }
  BOX_STRIDED_SUM(box, max_taps, sum, rbsm_visibility_at(sc, gradient, cell_centre))
  return sum * box.norm;
}

#if defined(TECHNIQUE_RBSM) && !defined(PENUMBRA_COMPUTE)
float technique_visibility(vec3 sc, vec2 gradient, float depth_ws, out float filter_uv) {
  filter_uv = 0.0;
  return shadow_rbsm(sc, gradient);
}
#endif

#if defined(TECHNIQUE_RPCF) && !defined(PENUMBRA_COMPUTE)
float technique_visibility(vec3 sc, vec2 gradient, float depth_ws, out float filter_uv) {
  filter_uv = 0.0;
  return shadow_rpcf(sc, gradient, filter_radius_texels(depth_ws), u_rpcf_max_grid_taps);
}
#endif
#endif  // SHADOW_RBSM_GLSL
