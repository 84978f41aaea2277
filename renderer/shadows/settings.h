#pragma once
// Technique parameters, declared once. Each parameters struct is plain data; its table below
// (name, unit, range, help) feeds the CLI, the ImGui panels, the JSON reports and shader defines,
// so there is no second list to keep in sync.
#include <span>
#include <string>
#include <string_view>

#include <nlohmann/json_fwd.hpp>

namespace penumbra::shadows {

enum class Technique { hard, pcf, pcss, vsm, edtsm, edtssm, erosion, rbsm, rpcf, msm, evsm };
enum class Kernel { grid, poisson };
enum class RadiusUnit { texels, world };
enum class ShadowInput { hard, rbsm };  // the input shadows of EDTSM / EDTSSM
enum class MomentFormat { rgba32f, rgba16f };
enum class Storage { subrect, realloc };
enum class PcssRequirement { per_pixel, min_penumbra };

std::span<const std::string_view> technique_names();  // "hard", "pcf", ..., "msm", "evsm" (Technique order)
std::string_view to_string(Technique t);
Technique technique_from_string(std::string_view name);  // throws std::invalid_argument

// Shadow-map pass and biases, shared by every technique.
struct ShadowMapParams {
  int resolution_texels = 2048;
  bool fit = true;                    // fit the light frustum to the potential receivers L ∩ V ∩ S
  float slope_bias = 1.5f;            // glPolygonOffset factor (depth slopes)
  float offset_bias = 4.0f;           // glPolygonOffset units (smallest depth steps)
  float normal_offset_texels = 0.75f; // lookup moved along the normal, in texels at the receiver
  float depth_bias_texels = 0.5f;     // receiver moved toward the light by this many texel widths
  bool receiver_plane_bias = true;    // per-tap depth from the receiver's depth gradient
  // Cascades (directional lights, shadow-map techniques): 1 = one map; 2..4 = that many; 0 = as
  // few as the resolution rule allows for the view (adaptive/cascades.h).
  int cascades = 1;
  float cascade_lambda = 0.75f;       // split scheme: 0 uniform, 1 logarithmic, between: practical
  float cascade_blend = 0.1f;         // blend band at a cascade's far end, fraction of its depth range
  bool cascade_stabilize = true;      // window size in quarter-octave steps, corner snapped to texels
};

// Adaptive resolution: res = c / r_uv (Kreuzer 2017 eq. 5.3/5.6) per map or cascade, clamped,
// quantized and rate-limited (adaptive/resolution_rule.h). Off: map.resolution_texels is used.
struct AdaptiveParams {
  bool enabled = false;
  float c = 3.47f;                    // texels; from calibration.json
  int min_texels = 32;
  int max_texels = 4096;
  int quantum_texels = 32;
  int shrink_delay_frames = 30;       // frames a smaller requirement must hold before shrinking
  Storage storage = Storage::subrect; // sub-rectangle of a max-size texture, or a texture per size
  PcssRequirement pcss = PcssRequirement::per_pixel;  // GPU max of c / r_filter (one frame late), or c / min penumbra
};

struct PcfParams {
  float radius = 2;                   // filter radius, in `radius_unit`
  RadiusUnit radius_unit = RadiusUnit::texels;
  Kernel kernel = Kernel::poisson;
  int poisson_taps = 25;
  bool rotate = true;                 // per-pixel random rotation of the Poisson disk
  int max_grid_taps = 32;             // per axis; larger kernels are sampled with a stride
};

struct PcssParams {
  Kernel kernel = Kernel::poisson;
  int blocker_taps = 25;
  int filter_taps = 25;
  float min_penumbra_ws = 0.01f;      // smallest filter radius, world units at the receiver
  float search_scale = 1.0f;          // blocker-search radius relative to its geometric bound
  int max_grid_taps = 32;
};

struct VsmParams {
  float radius = 2;                   // box-blur radius of the moments, in `radius_unit`
  RadiusUnit radius_unit = RadiusUnit::texels;
  float min_variance = 1e-6f;         // in normalized depth²
  float bleed_reduction = 0.2f;       // p below this maps to 0, rest rescaled to [0, 1]
};

// Screen-space techniques (renderer/shadows/screen_space.h; choices in docs/alternatives.md).
// Eye-depth differences are relative (|z_a - z_b| / min(z_a, z_b)) so one threshold serves every
// scene scale.

// EDT shadow mapping (Macedo & Apolinario 2016): hard shadows -> 3x3 sites -> exact EDT ->
// I = 1/2 -+ D/P for D <= P/2 (D in world units between G-buffer positions) -> edge-aware mean filter.
struct EdtsmParams {
  ShadowInput input = ShadowInput::rbsm;  // the paper's: revectorized hard shadows (uses the rbsm table)
  float penumbra_ws = 0.2f;           // P: full fake-penumbra width, world units
  float filter_ws = 0.1f;             // w_filter: mean-filter width, world units (screen size w z_screen / z_eye)
  float depth_threshold = 0.05f;      // largest relative eye-depth difference treated as one surface
  int max_filter_px = 64;             // clamp of the mean filter's width in pixels
  bool edge_between_pixels = false;   // D from the silhouette between the site pixels (D + 1/2 px), not the site centre
};

// EDT soft shadows (Macedo & Apolinario 2017): PCSS blocker search at silhouette pixels only ->
// w_p = w_light (z_R - z_avg) / z_avg -> EDT propagates w_p -> alpha = 1/2 -+ d / (beta w_p) -> mean filter.
struct EdtssmParams {
  ShadowInput input = ShadowInput::rbsm;
  float beta = 1.0f;                  // penumbra scale (w_p is in world units here; the paper's 750 was for light-space units)
  int blocker_taps = 25;              // Poisson taps of the blocker search at silhouette pixels
  float search_scale = 1.0f;          // blocker-search radius over its geometric bound
  float filter_ws = 0.05f;            // w_filter, world units
  float depth_threshold = 0.05f;
  int max_filter_px = 64;
  bool edge_between_pixels = false;
};

// Contact-hardening soft shadows by erosion (Klein, Nischwitz & Obermeier 2012): hard shadows ->
// 4-neighbour Laplacian edges with their penumbra width -> min-max mip-map erosion -> PCF scaled
// by the eroded width.
struct ErosionParams {
  int taps = 32;                      // Poisson taps of the final PCF (published: 32)
  int blocker_taps = 25;              // Poisson taps of the blocker search at edge pixels
  float search_scale = 1.0f;
  int max_search_px = 128;            // clamp of the erosion's search radius, pixels
  bool rotate = true;                 // rotate the PCF disk per pixel
  float depth_threshold = 0.05f;      // edges only between pixels of one surface
};

// Revectorization-based shadow mapping (Macedo & Apolinario 2016): hard shadows whose texel
// staircase is replaced by the line through the steps' risers (docs/alternatives.md).
struct RbsmParams {
  int max_search_texels = 16;         // texels walked along a silhouette step in each direction
};

// RPCF: the box PCF of the revectorized hard shadow, each texel under the box integrated exactly.
struct RpcfParams {
  float radius = 2;                   // half side of the box, in `radius_unit`
  RadiusUnit radius_unit = RadiusUnit::texels;
  int max_grid_taps = 16;             // texels per axis before the box is strided
  int max_search_texels = 16;         // as RbsmParams
};

// Moment shadow maps (Peters & Klein 2015), Hamburger 4MSM on plain RGBA32F moments.
struct MsmParams {
  float radius = 2;                   // box-blur radius of the moments, in `radius_unit`
  RadiusUnit radius_unit = RadiusUnit::texels;
  float moment_bias = 3e-5f;          // alpha: b' = (1 - alpha) b + alpha (0, 0.63, 0, 0.63)
  float depth_bias = 0;               // subtracted from the receiver's depth in [-1, 1]
  float bleed_reduction = 0;          // visibility below this maps to 0, rest rescaled to [0, 1]
};

// Exponential variance shadow maps (Lauritzen & McCool 2008): VSM of exp(c+ x) and -exp(-c- x).
struct EvsmParams {
  float radius = 2;                   // box-blur radius of the moments, in `radius_unit`
  RadiusUnit radius_unit = RadiusUnit::texels;
  MomentFormat format = MomentFormat::rgba32f;
  float positive_exponent = 40;       // c+, clamped to the format's limit (42 float32, 5.54 float16)
  float negative_exponent = 5;        // c-, clamped likewise
  float min_variance = 1e-6f;         // in normalized depth^2, carried through the warp's slope
  float bleed_reduction = 0;          // as VsmParams
};

// Everything a frame needs to know about its shadows.
struct ShadowSettings {
  Technique technique = Technique::pcf;
  ShadowMapParams map;
  AdaptiveParams adaptive;
  PcfParams pcf;
  PcssParams pcss;
  VsmParams vsm;
  EdtsmParams edtsm;
  EdtssmParams edtssm;
  ErosionParams erosion;
  RbsmParams rbsm;
  RpcfParams rpcf;
  MsmParams msm;
  EvsmParams evsm;
};

enum class SettingType { real, integer, boolean, choice };

// One row of a parameters table. get/set go through double so every front end handles a row the
// same way; choices are stored as their index.
template <class P>
struct Setting {
  std::string_view key;
  std::string_view unit;
  SettingType type;
  double min;
  double max;
  std::string_view help;
  double (*get)(const P&);
  void (*set)(P&, double);
  std::span<const std::string_view> choices = {};
};

std::span<const Setting<ShadowMapParams>> settings_table(const ShadowMapParams*);
std::span<const Setting<PcfParams>> settings_table(const PcfParams*);
std::span<const Setting<PcssParams>> settings_table(const PcssParams*);
std::span<const Setting<VsmParams>> settings_table(const VsmParams*);
std::span<const Setting<AdaptiveParams>> settings_table(const AdaptiveParams*);
std::span<const Setting<EdtsmParams>> settings_table(const EdtsmParams*);
std::span<const Setting<EdtssmParams>> settings_table(const EdtssmParams*);
std::span<const Setting<ErosionParams>> settings_table(const ErosionParams*);
std::span<const Setting<RbsmParams>> settings_table(const RbsmParams*);
std::span<const Setting<RpcfParams>> settings_table(const RpcfParams*);
std::span<const Setting<MsmParams>> settings_table(const MsmParams*);
std::span<const Setting<EvsmParams>> settings_table(const EvsmParams*);

// Sets one row from its textual value ("2.5", "true", "poisson"); throws std::invalid_argument
// naming the key, the value and the accepted range or choices.
template <class P>
void set_from_string(const Setting<P>& s, P& params, std::string_view value);
template <class P>
std::string value_to_string(const Setting<P>& s, const P& params);

// {"key": value, ...} using the table; choices as strings.
nlohmann::json to_json(const ShadowSettings& s);
nlohmann::json to_json(const ShadowMapParams& p);
nlohmann::json to_json(const PcfParams& p);
nlohmann::json to_json(const PcssParams& p);
nlohmann::json to_json(const VsmParams& p);
nlohmann::json to_json(const AdaptiveParams& p);
nlohmann::json to_json(const EdtsmParams& p);
nlohmann::json to_json(const EdtssmParams& p);
nlohmann::json to_json(const ErosionParams& p);
nlohmann::json to_json(const RbsmParams& p);
nlohmann::json to_json(const RpcfParams& p);
nlohmann::json to_json(const MsmParams& p);
nlohmann::json to_json(const EvsmParams& p);

// Calls f(section, params) for every technique's parameters section ("pcf", s.pcf), ..., in
// technique order, so front ends need no list of their own. `hard` has no section.
template <class S, class F>
void for_each_technique_section(S& s, F&& f) {
  f("pcf", s.pcf);
  f("pcss", s.pcss);
  f("vsm", s.vsm);
  f("edtsm", s.edtsm);
  f("edtssm", s.edtssm);
  f("erosion", s.erosion);
  f("rbsm", s.rbsm);
  f("rpcf", s.rpcf);
  f("msm", s.msm);
  f("evsm", s.evsm);
}

// Calls f(section, params) for the section of `s.technique`; not at all for `hard`.
template <class S, class F>
void visit_technique_section(S& s, F&& f) {
  const std::string_view name = to_string(s.technique);
  for_each_technique_section(s, [&](std::string_view section, auto& params) {
    if (section == name) f(section, params);
  });
}


// The parameters relevant to `s.technique`, as "section.key=value" pairs (for names and reports).
std::string describe(const ShadowSettings& s);

}  // namespace penumbra::shadows
