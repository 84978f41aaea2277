#pragma once
// Row builders for the parameters tables (settings_table.h); include only from .cpp files. Each
// expands to a Setting whose get/set lambdas touch exactly one field.
#include <array>
#include <charconv>
#include <cmath>
#include <string_view>

#include <penumbra/shadows/settings_table.h>

namespace penumbra::shadows::rows {

// The double nearest to a float's shortest decimal form (0.2f → 0.2, not 0.20000000298...), so that
// printed, reported and range-checked values are the ones a user typed.
inline double decimal(float v) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  double d = v;
  std::from_chars(buf, r.ptr, d);
  return d;
}
// A double row is its own value (adaptive.visibility: 1e-300 must not become a float's 0).
inline double decimal(double v) { return v; }

inline constexpr std::array<std::string_view, 3> kKernels = {"grid", "poisson", "disk"};
inline constexpr std::array<std::string_view, 2> kUnits = {"texels", "world"};
inline constexpr std::array<std::string_view, 2> kMomentFormats = {"rgba32f", "rgba16f"};
inline constexpr std::array<std::string_view, 2> kInputs = {"hard", "rbsm"};

// Help shared by the screen-space techniques' rows.
inline constexpr std::string_view kInputHelp =
    "input hard shadows: rbsm (revectorized, as the papers; parameters from the rbsm table) or hard (plain test)";
inline constexpr std::string_view kEdgeHelp =
    "measure D from the silhouette between the two site pixels (D + half a pixel: sub-pixel penumbrae stay hard) "
    "instead of from the site pixel's centre (the paper: site pixels are 1/2)";
inline constexpr std::string_view kDepthThresholdHelp =
    "largest relative eye-depth difference |dz|/z between pixels treated as one surface (edge-aware sites, EDT and filter)";

}  // namespace penumbra::shadows::rows

#define PENUMBRA_REAL(P, field, unit, lo, hi, help)                                                        \
  ::penumbra::shadows::Setting<P> {                                                                        \
    #field, unit, ::penumbra::shadows::SettingType::real, lo, hi, help,                                    \
        [](const P& p) { return ::penumbra::shadows::rows::decimal(p.field); },                            \
        [](P& p, double v) { p.field = static_cast<decltype(P::field)>(v); }                               \
  }
// A real row whose 0 stands for something else (off, the default) and whose values otherwise lie
// in [lo, hi] (Setting::min_positive).
#define PENUMBRA_REAL_OR_ZERO(P, field, unit, lo, hi, help)                                               \
  ::penumbra::shadows::Setting<P> {                                                                        \
    #field, unit, ::penumbra::shadows::SettingType::real, 0, hi, help,                                     \
        [](const P& p) { return ::penumbra::shadows::rows::decimal(p.field); },                            \
        [](P& p, double v) { p.field = static_cast<decltype(P::field)>(v); }, {}, lo                       \
  }
#define PENUMBRA_INT(P, field, unit, lo, hi, help)                                                         \
  ::penumbra::shadows::Setting<P> {                                                                        \
    #field, unit, ::penumbra::shadows::SettingType::integer, lo, hi, help,                                 \
        [](const P& p) { return static_cast<double>(p.field); },                                           \
        [](P& p, double v) { p.field = static_cast<int>(std::lround(v)); }                                 \
  }
#define PENUMBRA_BOOL(P, field, help)                                                                      \
  ::penumbra::shadows::Setting<P> {                                                                        \
    #field, "", ::penumbra::shadows::SettingType::boolean, 0, 1, help,                                     \
        [](const P& p) { return p.field ? 1.0 : 0.0; }, [](P& p, double v) { p.field = v != 0.0; }         \
  }
#define PENUMBRA_CHOICE(P, field, Enum, names, help)                                                       \
  ::penumbra::shadows::Setting<P> {                                                                        \
    #field, "", ::penumbra::shadows::SettingType::choice, 0, static_cast<double>(names.size() - 1), help,  \
        [](const P& p) { return static_cast<double>(p.field); },                                           \
        [](P& p, double v) { p.field = static_cast<Enum>(static_cast<int>(v)); }, names                    \
  }
// The edge-aware mean filter after the EDT and the site geometry (EDTSM, EDTSSM).
#define PENUMBRA_EDT_FILTER_ROWS(P)                                                                        \
  PENUMBRA_REAL(P, filter_ws, "world", 0, 1e6, "w_filter: edge-aware mean-filter width; on screen w z_screen / z_eye pixels"), \
      PENUMBRA_REAL(P, depth_threshold, "", 0, 10, ::penumbra::shadows::rows::kDepthThresholdHelp),       \
      PENUMBRA_INT(P, max_filter_px, "px", 1, 1024, "largest mean-filter width on screen"),                 \
      PENUMBRA_BOOL(P, edge_between_pixels, ::penumbra::shadows::rows::kEdgeHelp)
// A filter radius and its unit (the rows every fixed-radius filter shares).
#define PENUMBRA_RADIUS_ROWS(P, help)                                                                      \
  PENUMBRA_REAL(P, radius, "radius_unit", 0, 1e6, help),                                                   \
      PENUMBRA_CHOICE(P, radius_unit, ::penumbra::shadows::RadiusUnit, ::penumbra::shadows::rows::kUnits,  \
                      "unit of the radius: shadow-map texels or world units")
