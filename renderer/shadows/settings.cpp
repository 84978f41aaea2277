#include "shadows/settings.h"

#include <array>
#include <charconv>
#include <cmath>
#include <stdexcept>

#include <nlohmann/json.hpp>

namespace penumbra::shadows {
namespace {

constexpr std::array<std::string_view, 11> kTechniques = {"hard", "pcf", "pcss", "vsm", "edtsm", "edtssm",
                                                          "erosion", "rbsm", "rpcf", "msm", "evsm"};
constexpr std::array<std::string_view, 2> kKernels = {"grid", "poisson"};
constexpr std::array<std::string_view, 2> kUnits = {"texels", "world"};
constexpr std::array<std::string_view, 2> kMomentFormats = {"rgba32f", "rgba16f"};
constexpr std::array<std::string_view, 2> kInputs = {"hard", "rbsm"};
constexpr std::array<std::string_view, 2> kStorage = {"subrect", "realloc"};
constexpr std::array<std::string_view, 2> kPcssRequirement = {"per_pixel", "min_penumbra"};

// The double nearest to a float's shortest decimal form (0.2f → 0.2, not 0.20000000298...), so that
// printed, reported and range-checked values are the ones a user typed.
double decimal(float v) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  double d = v;
  std::from_chars(buf, r.ptr, d);
  return d;
}

// Row builders. Each expands to a Setting whose get/set lambdas touch exactly one field.
#define PENUMBRA_REAL(P, field, unit, lo, hi, help)                                                      \
  Setting<P> {                                                                                           \
    #field, unit, SettingType::real, lo, hi, help, [](const P& p) { return decimal(p.field); },            \
        [](P& p, double v) { p.field = static_cast<float>(v); }                                          \
  }
#define PENUMBRA_INT(P, field, unit, lo, hi, help)                                                          \
  Setting<P> {                                                                                              \
    #field, unit, SettingType::integer, lo, hi, help, [](const P& p) { return static_cast<double>(p.field); }, \
        [](P& p, double v) { p.field = static_cast<int>(std::lround(v)); }                                  \
  }
#define PENUMBRA_BOOL(P, field, help)                                                                    \
  Setting<P> {                                                                                           \
    #field, "", SettingType::boolean, 0, 1, help, [](const P& p) { return p.field ? 1.0 : 0.0; },        \
        [](P& p, double v) { p.field = v != 0.0; }                                                       \
  }
#define PENUMBRA_CHOICE(P, field, Enum, names, help)                                                       \
  Setting<P> {                                                                                             \
    #field, "", SettingType::choice, 0, static_cast<double>(names.size() - 1), help,                       \
        [](const P& p) { return static_cast<double>(p.field); },                                           \
        [](P& p, double v) { p.field = static_cast<Enum>(static_cast<int>(v)); }, names                    \
  }

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
};

const Setting<AdaptiveParams> kAdaptiveTable[] = {
    PENUMBRA_BOOL(AdaptiveParams, enabled, "choose the resolution from the filter with res = c / r_uv"),
    PENUMBRA_REAL(AdaptiveParams, c, "texels", 0.01, 100, "filter radius per hidden texel (calibration.json)"),
    PENUMBRA_INT(AdaptiveParams, min_texels, "texels", 1, 65536, "smallest resolution"),
    PENUMBRA_INT(AdaptiveParams, max_texels, "texels", 1, 65536, "largest resolution (sub-rectangle storage allocates this)"),
    PENUMBRA_INT(AdaptiveParams, quantum_texels, "texels", 1, 4096, "resolutions are rounded up to a multiple of this"),
    PENUMBRA_INT(AdaptiveParams, shrink_delay_frames, "frames", 0, 100000, "frames a smaller requirement must hold before shrinking"),
    PENUMBRA_CHOICE(AdaptiveParams, storage, Storage, kStorage, "subrect: part of a preallocated max-size map; realloc: a map per size"),
    PENUMBRA_CHOICE(AdaptiveParams, pcss, PcssRequirement, kPcssRequirement,
                    "PCSS: per_pixel = GPU max of c / r_filter over the last frame; min_penumbra = c / minimum penumbra"),
};

const Setting<PcfParams> kPcfTable[] = {
    PENUMBRA_REAL(PcfParams, radius, "radius_unit", 0, 1e6, "filter radius"),
    PENUMBRA_CHOICE(PcfParams, radius_unit, RadiusUnit, kUnits, "unit of the radius: shadow-map texels or world units"),
    PENUMBRA_CHOICE(PcfParams, kernel, Kernel, kKernels, "grid: box over whole texels, coverage-weighted; poisson: rotated disk"),
    PENUMBRA_INT(PcfParams, poisson_taps, "taps", 1, 64, "Poisson-disk taps (each a hardware 2x2 comparison)"),
    PENUMBRA_BOOL(PcfParams, rotate, "rotate the Poisson disk per pixel"),
    PENUMBRA_INT(PcfParams, max_grid_taps, "taps", 2, 256, "grid taps per axis before the grid is strided"),
};

const Setting<PcssParams> kPcssTable[] = {
    PENUMBRA_CHOICE(PcssParams, kernel, Kernel, kKernels, "kernel of the filtering step"),
    PENUMBRA_INT(PcssParams, blocker_taps, "taps", 1, 64, "Poisson taps of the blocker search"),
    PENUMBRA_INT(PcssParams, filter_taps, "taps", 1, 64, "Poisson taps of the filtering step"),
    PENUMBRA_REAL(PcssParams, min_penumbra_ws, "world", 0, 1e6, "minimum filter radius at the receiver"),
    PENUMBRA_REAL(PcssParams, search_scale, "", 1, 8,
                  "blocker-search radius over its geometric bound; > 1 lets sparse taps find blockers near the penumbra's outer rim"),
    PENUMBRA_INT(PcssParams, max_grid_taps, "taps", 2, 256, "grid taps per axis before the grid is strided"),
};

const Setting<VsmParams> kVsmTable[] = {
    PENUMBRA_REAL(VsmParams, radius, "radius_unit", 0, 1e6, "box-blur radius of the moments"),
    PENUMBRA_CHOICE(VsmParams, radius_unit, RadiusUnit, kUnits, "unit of the radius: shadow-map texels or world units"),
    PENUMBRA_REAL(VsmParams, min_variance, "depth^2", 0, 1, "variance floor"),
    PENUMBRA_REAL(VsmParams, bleed_reduction, "", 0, 0.999, "light-bleeding reduction threshold"),
};

constexpr std::string_view kInputHelp =
    "input hard shadows: rbsm (revectorized, as the papers; parameters from the rbsm table) or hard (plain test)";
constexpr std::string_view kEdgeHelp =
    "measure D from the silhouette between the two site pixels (D + half a pixel: sub-pixel penumbrae stay hard) "
    "instead of from the site pixel's centre (the paper: site pixels are 1/2)";
constexpr std::string_view kDepthThresholdHelp =
    "largest relative eye-depth difference |dz|/z between pixels treated as one surface (edge-aware sites, EDT and filter)";

const Setting<EdtsmParams> kEdtsmTable[] = {
    PENUMBRA_CHOICE(EdtsmParams, input, ShadowInput, kInputs, kInputHelp),
    PENUMBRA_REAL(EdtsmParams, penumbra_ws, "world", 0, 1e6, "P: fake-penumbra width; I = 1/2 -+ D/P for D <= P/2"),
    PENUMBRA_REAL(EdtsmParams, filter_ws, "world", 0, 1e6, "w_filter: edge-aware mean-filter width; on screen w z_screen / z_eye pixels"),
    PENUMBRA_REAL(EdtsmParams, depth_threshold, "", 0, 10, kDepthThresholdHelp),
    PENUMBRA_INT(EdtsmParams, max_filter_px, "px", 1, 1024, "largest mean-filter width on screen"),
    PENUMBRA_BOOL(EdtsmParams, edge_between_pixels, kEdgeHelp),
};

const Setting<EdtssmParams> kEdtssmTable[] = {
    PENUMBRA_CHOICE(EdtssmParams, input, ShadowInput, kInputs, kInputHelp),
    PENUMBRA_REAL(EdtssmParams, beta, "", 0, 1e6, "beta: penumbra scale; alpha = 1/2 -+ d / (beta w_p) for d <= beta w_p / 2"),
    PENUMBRA_INT(EdtssmParams, blocker_taps, "taps", 1, 64, "Poisson taps of the blocker search at silhouette pixels"),
    PENUMBRA_REAL(EdtssmParams, search_scale, "", 1, 8, "blocker-search radius over its geometric bound"),
    PENUMBRA_REAL(EdtssmParams, filter_ws, "world", 0, 1e6, "w_filter: edge-aware mean-filter width; on screen w z_screen / z_eye pixels"),
    PENUMBRA_REAL(EdtssmParams, depth_threshold, "", 0, 10, kDepthThresholdHelp),
    PENUMBRA_INT(EdtssmParams, max_filter_px, "px", 1, 1024, "largest mean-filter width on screen"),
    PENUMBRA_BOOL(EdtssmParams, edge_between_pixels, kEdgeHelp),
};

const Setting<ErosionParams> kErosionTable[] = {
    PENUMBRA_INT(ErosionParams, taps, "taps", 1, 64, "Poisson taps of the PCF scaled by the eroded penumbra width"),
    PENUMBRA_INT(ErosionParams, blocker_taps, "taps", 1, 64, "Poisson taps of the blocker search at edge pixels"),
    PENUMBRA_REAL(ErosionParams, search_scale, "", 1, 8, "blocker-search radius over its geometric bound"),
    PENUMBRA_INT(ErosionParams, max_search_px, "px", 1, 4096, "largest erosion search radius on screen"),
    PENUMBRA_BOOL(ErosionParams, rotate, "rotate the PCF disk per pixel"),
    PENUMBRA_REAL(ErosionParams, depth_threshold, "", 0, 10, kDepthThresholdHelp),
};

const Setting<RbsmParams> kRbsmTable[] = {
    PENUMBRA_INT(RbsmParams, max_search_texels, "texels", 1, 256,
                 "texels walked along a silhouette step in each direction; longer steps are revectorized as if straight"),
};

const Setting<RpcfParams> kRpcfTable[] = {
    PENUMBRA_REAL(RpcfParams, radius, "radius_unit", 0, 1e6, "half side of the filter box"),
    PENUMBRA_CHOICE(RpcfParams, radius_unit, RadiusUnit, kUnits, "unit of the radius: shadow-map texels or world units"),
    PENUMBRA_INT(RpcfParams, max_grid_taps, "taps", 2, 256, "texels per axis integrated exactly before the box is strided"),
    PENUMBRA_INT(RpcfParams, max_search_texels, "texels", 1, 256, "texels walked along a silhouette step in each direction"),
};

const Setting<MsmParams> kMsmTable[] = {
    PENUMBRA_REAL(MsmParams, radius, "radius_unit", 0, 1e6, "box-blur radius of the moments"),
    PENUMBRA_CHOICE(MsmParams, radius_unit, RadiusUnit, kUnits, "unit of the radius: shadow-map texels or world units"),
    PENUMBRA_REAL(MsmParams, moment_bias, "", 1e-9, 0.1, "moment bias alpha toward (0, 0.63, 0, 0.63)"),
    PENUMBRA_REAL(MsmParams, depth_bias, "depth", 0, 0.1, "receiver depth offset, depth in [-1, 1] over the light's depth range"),
    PENUMBRA_REAL(MsmParams, bleed_reduction, "", 0, 0.999, "light-bleeding reduction threshold"),
};

const Setting<EvsmParams> kEvsmTable[] = {
    PENUMBRA_REAL(EvsmParams, radius, "radius_unit", 0, 1e6, "box-blur radius of the moments"),
    PENUMBRA_CHOICE(EvsmParams, radius_unit, RadiusUnit, kUnits, "unit of the radius: shadow-map texels or world units"),
    PENUMBRA_CHOICE(EvsmParams, format, MomentFormat, kMomentFormats, "storage of the four warped moments"),
    PENUMBRA_REAL(EvsmParams, positive_exponent, "", 0, 42, "c+ of exp(c+ x); clamped to 42 (rgba32f) or 5.54 (rgba16f)"),
    PENUMBRA_REAL(EvsmParams, negative_exponent, "", 0, 42, "c- of -exp(-c- x); clamped like c+"),
    PENUMBRA_REAL(EvsmParams, min_variance, "depth^2", 0, 1, "variance floor before the warp"),
    PENUMBRA_REAL(EvsmParams, bleed_reduction, "", 0, 0.999, "light-bleeding reduction threshold"),
};

#undef PENUMBRA_REAL
#undef PENUMBRA_INT
#undef PENUMBRA_BOOL
#undef PENUMBRA_CHOICE

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
std::span<const Setting<PcfParams>> settings_table(const PcfParams*) { return kPcfTable; }
std::span<const Setting<PcssParams>> settings_table(const PcssParams*) { return kPcssTable; }
std::span<const Setting<VsmParams>> settings_table(const VsmParams*) { return kVsmTable; }
std::span<const Setting<AdaptiveParams>> settings_table(const AdaptiveParams*) { return kAdaptiveTable; }
std::span<const Setting<EdtsmParams>> settings_table(const EdtsmParams*) { return kEdtsmTable; }
std::span<const Setting<EdtssmParams>> settings_table(const EdtssmParams*) { return kEdtssmTable; }
std::span<const Setting<ErosionParams>> settings_table(const ErosionParams*) { return kErosionTable; }
std::span<const Setting<RbsmParams>> settings_table(const RbsmParams*) { return kRbsmTable; }
std::span<const Setting<RpcfParams>> settings_table(const RpcfParams*) { return kRpcfTable; }
std::span<const Setting<MsmParams>> settings_table(const MsmParams*) { return kMsmTable; }
std::span<const Setting<EvsmParams>> settings_table(const EvsmParams*) { return kEvsmTable; }

template <class P>
void set_from_string(const Setting<P>& s, P& params, std::string_view value) {
  const std::string key(s.key);
  const std::string text(value);
  auto fail = [&](const std::string& expected) {
    throw std::invalid_argument(key + ": expected " + expected + ", got '" + text + "'");
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

#define PENUMBRA_INSTANTIATE(P)                                                      \
  template void set_from_string<P>(const Setting<P>&, P&, std::string_view);       \
  template std::string value_to_string<P>(const Setting<P>&, const P&);
PENUMBRA_INSTANTIATE(ShadowMapParams)
PENUMBRA_INSTANTIATE(PcfParams)
PENUMBRA_INSTANTIATE(PcssParams)
PENUMBRA_INSTANTIATE(VsmParams)
PENUMBRA_INSTANTIATE(AdaptiveParams)
PENUMBRA_INSTANTIATE(EdtsmParams)
PENUMBRA_INSTANTIATE(EdtssmParams)
PENUMBRA_INSTANTIATE(ErosionParams)
PENUMBRA_INSTANTIATE(RbsmParams)
PENUMBRA_INSTANTIATE(RpcfParams)
PENUMBRA_INSTANTIATE(MsmParams)
PENUMBRA_INSTANTIATE(EvsmParams)
#undef PENUMBRA_INSTANTIATE

nlohmann::json to_json(const ShadowMapParams& p) { return table_json(p); }
nlohmann::json to_json(const PcfParams& p) { return table_json(p); }
nlohmann::json to_json(const PcssParams& p) { return table_json(p); }
nlohmann::json to_json(const VsmParams& p) { return table_json(p); }
nlohmann::json to_json(const AdaptiveParams& p) { return table_json(p); }
nlohmann::json to_json(const EdtsmParams& p) { return table_json(p); }
nlohmann::json to_json(const EdtssmParams& p) { return table_json(p); }
nlohmann::json to_json(const ErosionParams& p) { return table_json(p); }
nlohmann::json to_json(const RbsmParams& p) { return table_json(p); }
nlohmann::json to_json(const RpcfParams& p) { return table_json(p); }
nlohmann::json to_json(const MsmParams& p) { return table_json(p); }
nlohmann::json to_json(const EvsmParams& p) { return table_json(p); }

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

}  // namespace penumbra::shadows
