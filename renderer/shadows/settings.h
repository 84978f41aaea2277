#pragma once
// Shadow settings, declared once. The shared sections (the shadow-map pass, adaptive resolution)
// live here; each technique's parameters and registry entry live in techniques/<name>.h and are
// listed once in technique_list.h. Every parameters struct is plain data; its table (name, unit,
// range, help) feeds the CLI, the ImGui panels, the JSON reports and shader defines, so there is
// no second list to keep in sync.
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include <penumbra/adaptive/resolution_rule.h>
#include <penumbra/published.h>
#include <penumbra/shadows/settings_table.h>
#include <penumbra/shadows/technique_list.h>

namespace penumbra::shadows {

#define PENUMBRA_ENUM(name, P) name,
enum class Technique : int { PENUMBRA_TECHNIQUES(PENUMBRA_ENUM) };
#undef PENUMBRA_ENUM
enum class Storage { subrect, realloc };
// How a frame's sun shadow is stored: maps or cascades (off), or a virtual shadow map whose pages
// each pixel marks on the level its filter asks for (rule) or its footprint alone (footprint).
enum class VirtualPages { off, rule, footprint };
enum class PcssRequirement { per_pixel, min_penumbra };

std::span<const std::string_view> technique_names();  // "hard", "pcf", ... (Technique order)
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
  // Skip the clusters of draw units whose bounds miss a map's sides (casters, per map or cascade)
  // and the draw units whose bounds miss the camera's view (scene/culling.h). The image is the same
  // either way; off draws every unit everywhere.
  bool culling = true;
  // The camera's depth first, in a depth-only pass, so that the shading pass shades each pixel's
  // visible surface once (depth test LEQUAL against it, no depth written) instead of every surface
  // drawn over it before: what engines do before forward shading. The virtual shadow map's
  // position pass and the screen-space techniques' G-buffer pass already leave that depth. The
  // image is the same but where two surfaces tie in depth (the last drawn shows, not the first).
  bool depth_prepass = true;
  // A virtual shadow map of the sun (shadows/virtual_shadow_map.h) instead of maps or cascades:
  // each pixel marks the pages of the coarsest clipmap level whose texel is at most
  // max(r / c, virtual_min_texel_px pixels) (rule, c = adaptive.c) or at most virtual_min_texel_px
  // pixels (footprint); only marked pages are drawn and stored. PCF with a world radius.
  VirtualPages virtual_pages = VirtualPages::off;
  // The pages' pixel floor: no page texel asked for finer than this many footprints of the pixel
  // asking (s, its world width at its depth); the levels' powers of two then give texels of half
  // the floor to the floor. Where the floor, not the rule, sets the level (the town seen from
  // above), a floor of 1 (texels of 0.5 to 1 s) shifts shadow edges and drops thin lit rims by a
  // pixel; the default 2^-0.5 (texels of 0.35 to 0.71 s) was the best of 1, 0.71 and 0.5 at equal
  // FLIP on the main job (docs/results/virtual-maps.md). Engines bias their levels finer too
  // (Unreal Engine 5.4: r.Shadow.Virtual.ResolutionLodBiasDirectional, -0.5). The virtual map's own,
  // not adaptive.min_texel_px: a page's floor is paid only where a pixel asks for it, a cascade's
  // over the whole cascade.
  float virtual_min_texel_px = 0.7071f;
  int virtual_pool_pages = 32;  // page slots per side of the pool (32² slots of 128² texels: 64 MiB)
  bool virtual_cache = true;    // keep drawn pages across frames (off: every marked page drawn every frame)
  // Depth bounds per tile of each drawn page (two planes around its depths, virtual_bounds.comp), with
  // which the filters skip a square surely lit or in umbra and PCSS's search one without blockers.
  // The image is the same either way, up to float rounding; off measures what they save.
  bool virtual_bounds = true;
  // A frame drawn anew (virtual_cache false) draws each page with the casters over the tiles (16²
  // texels) its pixels' squares reach only, not over the whole page (the marking's tiles, PageMarker;
  // PCSS's search pages are drawn again for the penumbrae's tiles they lack). The image is the same;
  // off measures what it saves. Cached pages are drawn whole: later frames read other tiles of them,
  // and drawing a page again for each new tile cost the main job's walking camera ten times the
  // triangles (docs/results/virtual-maps.md). So are the pages late marks draw (virtual_marks_late).
  bool virtual_page_tiles = true;
  // Draw the pages the previous frame marked, read a frame late, with a coarse floor over the
  // sun's region (adaptive::region_floor_pages) so that every pixel finds a page: no read-back is
  // waited for within a frame. A pixel whose page is not there yet (the first frame after a cut, a
  // pixel newly in view) reads a coarser resident level for a frame. Off: marked, read and drawn
  // within the frame.
  bool virtual_marks_late = false;
};

inline constexpr double kMinVisibility = 0.001;  // adaptive.visibility's range besides 0
inline constexpr double kMaxVisibility = 0.999;

// Adaptive resolution: res = c / r_uv (Kreuzer 2017 eq. 5.3/5.6) per map or cascade, clamped,
// quantized and rate-limited (adaptive/resolution_rule.h). Off: map.resolution_texels is used.
struct AdaptiveParams {
  bool enabled = false;
  // texels: from calibration.json, the radius per artifact at which the staircase is still detected
  // with the entry's criterion probability (not hidden), or at `visibility` when that is set.
  float c = static_cast<float>(kPublishedC);
  // The detection probability F the rule is for; 0 = the calibration entry's own criterion (in 2AFC
  // terms F* = 0.6465, 82 % correct). Lower is less visible and needs a larger filter radius per
  // texel (adaptive::c_at_visibility: about 1.9 c at F 0.10 with slope 3.5). Used when c comes from
  // the calibration file (an explicit --adaptive.c with it is refused). A double: a float made
  // 1e-45 .. 5e-324 the criterion's 0. Else in [kMinVisibility, kMaxVisibility]: below 0.1 % the
  // psychometric function is extrapolated far beyond any trial a study runs.
  double visibility = 0;
  // The limits and the hysteresis delay default to the library's (adaptive/resolution_rule.h):
  // one set of defaults for the tools and for an engine linking Penumbra::adaptive.
  int min_texels = adaptive::ResolutionLimits{}.min_texels;          // 32
  int max_texels = adaptive::ResolutionLimits{}.max_texels;          // 4096
  int quantum_texels = adaptive::ResolutionLimits{}.quantum_texels;  // 32
  // 30: frames a smaller requirement must hold before shrinking
  int shrink_delay_frames = adaptive::ResolutionController::Params{}.shrink_delay_frames;
  // The coarsest texel allowed, world units; 0 = the rule alone. The rule is measured on edges: a
  // caster narrower than a texel covers some texel centres and misses others, and its shadow
  // breaks up whatever the filter. Set it to the thinnest caster that must keep its shadow (the
  // outdoor crane's lattice: 0.06); each map then has at least L_ws / max_texel_ws texels.
  float max_texel_ws = 0;
  // The finest texel worth drawing, in pixel footprints at the map's nearest receiver (directional
  // lights); 0 = the rule alone. A texel narrower than the pixel it lands on cannot show a stair
  // (its stair is below the image's resolution), so a map (a far cascade) needs no more than
  // L_ws / (min_texel_px · footprint) texels, the footprint being the width one pixel covers at the
  // cascade's near split, facing the camera (the smallest it gets in the cascade). The texel
  // ceiling (max_texel_ws) wins over it.
  float min_texel_px = 0;
  Storage storage = Storage::subrect; // sub-rectangle of a max-size texture, or a texture per size
  PcssRequirement pcss = PcssRequirement::per_pixel;  // GPU max of c / r_filter (one frame late), or c / min penumbra
};

// Everything a frame needs to know about its shadows: the shared sections and one section per
// technique, named like it (s.pcf, s.pcss, ...; `hard` has no parameters).
struct ShadowSettings {
  Technique technique = Technique::pcf;
  ShadowMapParams map;
  AdaptiveParams adaptive;
#define PENUMBRA_SECTION(name, P) P name;
  PENUMBRA_TECHNIQUES(PENUMBRA_SECTION)
#undef PENUMBRA_SECTION
};

std::span<const Setting<ShadowMapParams>> settings_table(const ShadowMapParams*);
std::span<const Setting<AdaptiveParams>> settings_table(const AdaptiveParams*);

// A parameters struct with a table (the shared sections and every technique's).
template <class P>
concept SettingsSection = requires(const P* p) { settings_table(p); };

// Sets one row from its textual value ("2.5", "true", "poisson"); throws std::invalid_argument
// naming the key, the value and the accepted range or choices.
template <class P>
void set_from_string(const Setting<P>& s, P& params, std::string_view value);
template <class P>
std::string value_to_string(const Setting<P>& s, const P& params);

// {"key": value, ...} using the table; choices as strings.
template <SettingsSection P>
nlohmann::json to_json(const P& p);
nlohmann::json to_json(const ShadowSettings& s);

// Calls f(section, params) for every technique's parameters section ("pcf", s.pcf), ..., in
// technique order, so front ends need no list of their own. `hard` has no section.
template <class S, class F>
void for_each_technique_section(S& s, F&& f) {
#define PENUMBRA_VISIT(name, P) \
  if constexpr (!std::is_same_v<P, NoParams>) f(#name, s.name);
  PENUMBRA_TECHNIQUES(PENUMBRA_VISIT)
#undef PENUMBRA_VISIT
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

// The frame without a meaningful shadow, the physical floor a shadow's cost sits on: `base` with
// hard shadows from one 1×1 unfitted map (no cascades, no pages, no rule), so that the depth pass
// rasterizes into one texel and the shading pass does one lookup; everything else (camera,
// shading) as `base` has it. penumbra-bench and the main job time it beside each frame.
ShadowSettings unshadowed_floor(const ShadowSettings& base);

// The value of the technique's variant setting (PCF's kernel: "grid", "poisson"), or "" for a
// technique without one: with the technique's name, what calibration.json entries are keyed by.
std::string variant_choice(const ShadowSettings& s);
// Why a frame rendered with `s` never reads the shared setting `section`.`key` ("map",
// "virtual_pool_pages"), or "" when it may: the one list of what a configuration reads of the
// map and adaptive sections. A virtual shadow map reads no map size, fit or cascades and none of
// the rule's map limits; maps read no page pool; adaptive.visibility is read (as c) only where the
// rule sizes something. The apps refuse an option a configuration does not read from it.
std::string unread_setting(const ShadowSettings& s, std::string_view section, std::string_view key);
// Every value the technique's variant setting can take (PCF: disk, grid, poisson); empty for a
// technique without one.
std::vector<std::string> variant_choices(Technique t);
// Sets the technique's variant setting to `choice` (one of variant_choices); throws
// std::invalid_argument for another value or a technique without one.
void set_variant_choice(ShadowSettings& s, std::string_view choice);

}  // namespace penumbra::shadows
