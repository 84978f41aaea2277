#include "shadows/settings.h"

#include <algorithm>
#include <array>
#include <initializer_list>
#include <charconv>
#include <cmath>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "json/json_input.h"
#include "shadows/settings_rows.h"
#include "shadows/technique.h"

namespace penumbra::shadows {
namespace {

#define PENUMBRA_NAME(name, P) #name,
constexpr auto kTechniques = std::to_array<std::string_view>({PENUMBRA_TECHNIQUES(PENUMBRA_NAME)});
#undef PENUMBRA_NAME
constexpr std::array<std::string_view, 2> kStorage = {"subrect", "realloc"};
constexpr std::array<std::string_view, 3> kVirtualPages = {"off", "rule", "footprint"};
constexpr std::array<std::string_view, 2> kPcssRequirement = {"per_pixel", "min_penumbra"};

const Setting<ShadowMapParams> kMapTable[] = {
    PENUMBRA_INT(ShadowMapParams, resolution_texels, "texels", 1, 65536, "shadow-map width = height"),
    PENUMBRA_BOOL(ShadowMapParams, fit, "fit the light frustum to the potential shadow receivers"),
    PENUMBRA_REAL(ShadowMapParams, slope_bias, "", 0, 16, "slope-scaled raster depth offset (glPolygonOffset factor)"),
    PENUMBRA_REAL(ShadowMapParams, offset_bias, "depth steps", 0, 1e4, "constant raster depth offset (glPolygonOffset units)"),
    PENUMBRA_REAL(ShadowMapParams, normal_offset_texels, "texels", 0, 16, "lookup offset along the surface normal"),
    PENUMBRA_REAL(ShadowMapParams, depth_bias_texels, "texels", 0, 64, "constant receiver depth offset, in texel widths at the receiver"),
    PENUMBRA_BOOL(ShadowMapParams, receiver_plane_bias, "per-tap reference depth from the receiver's depth gradient"),
    PENUMBRA_INT(ShadowMapParams, cascades, "", 0, 4, "directional light: cascade count, 0 = as few as the resolution rule allows"),
    PENUMBRA_REAL(ShadowMapParams, cascade_lambda, "", 0, 1, "cascade splits: 0 uniform, 1 logarithmic, between: practical"),
    PENUMBRA_REAL(ShadowMapParams, cascade_blend, "", 0, 0.5, "blend band at each cascade's far end (fraction of its depth range)"),
    PENUMBRA_BOOL(ShadowMapParams, cascade_stabilize, "cascade windows in quarter-octave sizes snapped to whole texels (no crawling)"),
    PENUMBRA_BOOL(ShadowMapParams, culling, "draw only the clusters of triangles whose bounds touch a map (casters) and the units whose bounds touch the camera's view; the image is the same"),
    PENUMBRA_BOOL(ShadowMapParams, depth_prepass,
                  "the camera's depth drawn first (depth only), so that the shading pass shades each pixel's visible surface once; "
                  "the image is the same but for surfaces tied in depth"),
    PENUMBRA_CHOICE(ShadowMapParams, virtual_pages, VirtualPages, kVirtualPages,
                    "sun: a virtual shadow map whose pages each pixel marks by its filter (rule: r / c) or its footprint; off: maps"),
    PENUMBRA_REAL(ShadowMapParams, virtual_min_texel_px, "pixels", 0.125, 64,
                  "virtual shadow map: the pixel floor, no page texel finer than this many footprints of the pixel asking (0.71: texels of 0.35 to 0.71 pixel where the floor sets the level)"),
    PENUMBRA_INT(ShadowMapParams, virtual_pool_pages, "pages", 1, 128, "virtual shadow map: page slots per side of the pool (128² texels each)"),
    PENUMBRA_BOOL(ShadowMapParams, virtual_cache, "virtual shadow map: keep drawn pages across frames until the light or a caster moves"),
    PENUMBRA_BOOL(ShadowMapParams, virtual_bounds,
                  "virtual shadow map: depth bounds per tile of each page, to skip filters surely lit or in umbra; the image is the same"),
    PENUMBRA_BOOL(ShadowMapParams, virtual_page_tiles,
                  "virtual shadow map, uncached: draw into each page only the casters over the tiles its pixels read; the image is the same"),
    PENUMBRA_BOOL(ShadowMapParams, virtual_marks_late,
                  "virtual shadow map: draw the pages the previous frame marked (no read-back waited for within a frame); a pixel "
                  "whose page is not there yet reads a coarser one"),
};

const Setting<AdaptiveParams> kAdaptiveTable[] = {
    PENUMBRA_BOOL(AdaptiveParams, enabled, "choose the resolution from the filter with res = c / r_uv"),
    PENUMBRA_REAL(AdaptiveParams, c, "texels", 0.01, 100,
                  "filter radius per texel at which its staircase is still detected with the entry's criterion probability (calibration.json)"),
    PENUMBRA_REAL_OR_ZERO(AdaptiveParams, visibility, "", kMinVisibility, kMaxVisibility,
                          "detection probability F the rule is for: 0 = the calibration entry's criterion (0.65 for 82 % correct in "
                          "2AFC), else in [0.001, 0.999]; lower needs a larger c"),
    PENUMBRA_INT(AdaptiveParams, min_texels, "texels", 1, 65536, "smallest resolution"),
    PENUMBRA_INT(AdaptiveParams, max_texels, "texels", 1, 65536, "largest resolution (sub-rectangle storage allocates this)"),
    PENUMBRA_INT(AdaptiveParams, quantum_texels, "texels", 1, 4096, "resolutions are rounded up to a multiple of this"),
    PENUMBRA_INT(AdaptiveParams, shrink_delay_frames, "frames", 0, 100000, "frames a smaller requirement must hold before shrinking"),
    PENUMBRA_REAL(AdaptiveParams, max_texel_ws, "world", 0, 1e6,
                  "coarsest texel allowed (the thinnest caster that must keep its shadow); 0 = the rule alone"),
    PENUMBRA_REAL(AdaptiveParams, min_texel_px, "pixels", 0, 1000,
                  "finest texel worth drawing, in pixel footprints at the map's nearest receiver (directional); 0 = the rule alone"),
    PENUMBRA_CHOICE(AdaptiveParams, storage, Storage, kStorage, "subrect: part of a preallocated max-size map; realloc: a map per size"),
    PENUMBRA_CHOICE(AdaptiveParams, pcss, PcssRequirement, kPcssRequirement,
                    "PCSS: per_pixel = GPU max of c / r_filter over the last frame; min_penumbra = c / minimum penumbra"),
};

template <class P>
nlohmann::json table_json(const P& p) {
  nlohmann::json j = nlohmann::json::object();
  for (const auto& s : settings_table(static_cast<const P*>(nullptr))) {
    const double v = s.get(p);
    switch (s.type) {
      case SettingType::real: j[std::string(s.key)] = v; break;
      case SettingType::integer: j[std::string(s.key)] = static_cast<long long>(v); break;
      case SettingType::boolean: j[std::string(s.key)] = v != 0.0; break;
      case SettingType::choice: j[std::string(s.key)] = std::string(s.choices[static_cast<std::size_t>(v)]); break;
    }
  }
  return j;
}

std::string value_of_virtual_pages(const ShadowSettings& s) { return std::string(kVirtualPages[static_cast<std::size_t>(s.map.virtual_pages)]); }

}  // namespace

std::span<const std::string_view> technique_names() { return kTechniques; }
std::string_view to_string(Technique t) { return kTechniques[static_cast<std::size_t>(t)]; }
Technique technique_from_string(std::string_view name) {
  for (std::size_t i = 0; i < kTechniques.size(); ++i)
    if (kTechniques[i] == name) return static_cast<Technique>(i);
  std::string names;
  for (std::size_t i = 0; i < kTechniques.size(); ++i)
    names += (i == 0 ? "" : i + 1 == kTechniques.size() ? " or " : ", ") + std::string(kTechniques[i]);
  throw std::invalid_argument("unknown technique '" + std::string(name) + "' (expected " + names + ")");
}

std::span<const Setting<ShadowMapParams>> settings_table(const ShadowMapParams*) { return kMapTable; }
std::span<const Setting<AdaptiveParams>> settings_table(const AdaptiveParams*) { return kAdaptiveTable; }

template <class P>
void set_from_string(const Setting<P>& s, P& params, std::string_view value) {
  const std::string key(s.key);
  const std::string text(value);
  auto fail = [&](const std::string& expected) {
    throw std::invalid_argument(key + ": expected " + expected + ", got '" + json_input::printable(text) + "'");
  };
  auto range = [&] {
    return "a number in [" + nlohmann::json(s.min).dump() + ", " + nlohmann::json(s.max).dump() + "]";
  };
  switch (s.type) {
    case SettingType::boolean:
      if (value == "true" || value == "1" || value == "on") s.set(params, 1);
      else if (value == "false" || value == "0" || value == "off") s.set(params, 0);
      else fail("true or false");
      return;
    case SettingType::choice: {
      for (std::size_t i = 0; i < s.choices.size(); ++i) {
        if (s.choices[i] == value) {
          s.set(params, static_cast<double>(i));
          return;
        }
      }
      std::string names;
      for (auto c : s.choices) names += (names.empty() ? "" : " or ") + std::string(c);
      fail(names);
      return;
    }
    case SettingType::real:
    case SettingType::integer: {
      double v = 0;
      const auto* end = text.data() + text.size();
      auto [ptr, ec] = std::from_chars(text.data(), end, v);
      if (ec != std::errc() || ptr != end || !std::isfinite(v)) fail(range());
      if (s.type == SettingType::integer && v != std::floor(v)) fail("an integer in [" + nlohmann::json(s.min).dump() + ", " + nlohmann::json(s.max).dump() + "]");
      if (s.min_positive > 0 && v != 0 && !(v >= s.min_positive && v <= s.max))
        fail("0 or a number in [" + nlohmann::json(s.min_positive).dump() + ", " + nlohmann::json(s.max).dump() + "]");
      if (v < s.min || v > s.max) fail(range());
      s.set(params, v);
      return;
    }
  }
}

template <class P>
std::string value_to_string(const Setting<P>& s, const P& params) {
  const double v = s.get(params);
  switch (s.type) {
    case SettingType::boolean: return v != 0.0 ? "true" : "false";
    case SettingType::choice: return std::string(s.choices[static_cast<std::size_t>(v)]);
    case SettingType::integer: return std::to_string(static_cast<long long>(v));
    case SettingType::real: return nlohmann::json(v).dump();
  }
  return {};
}

// Hand-written (from the settings table): choices as their names, integers and booleans by the row's type.
template <SettingsSection P>
nlohmann::json to_json(const P& p) {
  return table_json(p);
}

#define PENUMBRA_INSTANTIATE(P)                                                      \
  template void set_from_string<P>(const Setting<P>&, P&, std::string_view);       \
  template std::string value_to_string<P>(const Setting<P>&, const P&);            \
  template nlohmann::json to_json<P>(const P&);
#define PENUMBRA_INSTANTIATE_SECTION(name, P) PENUMBRA_INSTANTIATE(P)
PENUMBRA_INSTANTIATE(ShadowMapParams)
PENUMBRA_INSTANTIATE(AdaptiveParams)
PENUMBRA_TECHNIQUES(PENUMBRA_INSTANTIATE_SECTION)
#undef PENUMBRA_INSTANTIATE_SECTION
#undef PENUMBRA_INSTANTIATE

// Hand-written: the technique as its name, and the sections (map, adaptive, each technique's) by the table.
nlohmann::json to_json(const ShadowSettings& s) {
  nlohmann::json j;
  j["technique"] = std::string(to_string(s.technique));
  j["map"] = to_json(s.map);
  j["adaptive"] = to_json(s.adaptive);
  visit_technique_section(s, [&](std::string_view section, const auto& params) { j[std::string(section)] = to_json(params); });
  return j;
}

std::string describe(const ShadowSettings& s) {
  std::string out(to_string(s.technique));
  auto add = [&](const auto& params) {
    for (const auto& row : settings_table(&params)) out += " " + std::string(row.key) + "=" + value_to_string(row, params);
  };
  visit_technique_section(s, [&](std::string_view, const auto& params) { add(params); });
  return out;
}

ShadowSettings unshadowed_floor(const ShadowSettings& base) {
  ShadowSettings s = base;
  s.technique = Technique::hard;
  s.adaptive.enabled = false;
  s.map.resolution_texels = 1;
  s.map.fit = false;
  s.map.cascades = 1;
  s.map.virtual_pages = VirtualPages::off;
  return s;
}

std::string variant_choice(const ShadowSettings& s) {
  const std::string_view key = technique_entry(s.technique).variant_setting;
  std::string out;
  if (key.empty()) return out;
  visit_technique_section(s, [&](std::string_view, const auto& params) {
    for (const auto& row : settings_table(&params))
      if (row.key == key && row.type == SettingType::choice) out = value_to_string(row, params);
  });
  return out;
}

std::string unread_setting(const ShadowSettings& s, std::string_view section, std::string_view key) {
  const auto among = [&](std::initializer_list<std::string_view> keys) { return std::find(keys.begin(), keys.end(), key) != keys.end(); };
  const bool virtual_map = s.map.virtual_pages != VirtualPages::off;
  if (section == "map") {
    if (virtual_map && among({"resolution_texels", "fit", "cascades", "cascade_lambda", "cascade_blend", "cascade_stabilize"}))
      return "a virtual shadow map (map.virtual_pages " + value_of_virtual_pages(s) + ") has pages, not a map's size, fit or cascades";
    if (!virtual_map && among({"virtual_min_texel_px", "virtual_pool_pages", "virtual_cache", "virtual_bounds", "virtual_page_tiles", "virtual_marks_late"}))
      return "it sets the virtual shadow map, and map.virtual_pages is off";
  }
  if (section == "adaptive") {
    if (virtual_map && among({"enabled", "min_texels", "max_texels", "quantum_texels", "shrink_delay_frames", "max_texel_ws", "storage", "pcss"}))
      return "a virtual shadow map (map.virtual_pages " + value_of_virtual_pages(s) + ") marks pages by the rule's c, not map sizes";
    if (virtual_map && key == "min_texel_px")
      return "a virtual shadow map's pixel floor is map.virtual_min_texel_px (adaptive.min_texel_px is the cascades')";
    const bool rule = virtual_map ? s.map.virtual_pages == VirtualPages::rule : s.adaptive.enabled;
    if (!rule && key == "visibility")
      return virtual_map ? "pages marked by the footprint have no rule to set c for" : "the adaptive rule is off (adaptive.enabled false)";
  }
  return "";
}

std::vector<std::string> variant_choices(Technique t) {
  const std::string_view key = technique_entry(t).variant_setting;
  std::vector<std::string> out;
  if (key.empty()) return out;
  ShadowSettings s;
  s.technique = t;
  visit_technique_section(s, [&](std::string_view, const auto& params) {
    for (const auto& row : settings_table(&params))
      if (row.key == key && row.type == SettingType::choice) out.assign(row.choices.begin(), row.choices.end());
  });
  return out;
}

void set_variant_choice(ShadowSettings& s, std::string_view choice) {
  const std::string_view key = technique_entry(s.technique).variant_setting;
  bool set = false;
  visit_technique_section(s, [&](std::string_view, auto& params) {
    for (const auto& row : settings_table(&params))
      if (!key.empty() && row.key == key && row.type == SettingType::choice) {
        set_from_string(row, params, std::string(choice));
        set = true;
      }
  });
  if (!set) throw std::invalid_argument(std::string(to_string(s.technique)) + " has no variant setting to set to '" + std::string(choice) + "'");
}

}  // namespace penumbra::shadows
