// Reduces the shading pass's per-pixel PCSS requirement (1 / filter radius in map uv, per cascade)
// to its maximum and counts, per cascade, the pixels that evaluated a filter, those whose radius
// was raised to the minimum penumbra, and those that need more than the largest map (Kreuzer 2017
// eq. 5.12: res = max over fragments of c / r_filter). Positive floats order like their bits, so
// atomicMax on the bits is a float max. One global atomic per workgroup and counter.
layout(local_size_x = 16, local_size_y = 16) in;

layout(binding = 0) uniform sampler2D u_requirement;  // (1 / r_uv or 0, cascade + 0.5 if clamped)
layout(std430, binding = 0) buffer Result {
  uint max_inverse_uv[4];
  uint evaluated[4];
  uint clamped[4];
  uint above_max[4];
};
uniform float u_limit_inverse_uv;  // max_texels / c: pixels above this are limited by the largest map

shared uint s_max[4];
shared uint s_evaluated[4];
shared uint s_clamped[4];
shared uint s_above[4];

void main() {
  uint lane = gl_LocalInvocationIndex;
  if (lane < 4u) {
    s_max[lane] = 0u;
    s_evaluated[lane] = 0u;
    s_clamped[lane] = 0u;
    s_above[lane] = 0u;
  }
  barrier();
  ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  ivec2 size = textureSize(u_requirement, 0);
  if (all(lessThan(p, size))) {
    vec2 r = texelFetch(u_requirement, p, 0).rg;
    if (r.x > 0.0) {
      int cascade = clamp(int(r.y), 0, 3);
      atomicMax(s_max[cascade], floatBitsToUint(r.x));
      atomicAdd(s_evaluated[cascade], 1u);
      if (fract(r.y) > 0.25) atomicAdd(s_clamped[cascade], 1u);
      if (r.x > u_limit_inverse_uv) atomicAdd(s_above[cascade], 1u);
    }
  }
  barrier();
  if (lane < 4u && s_evaluated[lane] > 0u) {
    atomicMax(max_inverse_uv[lane], s_max[lane]);
    atomicAdd(evaluated[lane], s_evaluated[lane]);
    atomicAdd(clamped[lane], s_clamped[lane]);
    atomicAdd(above_max[lane], s_above[lane]);
  }
}
