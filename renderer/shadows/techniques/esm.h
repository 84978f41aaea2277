#pragma once
// Exponential shadow maps (Annen, Mertens, Seidel, Flerackers & Kautz 2008, "Exponential Shadow
// Maps", GI): the shadow test s(d, z) = [d <= z] approximated by exp(-c (d - z)) =
// exp(c z) exp(-c d), which separates, so the map stores exp(c z) of the occluders' normalized
// linear depth z, box-blurred like VSM, and a receiver at depth d reads
// clamp(E[exp(c z)] exp(-c d), 0, 1) (shaders/shadow_esm.glsl). The clamp is the paper's: a
// receiver in front of its filtered occluders (d < z, non-planar receivers) would exceed 1.
#include <penumbra/shadows/technique.h>

namespace penumbra::shadows {

struct EsmParams {
  float radius = 2;                   // box-blur radius of exp(c z), in `radius_unit`
  RadiusUnit radius_unit = RadiusUnit::texels;
  float exponent = 77;                // c: larger is sharper and leaks less; clamped to kEsmMaxExponent
};
std::span<const Setting<EsmParams>> settings_table(const EsmParams*);

// The largest c stored: exp(c) of the far plane, summed over a blur window of up to 2^16 texels
// (direct sums), stays below the float32 maximum 3.4e38 (exp(77) * 65536 = 1.8e38).
inline constexpr float kEsmMaxExponent = 77;
float esm_exponent(const EsmParams& p);  // c clamped to [0, kEsmMaxExponent]

const TechniqueEntry& esm_technique();

}  // namespace penumbra::shadows
