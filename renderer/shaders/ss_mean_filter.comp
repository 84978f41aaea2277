// One axis of the edge-aware, viewpoint-invariant mean filter of EDTSM/EDTSSM: the box of width
// w_filter (world units) projected at the pixel's depth, w z_screen / z_eye pixels (Macedo &
// Apolinario eq. 2-3), clamped to u_max_width_px; the end pixels are weighted by the part of them
// the box covers, and neighbours on another surface (eye-depth test) are left out. The source
// carries (value, the G-buffer's signed depth), so one fetch per tap serves both; the target too.
layout(local_size_x = 8, local_size_y = 8) in;

#include "screen_space.glsl"

layout(binding = UNIT_POST_INPUT) uniform sampler2D u_source;  // value, signed eye depth
layout(binding = 0, rg32f) uniform writeonly image2D u_target;

uniform float u_filter_ws;
uniform float u_max_width_px;
uniform int u_axis;  // 0: x, 1: y

void main() {
  ivec2 size = textureSize(u_source, 0);
  ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (any(greaterThanEqual(p, size))) return;

  vec2 centre = texelFetch(u_source, p, 0).rg;
  if (centre.y == 0.0) {
    imageStore(u_target, p, vec4(centre, 0.0, 0.0));
    return;
  }
  float z = abs(centre.y);
  float half_px = 0.5 * min(u_filter_ws * px_per_ws(z), u_max_width_px);
  int reach = int(ceil(half_px - 0.5));
  ivec2 step = u_axis == 0 ? ivec2(1, 0) : ivec2(0, 1);
  float sum = 0.0, weight = 0.0;
  for (int k = -reach; k <= reach; ++k) {
    ivec2 q = p + k * step;
    if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, size))) continue;
    vec2 tap = texelFetch(u_source, q, 0).rg;
    if (tap.y == 0.0 || !same_surface(z, abs(tap.y))) continue;
    // Coverage of pixel k ([k - 1/2, k + 1/2]) by the box [-half_px, half_px].
    float w = max(0.0, min(float(k) + 0.5, half_px) - max(float(k) - 0.5, -half_px));
    sum += w * tap.x;
    weight += w;
  }
  imageStore(u_target, p, vec4(weight > 0.0 ? sum / weight : centre.x, centre.y, 0.0, 0.0));
}
