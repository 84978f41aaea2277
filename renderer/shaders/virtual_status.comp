// Counts the shading pass's pixels by where they found their virtual-map pages (o_virtual_status: 1 on
// the level they marked, 2 on a coarser resident level, 3 none, 0 no surface) into the contract's
// VirtualShadingResult. Each invocation sums a BLOCK × BLOCK square in registers, the workgroup in
// shared memory, and one global atomic per counter and workgroup: per-fragment atomics on three
// counters serialised the shading pass on software GL (2.6x its time). A workgroup covers
// VIRTUAL_STATUS_GROUP_PIXELS² pixels.
#define PENUMBRA_VIRTUAL_SHADING_RESULT
#include "shadow_contract.h"

layout(local_size_x = 16, local_size_y = 16) in;
layout(binding = 0, r8ui) uniform readonly uimage2D u_status;

shared uint s_counts[3];

const int BLOCK = VIRTUAL_STATUS_GROUP_PIXELS / 16;

void main() {
  if (gl_LocalInvocationIndex < 3u) s_counts[gl_LocalInvocationIndex] = 0u;
  barrier();
  const ivec2 size = imageSize(u_status);
  const ivec2 origin = ivec2(gl_WorkGroupID.xy) * VIRTUAL_STATUS_GROUP_PIXELS + ivec2(gl_LocalInvocationID.xy) * BLOCK;
  uvec3 counts = uvec3(0u);
  for (int y = 0; y < BLOCK; ++y)
    for (int x = 0; x < BLOCK; ++x) {
      const ivec2 p = origin + ivec2(x, y);
      if (any(greaterThanEqual(p, size))) continue;
      const uint status = imageLoad(u_status, p).r;
      if (status >= 1u && status <= 3u) counts[status - 1u] += 1u;
    }
  for (int k = 0; k < 3; ++k)
    if (counts[k] > 0u) atomicAdd(s_counts[k], counts[k]);
  barrier();
  if (gl_LocalInvocationIndex == 0u) {
    if (s_counts[0] > 0u) atomicAdd(at_level, s_counts[0]);
    if (s_counts[1] > 0u) atomicAdd(coarser, s_counts[1]);
    if (s_counts[2] > 0u) atomicAdd(none, s_counts[2]);
  }
}
