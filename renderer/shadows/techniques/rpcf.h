#pragma once
// RPCF: the box PCF of the revectorized hard shadow (rbsm.h), each texel under the box
// integrated exactly (shaders/shadow_rbsm.glsl).
#include <penumbra/shadows/technique.h>

namespace penumbra::shadows {

struct RpcfParams {
  float radius = 2;                   // half side of the box, in `radius_unit`
  RadiusUnit radius_unit = RadiusUnit::texels;
  int max_grid_taps = 16;             // texels per axis before the box is strided
  int max_search_texels = 16;         // as RbsmParams
};
std::span<const Setting<RpcfParams>> settings_table(const RpcfParams*);

const TechniqueEntry& rpcf_technique();

}  // namespace penumbra::shadows
