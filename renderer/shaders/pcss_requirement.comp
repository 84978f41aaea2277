// Reduces the shading pass's per-pixel PCSS requirement (1 / filter radius in map uv, per cascade)
// to its maximum and counts, per cascade, the pixels that evaluated a filter, those whose radius
// was raised to the minimum penumbra, and those that need more than the largest map (Kreuzer 2017
// eq. 5.12: res = max over fragments of c / r_filter). Positive floats order like their bits, so
// atomicMax on the bits is a float max. One global atomic per workgroup and counter; a workgroup
// covers PCSS_REQUIREMENT_GROUP_PIXELS² pixels (the renderer dispatches that many fewer groups
// per axis); the result's layout is the contract's PcssRequirementResult.
#define PENUMBRA_PCSS_REQUIREMENT_RESULT
#include "shadow_contract.h"

layout(local_size_x = 16, local_size_y = 16) in;

layout(binding = 0) uniform sampler2D u_requirement;  // (1 / r_uv or 0, cascade + 0.5 if clamped)
uniform float u_limit_inverse_uv;  // max_texels / c: pixels above this are limited by the largest map

shared uint s_max[MAX_CASCADES];
shared uint s_evaluated[MAX_CASCADES];
shared uint s_clamped[MAX_CASCADES];
shared uint s_above[MAX_CASCADES];

// Each invocation reduces a BLOCK x BLOCK square of pixels in registers first, so that shared
// atomics and workgroup barriers (costly on software GL) are paid per 16 pixels, not per pixel.
const int BLOCK = PCSS_REQUIREMENT_GROUP_PIXELS / 16;

void main() {
  uint lane = gl_LocalInvocationIndex;
  if (lane < uint(MAX_CASCADES)) {
    s_max[lane] = 0u;
    s_evaluated[lane] = 0u;
    s_clamped[lane] = 0u;
    s_above[lane] = 0u;
  }
  barrier();
  uint m[MAX_CASCADES], e[MAX_CASCADES], c[MAX_CASCADES], a[MAX_CASCADES];
  for (int k = 0; k < MAX_CASCADES; ++k) m[k] = e[k] = c[k] = a[k] = 0u;
  ivec2 size = textureSize(u_requirement, 0);
  ivec2 origin = ivec2(gl_GlobalInvocationID.xy) * BLOCK;
  for (int y = 0; y < BLOCK; ++y)
    for (int x = 0; x < BLOCK; ++x) {
      ivec2 p = origin + ivec2(x, y);
      if (any(greaterThanEqual(p, size))) continue;
      vec2 r = texelFetch(u_requirement, p, 0).rg;
      if (r.x <= 0.0) continue;
      int k = clamp(int(r.y), 0, MAX_CASCADES - 1);
      m[k] = max(m[k], floatBitsToUint(r.x));
      e[k] += 1u;
      if (fract(r.y) > 0.25) c[k] += 1u;
      if (r.x > u_limit_inverse_uv) a[k] += 1u;
    }
  for (int k = 0; k < MAX_CASCADES; ++k) {
    if (e[k] == 0u) continue;
    atomicMax(s_max[k], m[k]);
    atomicAdd(s_evaluated[k], e[k]);
    atomicAdd(s_clamped[k], c[k]);
    atomicAdd(s_above[k], a[k]);
  }
  barrier();
  if (lane < uint(MAX_CASCADES) && s_evaluated[lane] > 0u) {
    atomicMax(max_inverse_uv[lane], s_max[lane]);
    atomicAdd(evaluated[lane], s_evaluated[lane]);
    atomicAdd(clamped[lane], s_clamped[lane]);
    atomicAdd(above_max[lane], s_above[lane]);
  }
}
