#pragma once
// Contact-hardening soft shadows by erosion (Klein, Nischwitz & Obermeier 2012), screen space:
// hard shadows -> 4-neighbour Laplacian edges with their penumbra width -> min-max mip-map erosion
// -> PCF scaled by the eroded width.
#include <penumbra/shadows/technique.h>

namespace penumbra::shadows {

struct ErosionParams {
  int taps = 32;                      // Poisson taps of the final PCF (published: 32)
  int blocker_taps = 25;              // Poisson taps of the blocker search at edge pixels
  float search_scale = 1.0f;
  int max_search_px = 128;            // clamp of the erosion's search radius, pixels
  bool rotate = true;                 // rotate the PCF disk per pixel
  float depth_threshold = 0.05f;      // edges only between pixels of one surface
};
std::span<const Setting<ErosionParams>> settings_table(const ErosionParams*);

const TechniqueEntry& erosion_technique();

}  // namespace penumbra::shadows
