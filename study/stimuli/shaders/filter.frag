// Stimulus pass: PCF of the receiver's shadow test at every pixel centre, in linear light.
// Writes the lit fraction (visibility) in [0, 1]; the display encoding happens on the CPU.
//
// Kernels (u_kernel): 0 disk   exact area-weighted disk of radius r (the limit of a dense disk
//                              kernel: the value depends only on r, not on a tap pattern)
//                     1 grid   exact area-weighted square of half-side r (box PCF)
//                     2 poisson u_tap_count Poisson-disk taps scaled by r and rotated per trial
// Sources (u_source): 0 the shadow map (nearest texel, depth < 0.5 = occluded)
//                     1 the original straight edge y = m x + b (occluded below), analytically

layout(location = 0) out float o_visibility;

uniform sampler2D u_depth;       // the shadow map, read with texelFetch
uniform vec2 u_map_origin_px;    // canonical position of texel (0, 0)'s lower-left corner
uniform float u_texel_px;        // artifact size: one texel in stimulus px
uniform int u_map_texels;        // texels per side
uniform vec2 u_size_px;          // stimulus size
uniform mat2 u_to_canonical;     // the trial's orientation (a dihedral map: keeps the grid aligned)
uniform float u_radius_px;
uniform int u_kernel;
uniform int u_source;
uniform vec2 u_line;             // (m, b): the original edge y = m x + b in the canonical frame
uniform vec2 u_taps[64];         // unit-disk taps, already rotated
uniform int u_tap_count;

const float PI = 3.14159265358979;

// Integral of sqrt(r^2 - t^2) for t in [0, x], x in [0, r].
float chord_integral(float x, float r) {
  return 0.5 * (x * sqrt(max(r * r - x * x, 0.0)) + r * r * asin(clamp(x / r, -1.0, 1.0)));
}

// Area of the disk (radius r, centre 0) inside [0, X] x [0, Y] for X, Y >= 0.
float quadrant_area(float X, float Y, float r) {
  X = min(X, r);
  Y = min(Y, r);
  if (X * X + Y * Y <= r * r) return X * Y;
  float xc = sqrt(max(r * r - Y * Y, 0.0));
  return xc * Y + chord_integral(X, r) - chord_integral(xc, r);
}

// Signed version: the disk's area between the axes and (X, Y), signed by quadrant.
float corner_area(float X, float Y, float r) {
  return sign(X) * sign(Y) * quadrant_area(abs(X), abs(Y), r);
}

// Area of the kernel (centred at 0) inside the rectangle [x0, x1] x [y0, y1].
float kernel_rect_area(float x0, float x1, float y0, float y1, float r) {
  if (u_kernel == 1) return max(0.0, min(x1, r) - max(x0, -r)) * max(0.0, min(y1, r) - max(y0, -r));
  return corner_area(x1, y1, r) - corner_area(x0, y1, r) - corner_area(x1, y0, r) + corner_area(x0, y0, r);
}

float kernel_area(float r) { return u_kernel == 1 ? 4.0 * r * r : PI * r * r; }

// 1 where the shadow map's texel (i, j) lets the light through.
float texel_lit(int i, int j) {
  if (i < 0 || j < 0 || i >= u_map_texels || j >= u_map_texels) return 1.0;
  return texelFetch(u_depth, ivec2(i, j), 0).r < 0.5 ? 0.0 : 1.0;
}

float lit_at_map(vec2 q) {
  ivec2 t = ivec2(floor((q - u_map_origin_px) / u_texel_px));
  return texel_lit(t.x, t.y);
}

float lit_at_line(vec2 q) { return q.y >= u_line.x * q.x + u_line.y ? 1.0 : 0.0; }

// Area-weighted PCF over the shadow map: per texel row, the kernel area of each lit run.
float filter_map(vec2 q, float r) {
  vec2 lo = (q - r - u_map_origin_px) / u_texel_px;
  vec2 hi = (q + r - u_map_origin_px) / u_texel_px;
  int i0 = int(floor(lo.x)), i1 = int(floor(hi.x));
  int j0 = int(floor(lo.y)), j1 = int(floor(hi.y));
  float lit = 0.0;
  for (int j = j0; j <= j1; ++j) {
    float y0 = u_map_origin_px.y + float(j) * u_texel_px - q.y;
    float y1 = y0 + u_texel_px;
    int run_start = -1;
    for (int i = i0; i <= i1 + 1; ++i) {
      bool on = i <= i1 && texel_lit(i, j) > 0.5;
      if (on && run_start < 0) run_start = i;
      if (!on && run_start >= 0) {
        float x0 = u_map_origin_px.x + float(run_start) * u_texel_px - q.x;
        float x1 = u_map_origin_px.x + float(i) * u_texel_px - q.x;
        lit += kernel_rect_area(x0, x1, y0, y1, r);
        run_start = -1;
      }
    }
  }
  return lit / kernel_area(r);
}

// Antiderivative of clamp(u, 0, L).
float clamp_antiderivative(float u, float L) {
  if (u <= 0.0) return 0.0;
  if (u <= L) return 0.5 * u * u;
  return 0.5 * L * L + L * (u - L);
}

// The kernel's lit fraction against the original edge.
float filter_line(vec2 q, float r) {
  float m = u_line.x, b = u_line.y;
  if (u_kernel == 0) {
    // Signed distance of the pixel centre from the edge (positive on the lit side) -> the
    // circular segment on the occluded side.
    float s = (q.y - m * q.x - b) / sqrt(1.0 + m * m);
    if (s >= r) return 1.0;
    if (s <= -r) return 0.0;
    float segment = r * r * acos(s / r) - s * sqrt(r * r - s * s);
    return 1.0 - segment / (PI * r * r);
  }
  // Square: lit height of the column at x is clamp(q.y + r - (m (q.x + x) + b), 0, 2r), linear in x.
  float u_left = q.y + r - m * (q.x - r) - b;
  float u_right = q.y + r - m * (q.x + r) - b;
  float L = 2.0 * r;
  float lit = abs(m) < 1e-7 ? L * clamp(u_left, 0.0, L)
                             : (clamp_antiderivative(u_left, L) - clamp_antiderivative(u_right, L)) / m;
  return lit / (L * L);
}

float filter_taps(vec2 q, float r) {
  float sum = 0.0;
  for (int k = 0; k < u_tap_count; ++k) {
    vec2 p = q + u_taps[k] * r;
    sum += u_source == 0 ? lit_at_map(p) : lit_at_line(p);
  }
  return sum / float(u_tap_count);
}

void main() {
  vec2 q = u_to_canonical * (gl_FragCoord.xy - 0.5 * u_size_px);
  float r = u_radius_px;
  float v;
  if (u_kernel == 2) v = filter_taps(q, r);
  else v = u_source == 0 ? filter_map(q, r) : filter_line(q, r);
  o_visibility = clamp(v, 0.0, 1.0);
}
