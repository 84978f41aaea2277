#pragma once
// EDT shadow mapping (Macedo & Apolinario 2016), a screen-space technique (screen_space.h):
// hard shadows -> 3x3 sites -> exact EDT -> I = 1/2 -+ D/P for D <= P/2 (D in world units between
// G-buffer positions) -> edge-aware mean filter. Eye-depth differences are relative
// (|z_a - z_b| / min(z_a, z_b)) so one threshold serves every scene scale. Choices not fixed by the
// paper: docs/alternatives.md.
#include <penumbra/shadows/technique.h>

namespace penumbra::shadows {

struct EdtsmParams {
  ShadowInput input = ShadowInput::rbsm;  // the paper's: revectorized hard shadows (uses the rbsm table)
  float penumbra_ws = 0.2f;           // P: full fake-penumbra width, world units
  float filter_ws = 0.1f;             // w_filter: mean-filter width, world units (screen size w z_screen / z_eye)
  float depth_threshold = 0.05f;      // largest relative eye-depth difference treated as one surface
  int max_filter_px = 64;             // clamp of the mean filter's width in pixels
  bool edge_between_pixels = false;   // D from the silhouette between the site pixels (D + 1/2 px), not the site centre
};
std::span<const Setting<EdtsmParams>> settings_table(const EdtsmParams*);

const TechniqueEntry& edtsm_technique();

}  // namespace penumbra::shadows
