#pragma once
// Percentage-closer filtering (Reeves et al. 1987): the mean of the depth test over a fixed
// box of whole texels (grid, coverage-weighted), a rotated Poisson disk, or the exact disk of whole
// texels (disk, coverage-weighted: the ideal filter the perception studies use) (shaders/shadow_pcf.glsl).
#include <penumbra/shadows/technique.h>

namespace penumbra::shadows {

struct PcfParams {
  float radius = 2;                   // filter radius, in `radius_unit`
  RadiusUnit radius_unit = RadiusUnit::texels;
  // disk by default: the kernel the study's shipped configs draw, which the published calibration
  // entry assumes, so the c the adaptive rule uses was measured for it.
  Kernel kernel = Kernel::disk;
  int poisson_taps = 25;
  bool rotate = true;                 // per-pixel random rotation of the Poisson disk
  int max_grid_taps = 32;             // per axis; larger kernels are sampled with a stride
};
std::span<const Setting<PcfParams>> settings_table(const PcfParams*);

const TechniqueEntry& pcf_technique();

}  // namespace penumbra::shadows
