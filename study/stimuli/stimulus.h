#pragma once
// 2AFC stimuli drawn by the shadow renderer's own techniques (stimulus_scene, stimulus_settings):
// an occluder whose straight edge is the original line casts into an unfitted shadow map whose
// texels are `artifact_px` stimulus pixels wide, and the receiver (a white plane seen
// orthographically, 1 world unit = 1 screen pixel, light straight down) is shaded by the
// technique with its filter radius set to `filter_radius_px`. The artifact-free partner is the
// same filter over the original edge (partner_for). A spec without a technique (the study's
// earlier kernel field) is drawn by the renderer's PCF with that kernel (as_renderer_pcf).
//
// Light levels: `lit_linear` is the lit receiver's level in *linear light* as a fraction of the
// display's white luminance (1.0 = full contrast, 0.5 = half the luminance). The GL pass computes
// visibility in linear light; `encode` applies the display's transfer function once, on the CPU,
// and the resulting 8-bit values are what is shown and what the PNGs hold.
#include <cstdint>
#include <memory>
#include <string>

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

#include "io/image_io.h"
#include "scene/scene.h"
#include "shadows/settings.h"
#include "stimuli/stimulus_spec.h"

namespace penumbra::stimuli {

// Everything random about one stimulus, derived from spec.seed. Canonical frame: stimulus px,
// origin at the stimulus centre, y up; the edge is y = line_m x + line_b with the occluder below.
struct Geometry {
  int orientation = 0;          // 0..7: rotation by 90° * (orientation % 4), mirrored when >= 4
  glm::dmat2 to_canonical{1.0}; // screen offset from the centre (y up) -> canonical
  double line_m = 0, line_b = 0;
  glm::dvec2 map_origin_px{0};  // canonical position of shadow-map texel (0, 0)'s lower-left corner
  int map_texels = 0;           // per side
  double poisson_rotation = 0;  // radians
};
Geometry make_geometry(const StimulusSpec& spec);

// Linear light in [0, 1] -> 8-bit display value through the transfer function: the one place the
// display's transfer is applied. For a measured transfer, linear light is the fraction of the way
// from the monitor's black to its white luminance, and the level is the one whose measured
// luminance is nearest (display::DisplayCalibration::encode). decode is the inverse (for a
// measured transfer: the level's relative luminance under the calibration's model).
std::uint8_t encode(double linear, const Transfer& transfer);
double decode(std::uint8_t value, const Transfer& transfer);

struct StimulusPair {
  Geometry geometry;
  io::ImageF artifact_visibility;  // linear visibility in [0, 1], top row first
  io::ImageF line_visibility;
  io::Image8 artifact;  // one channel, encoded: exactly the displayed values
  io::Image8 line;
};

nlohmann::json to_json(const StimulusSpec& spec, const Geometry& geometry);

// Stimuli drawn by the renderer's own technique (spec.technique set). The scene: a white receiver
// square in y = 0 that is exactly the shadow map's footprint (so the unfitted map's texel is
// `artifact_px` wide, at the trial's grid phase), the occluder's polygon (the part of that square
// below the edge, in the canonical frame turned to the screen by the trial's orientation) above
// it, a directional light straight down, and an orthographic camera between the two looking down
// with 1 world unit = 1 stimulus pixel (world x = screen x, world -z = screen y, origin at the
// stimulus centre).
scene::Scene stimulus_scene(const StimulusSpec& spec, const Geometry& geometry);
// The renderer settings that draw it: the technique and its settings (spec.technique_settings,
// penumbra-render's keys), one unfitted map of geometry.map_texels, no adaptive rule, and the
// technique's filter radius set to filter_radius_px / artifact_px texels. Throws
// std::invalid_argument naming "technique" or the setting ("pcf.kernel: ...") for a technique
// that cannot be studied or a setting the study controls itself (the radius, the map's size, fit,
// cascades, the adaptive rule).
// `texel_px` (0: artifact_px) is the map's texel when the map is not the trial's (the partner's
// finer one over the same square).
shadows::ShadowSettings stimulus_settings(const StimulusSpec& spec, int map_texels, double texel_px = 0);

// The artifact-free partner: the same technique with the same radius in px over the original edge.
enum class PartnerMethod {
  box_integral,  // box kernels (PCF grid, RPCF: revectorizing a straight edge gives it back): closed form
  disk_integral, // PCF disk: the circular segment beyond the edge, closed form
  edge_taps,     // PCF Poisson, unrotated: each of the renderer's taps tested against the edge
  fine_map,      // filtered moments (VSM, MSM, EVSM, ESM): the technique itself on a map of
                 // fine_map_texels over the same square (its blur costs the same at any radius)
};
// Throws std::invalid_argument ("technique: ..." or "pcf.rotate: ...") when there is none.
PartnerMethod partner_for(const shadows::ShadowSettings& settings);
// "" when partner_for has one, else its reason.
std::string partner_unavailable(const shadows::ShadowSettings& settings);
// The technique a spec without one is drawn with: the renderer's PCF with the spec's kernel (disk,
// grid, or poisson with poisson_taps taps, unrotated); a spec with a technique as it is.
StimulusSpec as_renderer_pcf(const StimulusSpec& spec);
// The fine map's texels: its texel min(a, r) / 64, at most kMaxFineMapTexels per side. The
// moments techniques' edge sits a quarter texel off the line (it moves with the texel), so the
// partner's map must be finer than its staircase alone needs: at min(a, r) / 16 the partner
// moved by 2 linear 8-bit levels when the map was halved again, at / 64 by under one.
inline constexpr int kMaxFineMapTexels = 4096;
int fine_map_texels(const StimulusSpec& spec, const Geometry& geometry);

// Needs a current OpenGL 4.5 context (headless or windowed).
class StimulusRenderer {
 public:
  StimulusRenderer();
  ~StimulusRenderer();
  StimulusRenderer(const StimulusRenderer&) = delete;
  StimulusRenderer& operator=(const StimulusRenderer&) = delete;

  StimulusPair render(const StimulusSpec& spec);
  // The same with a given geometry (e.g. make_geometry(spec) with the straight partner's line
  // moved); the shadow map must cover the stimulus plus the radius, as make_geometry's does.
  StimulusPair render(const StimulusSpec& spec, const Geometry& geometry);
  // The shadow map of the last render: 1 = lit texel, 0 = occluded, row 0 = canonical bottom,
  // indexed in the canonical frame.
  const std::vector<std::uint8_t>& last_shadow_map() const { return last_map_; }

 private:
  StimulusPair render_with_technique(const StimulusSpec& spec, const Geometry& geometry);
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::vector<std::uint8_t> last_map_;
};

}  // namespace penumbra::stimuli
