#pragma once
// Ground-truth visibility images for the bench, rendered through the public Renderer API.
//
// Two kinds of reference:
//   area_light   For techniques that approximate an area light's soft shadow (PCSS, EDT soft
//                shadows, erosion soft shadows): ray-traced where asked (ReferenceOptions::
//                ray_traced, a directional light, a build with Embree: ray_traced.h), else the mean of
//                N hard shadows, each from a point light placed on a stratified sample of the
//                emitter, every map fitted and high-resolution (4096² by default). The emitter
//                follows the scene's light conventions (scene/scene.h):
//                  directional light of angular diameter θ = light.size degrees: directions
//                    d + tan(θ/2)·(u e1 + v e2), normalized, for (u, v) uniform in the unit disk
//                    and e1, e2 perpendicular to d (uniform over the disk the PCSS formula
//                    assumes; for the small angles of a sun, uniform in solid angle too);
//                  spot light of width W = light.size: positions p + (W/2)(u e1 + v e2) on the
//                    disk perpendicular to the axis, direction unchanged.
//                The spot's cone factor is evaluated per sample, so within W/2 of the cone's
//                edge the reference averages the cone as well (the built-in scenes keep their
//                receivers well inside it).
//   same_filter  For fixed-radius filters and everything else (hard, PCF, VSM, EDTSM's fixed
//                world-space penumbra): the same settings on an 8192²
//                map (clamped to GL_MAX_TEXTURE_SIZE, halved while the device refuses the
//                allocation; either is reported in `note`). A filter radius is only "the same
//                filter" at another resolution when it is given in world units
//                (radius_unit = world); the bench sets that.
#include <string>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>

#include "io/image_io.h"
#include "scene/scene.h"
#include "shadows/renderer.h"
#include "shadows/settings.h"
#include "shadows/technique.h"

namespace penumbra::metrics {

class RayTracedScene;

using shadows::ReferenceKind;  // declared by each technique's registry entry (shadows/technique.h)
std::string_view to_string(ReferenceKind k);

// Which reference a technique is measured against: its registry entry's (TechniqueEntry::reference).
ReferenceKind reference_kind(std::string_view technique_name);

// Shirley and Chiu's concentric map from [-1, 1]² to the unit disk (area-preserving).
glm::vec2 concentric_disk(glm::vec2 square);

// per_side² points in the unit disk: one jittered point per cell of a per_side × per_side grid
// of strata of the unit square, mapped by Shirley and Chiu's area-preserving concentric map so
// every stratum keeps its share of the disk. The jitter comes from a fixed-seed generator with
// its own integer-to-float conversion: identical on every platform and run.
std::vector<glm::vec2> stratified_disk(int per_side);

// The scene's light as a point emitter at unit-disk position `uv` of its area (see above).
scene::Light light_sample(const scene::Light& light, glm::vec2 uv);

struct ReferenceOptions {
  int area_samples = 64;                  // area light: point-light samples, rounded up to a square
  int area_resolution_texels = 4096;      // area light: each hard, fitted shadow map
  int filter_resolution_texels = 8192;    // same filter: the reference map
  // Area light, directional, built with Embree (PENUMBRA_HAS_RAY_TRACING): ray-traced visibility
  // (ray_traced.h: area_samples shadow rays per pixel, no map, no bias) instead of the maps' mean.
  bool ray_traced = false;
  const RayTracedScene* traced = nullptr;  // with ray_traced: this scene's structure (else one is built per call)
};

struct Reference {
  io::ImageF visibility;                  // one channel, the image size asked for
  ReferenceKind kind = ReferenceKind::same_filter;
  int resolution_texels = 0;              // shadow-map size actually used (0: ray-traced)
  bool ray_traced = false;                // area light: ray-traced (ray_traced.h), not a mean of maps
  int samples = 1;                        // area light: point-light samples averaged
  std::string note;                       // why the resolution differs from the one asked for, if it does
  std::string description;                // one line: what was rendered
  double render_ms = 0;                   // wall time spent building it
};

// The mean visibility of `per_side`² hard shadows from point lights sampled over the scene
// light's area, each map `resolution_texels` wide (clamped like the same-filter reference),
// fitted, with `map`'s biases. The renderer's scene light is restored afterwards.
io::ImageF area_light_visibility(shadows::Renderer& renderer, int width_px, int height_px, int per_side,
                                 int resolution_texels, const shadows::ShadowMapParams& map);

// The reference for `settings` (its technique picks the kind) at width × height pixels.
Reference make_reference(shadows::Renderer& renderer, const shadows::ShadowSettings& settings, int width_px, int height_px,
                         const ReferenceOptions& options = {});

}  // namespace penumbra::metrics
