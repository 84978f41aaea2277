#pragma once
// A technique's registry entry: everything the frame, the front ends and the bench need to know
// about one shadow technique, declared in the technique's own file (techniques/<name>.{h,cpp})
// and listed once in technique_list.h. The enum, the names, the settings sections, the GUI/CLI/JSON
// tables and the template instantiations are all made from that list; code outside the technique
// files asks the entry instead of switching over techniques.
//
// Radius units: a fixed filter (a box or disk the same size everywhere) states its radius in
// shadow-map texels or world units at the receiver (FilterRadius); PCSS-like techniques have no
// fixed radius, the adaptive rule then works from `rule_radius_ws`.
#include <optional>
#include <string_view>
#include <vector>

#include <penumbra/shadows/moments.h>
#include <penumbra/shadows/settings_table.h>

namespace penumbra::gl {
class Program;
class Texture;
struct ShaderDefine;
}  // namespace penumbra::gl

namespace penumbra::shadows {

enum class Technique : int;
struct ShadowSettings;
class ScreenSpace;
struct PostPassContext;

struct FilterRadius {
  float radius = 0;
  RadiusUnit unit = RadiusUnit::texels;
};

// How the bench's ground truth for a technique is made (metrics/ground_truth.h).
enum class ReferenceKind {
  same_filter,  // the same filter on an 8192² map
  area_light,   // the average of hard shadows over the light's area (PCSS-like techniques)
};

// How a technique's filter radius reads; every entry states it (a test refuses `unset`).
enum class RadiusReading {
  unset,
  none,          // no filter radius (hard shadows, screen-space techniques with their own widths)
  fixed_filter,  // a box or disk of `radius` in `radius_unit` (texels or world): filter_radius
  penumbra,      // a penumbra estimated per pixel, bounded below in world units: rule_radius_ws
};

// The filter-radius accessors of a technique whose settings section holds `radius` and
// `radius_unit` (PENUMBRA_RADIUS_ROWS), e.g. `.filter_radius = section_radius<&ShadowSettings::vsm>`.
template <auto Section>
FilterRadius section_radius(const ShadowSettings& s) {
  return {(s.*Section).radius, (s.*Section).radius_unit};
}
template <auto Section>
void set_section_radius(ShadowSettings& s, FilterRadius r) {
  (s.*Section).radius = r.radius;
  (s.*Section).radius_unit = r.unit;
}

// How a technique's shading reads the sun's virtual shadow map (map.virtual_pages,
// virtual_shadow_map.h); every entry states it (a test refuses `unset`). What a pixel marks follows
// from it: the pages its fixed filter reaches (a world radius, filter_radius), or PCSS's two rounds.
enum class PageReading {
  unset,
  none,            // it cannot read pages
  filter_radius,   // a fixed filter of world radius over the pages' depths (PCF)
  blocker_search,  // a blocker search, then the penumbra it finds: two marking rounds (PCSS)
  moments,         // a fixed filter of world radius over moments drawn into the pages beside the depths (VSM)
};

struct TechniqueEntry {
  std::string_view name;    // CLI/JSON name and the settings section of its parameters
  std::string_view define;  // what the shading pass defines for it (shading.frag)
  RadiusReading radius = RadiusReading::unset;
  PageReading pages = PageReading::unset;
  // What the shading through pages needs of the settings beyond what marking needs (the pages'
  // filters are boxes: "--pcf.kernel grid"), or "" when the settings hold it; nullptr: nothing more.
  std::string_view (*pages_need)(const ShadowSettings&) = nullptr;
  ReferenceKind reference = ReferenceKind::same_filter;
  // The choice row penumbra-render's `--technique all` expands into one variant per choice
  // ("kernel": pcf-grid, pcf-poisson); empty: one variant.
  std::string_view variant_setting;

  // A fixed filter's radius (PCF, RPCF and the filtered-moments techniques); nullptr: none. The
  // adaptive rule, the frustum padding and the moments blur all read it from here.
  FilterRadius (*filter_radius)(const ShadowSettings&) = nullptr;
  void (*set_filter_radius)(ShadowSettings&, FilterRadius) = nullptr;
  // The world-space radius the adaptive rule works from when there is no fixed filter (PCSS: its
  // minimum penumbra); nullptr: the fixed filter's, or no rule input at all.
  float (*rule_radius_ws)(const ShadowSettings&) = nullptr;
  // A blocker search (PCSS-like): its radius over the geometric bound; nullptr: the light's size
  // is not used. The fitted frustum is padded by the search's reach.
  float (*search_scale)(const ShadowSettings&) = nullptr;
  int pad_texels = 0;  // texels beyond the receiver that a lookup reads (revectorization, search)
  // The shading pass can write each pixel's filter radius (PCSS_REQUIREMENT), which the
  // pcss_requirement pass reduces to the resolution the frame needed (adaptive.pcss = per_pixel).
  bool per_pixel_requirement = false;
  // Whether the shading reads the min-max depth pyramid of the atlas (the depth_minmax pass,
  // UNIT_DEPTH_MINMAX); nullptr: never.
  bool (*depth_minmax)(const ShadowSettings&) = nullptr;

  // Filtered moments drawn in the shadow-map pass and blurred (VSM, MSM, EVSM); nullptr: depth only.
  std::optional<MomentsLayout> (*moments)(const ShadowSettings&) = nullptr;
  // Defines beside `define` that select a variant (KERNEL_GRID).
  void (*variant_defines)(const ShadowSettings&, std::vector<gl::ShaderDefine>&) = nullptr;
  // Taps of the Poisson disk the frame uploads (u_poisson); nullptr: none.
  int (*poisson_taps)(const ShadowSettings&) = nullptr;
  // Sets the technique's own uniforms on the shading (and moments) program.
  void (*set_uniforms)(const gl::Program&, const ShadowSettings&) = nullptr;

  // Screen-space techniques: the post passes after the G-buffer (screen_space.h), returning what
  // the shading pass reads per pixel; nullptr: a shadow-map technique.
  const gl::Texture& (*post)(ScreenSpace&, const ShadowSettings&, const PostPassContext&) = nullptr;
  // Whether the G-buffer pass draws revectorized (RBSM) input shadows.
  bool (*rbsm_input)(const ShadowSettings&) = nullptr;

  bool screen_space() const { return post != nullptr; }
  bool uses_light_size() const { return search_scale != nullptr; }
};

// The entry of `t`; every value of Technique has one (technique_list.h).
const TechniqueEntry& technique_entry(Technique t);

}  // namespace penumbra::shadows
