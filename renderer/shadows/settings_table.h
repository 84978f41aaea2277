#pragma once
// A parameters table: one row per field of a plain parameters struct (name, unit, range, help),
// from which the CLI, the ImGui panels, the JSON reports and the shader defines are made. Every
// technique's parameters (techniques/*.h) and the shared sections (settings.h) declare one.
#include <span>
#include <string_view>

namespace penumbra::shadows {

// Choices shared by several techniques' parameters.
enum class Kernel { grid, poisson, disk };
enum class RadiusUnit { texels, world };
enum class ShadowInput { hard, rbsm };  // the input shadows of EDTSM / EDTSSM
enum class MomentFormat { rgba32f, rgba16f };

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
  // > 0: a real row whose 0 means "off" or "the default" (adaptive.visibility: the entry's
  // criterion) and whose other values lie in [min_positive, max]; what lies between is refused.
  double min_positive = 0;
};

// A technique without parameters (hard shadows): no section, an empty table.
struct NoParams {};
inline std::span<const Setting<NoParams>> settings_table(const NoParams*) { return {}; }

}  // namespace penumbra::shadows
