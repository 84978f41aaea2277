// One axis of an exact box blur of the VSM moments: output texel i averages [i+0.5-r, i+0.5+r]
// with the two edge texels weighted by coverage (the same box as the grid PCF). One invocation
// slides the window along a whole line, so the cost does not depend on r; the running sum is
// Kahan-compensated so that long lines keep the precision the variance needs.
layout(local_size_x = 64) in;

layout(binding = 0) uniform sampler2D u_source;
layout(binding = 0, rg32f) uniform writeonly image2D u_target;

uniform float u_radius_texels;
uniform int u_axis;      // 0: along x (one invocation per row), 1: along y
uniform ivec2 u_origin;  // the map's region in the atlas: u_size^2 texels from u_origin
uniform int u_size;

// Texel i of the line (clamped to the map's edge); `line` indexes rows for axis 0, columns for axis 1.
vec2 fetch(int i, int line, int len) {
  i = clamp(i, 0, len - 1);
  return texelFetch(u_source, u_origin + (u_axis == 0 ? ivec2(i, line) : ivec2(line, i)), 0).rg;
}

void store(int i, int line, vec2 v) {
  imageStore(u_target, u_origin + (u_axis == 0 ? ivec2(i, line) : ivec2(line, i)), vec4(v, 0.0, 0.0));
}

void main() {
  int len = u_size;
  int lines = u_size;
  int line = int(gl_GlobalInvocationID.x);
  if (line >= lines) return;

  float r = u_radius_texels;
  if (r <= 0.5) {  // the window lies inside one texel
    for (int i = 0; i < len; ++i) store(i, line, fetch(i, line, len));
    return;
  }
  // Window of texel i: [i + a, i + b]; full texels i+full_lo .. i+full_hi, partial ones at the ends.
  float a = 0.5 - r, b = 0.5 + r;
  int full_lo = int(ceil(a));
  int full_hi = int(floor(b)) - 1;
  float w_left = float(full_lo) - a;     // coverage of texel i + full_lo - 1
  float w_right = b - floor(b);          // coverage of texel i + full_hi + 1
  float norm = 1.0 / (2.0 * r);

  precise vec2 sum = vec2(0.0);
  precise vec2 comp = vec2(0.0);
  for (int j = full_lo; j <= full_hi; ++j) {
    precise vec2 y = fetch(j, line, len) - comp;
    precise vec2 t = sum + y;
    comp = (t - sum) - y;
    sum = t;
  }
  for (int i = 0; i < len; ++i) {
    vec2 total = sum + w_left * fetch(i + full_lo - 1, line, len) + w_right * fetch(i + full_hi + 1, line, len);
    store(i, line, total * norm);
    precise vec2 y = (fetch(i + full_hi + 1, line, len) - fetch(i + full_lo, line, len)) - comp;
    precise vec2 t = sum + y;
    comp = (t - sum) - y;
    sum = t;
  }
}
