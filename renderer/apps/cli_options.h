#pragma once
// Command-line helpers shared by the renderer's apps: options generated from a settings table,
// comma-separated number lists, the light-size override and the calibration file (parsing and
// error lines: cli/main.h). Errors are CLI::ValidationError naming the option.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "adaptive/resolution_rule.h"
#include "cli/checks.h"
#include "cli/list_option.h"
#include "cli/main.h"
#include "json/json_input.h"
#include "scene/scene.h"
#include "shadows/settings.h"
#include "tool/tool.h"

namespace penumbra::apps {

// --<section>.<key> for every row of a parameters table, with the unit and default in the help
// and the table's own range check.
template <class P>
void add_table_options(CLI::App& app, const std::string& section, P& params) {
  for (const auto& row : shadows::settings_table(&params)) {
    const std::string name = "--" + section + "." + std::string(row.key);
    std::string help(row.help);
    if (!row.unit.empty()) help += " [" + std::string(row.unit == "radius_unit" ? "see radius_unit" : row.unit) + "]";
    help += " (default " + shadows::value_to_string(row, params) + ")";
    app.add_option_function<std::string>(
           name, [&params, row, name](const std::string& v) {
             try {
               shadows::set_from_string(row, params, v);
             } catch (const std::invalid_argument& e) {
               throw CLI::ValidationError(name, e.what());
             }
           },
           help)
        ->group(section + " parameters");
  }
}

// Every section of the shadow settings: --map.*, and one group per technique's parameters.
inline void add_settings_options(CLI::App& app, shadows::ShadowSettings& s) {
  add_table_options(app, "map", s.map);
  add_table_options(app, "adaptive", s.adaptive);
  shadows::for_each_technique_section(s, [&](std::string_view section, auto& params) {
    add_table_options(app, std::string(section), params);
  });
}

// A settings option the tool sets itself from its own option (penumbra-render's --resolution sets
// map.resolution_texels): given alone it stands for the tool's option, given with it the command
// is contradictory. Returns whether `setting` was given (then `own` should take its value).
inline bool setting_stands_for(const CLI::App& app, const std::string& setting, const std::string& own) {
  if (app.count(setting) == 0) return false;
  if (app.count(own) > 0) throw CLI::ValidationError(setting, "sets what " + own + " sets; give one of them");
  return true;
}

// Options of a technique's parameters section (--vsm.radius) when no technique that reads them is
// rendered are refused: the run would ignore them without a word (--technique hard --vsm.radius 3).
// `rendered` names the techniques the command renders; `by` says how they were chosen
// ("--technique hard").
inline void refuse_unused_technique_options(const CLI::App& app, const std::vector<shadows::Technique>& rendered, const std::string& by) {
  shadows::ShadowSettings probe;
  shadows::for_each_technique_section(probe, [&](std::string_view section, auto& params) {
    bool read = false;
    for (const shadows::Technique t : rendered) read = read || shadows::to_string(t) == section;
    if (read) return;
    for (const auto& row : shadows::settings_table(&params)) {
      const std::string name = "--" + std::string(section) + "." + std::string(row.key);
      if (app.count(name) > 0)
        throw CLI::ValidationError(name, "a parameter of " + std::string(section) + ", which " + by + " does not render");
    }
  });
}

// Options of the map and adaptive sections that no configuration the command renders reads
// (shadows::unread_setting, the one list of them) are refused, naming the option and why: the run
// would ignore them without a word (--map.virtual_pool_pages 1 with maps, --map.cascades 4 with a
// virtual shadow map). `stands_for` pairs a tool's own option with the setting it sets
// ({"--resolution", "map.resolution_texels"}: a virtual map reads no resolution, and rendered one
// image per value). `rendered`: the settings of every configuration the command renders.
inline void refuse_unread_settings(const CLI::App& app, const std::vector<shadows::ShadowSettings>& rendered,
                                   const std::vector<std::pair<std::string, std::string>>& stands_for = {}) {
  const auto why_unread = [&](std::string_view section, std::string_view key) {
    std::string why;
    for (const shadows::ShadowSettings& s : rendered) {
      const std::string w = shadows::unread_setting(s, section, key);
      if (w.empty()) return std::string();
      if (why.empty()) why = w;
    }
    return why;
  };
  const auto check_section = [&](std::string_view section, const auto& params) {
    for (const auto& row : shadows::settings_table(&params)) {
      const std::string name = "--" + std::string(section) + "." + std::string(row.key);
      if (app.count(name) == 0) continue;
      if (const std::string why = why_unread(section, row.key); !why.empty()) throw CLI::ValidationError(name, "not read: " + why);
    }
  };
  const shadows::ShadowSettings probe;
  check_section("map", probe.map);
  check_section("adaptive", probe.adaptive);
  for (const auto& [option, setting] : stands_for) {
    const std::size_t dot = setting.find('.');
    if (app.count(option) == 0 || dot == std::string::npos) continue;
    if (const std::string why = why_unread(setting.substr(0, dot), setting.substr(dot + 1)); !why.empty())
      throw CLI::ValidationError(option, "not read (it sets " + setting + "): " + why);
  }
}

// Items of --techniques: a technique of the registry, or also "all" where the tool takes it; refused
// while parsing, naming the option (exit 2), like any other bad item of a list.
inline cli::ListItem<std::string> technique_items(bool with_all) {
  std::vector<std::string> names(shadows::technique_names().begin(), shadows::technique_names().end());
  if (with_all) names.emplace_back("all");
  return cli::one_of(std::move(names));
}

// Items of --scenes: a built-in scene's name, or a scene file (.json), which is read (and blamed,
// exit 1) later.
inline cli::ListItem<std::string> scene_items() {
  std::string one;
  for (const std::string_view n : scene::builtin_scene_names()) one += (one.empty() ? "" : ", ") + std::string(n);
  return {"a built-in scene (" + one + ") or a scene file ending in .json",
          [](const std::string& s) -> std::optional<std::string> {
            const auto builtin = scene::builtin_scene_names();
            if (std::find(builtin.begin(), builtin.end(), s) != builtin.end()) return s;
            if (s.size() > 5 && s.compare(s.size() - 5, 5, ".json") == 0) return s;
            return std::nullopt;
          }};
}

// --light-size: overrides the scene light's size; `size` < 0 (its default here) keeps the scene's.
// Which range applies depends on the scene's light, so override_light_size checks it once the
// scene is loaded.
inline void add_light_size_option(CLI::App& app, float& size) {
  app.add_option("--light-size", size,
                 "override the scene light's size: angular diameter in degrees, in [0, 90], for a directional light (the sun's "
                 "is 0.53), or width in world units for a spot light")
      ->check(cli::finite_range(0.0, 1e6));
}

// The --light-size override applied to `light`: a directional light's angular diameter beyond 90°
// is refused naming the option (180° failed as "the shadow map's frame is not finite", exit 1, and
// 400° rendered as 40°).
inline void override_light_size(float size, scene::Light& light) {
  if (size < 0) return;
  if (light.type == scene::Light::Type::directional && size > scene::Light::kMaxAngularDiameterDeg) {
    char line[200];
    std::snprintf(line, sizeof line,
                  "--light-size %g: a directional light's angular diameter must lie in [0, 90] degrees (the sun's is 0.53)", size);
    throw cli::UsageError(line);
  }
  light.size = size;
}

// --calibration FILE: the constant c of the adaptive rule per technique, from the fitter's
// calibration.json (by default the published c: calibration/default.json of the installed data or
// the source tree's data/, tool::data_file). apply_calibration() reads it once the command line is
// parsed; apply_calibration_for() sets c for each technique an app renders.
struct CalibrationOption {
  std::string file = tool::data_file("calibration/default.json").string();
  adaptive::Calibration loaded;      // after apply_calibration
  bool c_from_command_line = false;  // --adaptive.c was given and wins over the file
  bool ci_upper = false;             // use the entries' upper ci95 bound instead of c
  float command_line_c = 0;          // --adaptive.c's value when given
  // --adaptive.observer-percentile P: c for the P-th percentile observer of the entry's population
  // (penumbra-fit's multilevel block) instead of the sample's c; 0: the entry's c.
  double observer_percentile = 0;

  // The entry the file has for the settings' technique and kernel (or its fallback). PCF's Poisson
  // disk rotated per pixel is another filter than the unrotated one every entry was measured with.
  adaptive::CalibrationChoice choice(const shadows::ShadowSettings& s) const {
    const std::string kernel = shadows::variant_choice(s);
    return loaded.choose(shadows::to_string(s.technique), kernel, rotated(s));
  }
  static bool rotated(const shadows::ShadowSettings& s) {
    return s.technique == shadows::Technique::pcf && shadows::variant_choice(s) == "poisson" && s.pcf.rotate;
  }
  // Where the settings' c came from, for a line of output: --adaptive.c, or the file's entry.
  std::string source_of_c(const shadows::ShadowSettings& s) const {
    return c_from_command_line ? "--adaptive.c" : choice(s).from + " of " + loaded.source;
  }
};

inline void add_calibration_option(CLI::App& app, CalibrationOption& calibration) {
  app.add_option("--calibration", calibration.file,
                 "calibration.json with the constant c of the adaptive rule per technique (an explicit --adaptive.c wins over the file)")
      ->capture_default_str()
      ->check(cli::path_given());
  app.add_option("--adaptive.observer-percentile", calibration.observer_percentile,
                 "c for the P-th percentile observer of the entry's population (P in (0, 100): 90 hides the artifact at the "
                 "entry's criterion for 90 % of observers), from the entry's population block (penumbra-fit's multilevel fit); "
                 "an entry without one is refused")
      ->check(CLI::Range(0.0, 100.0));
}

// The entry whose c the rule reads: the chosen entry (or the published value), with c and ci95
// replaced by the percentile observer's when --adaptive.observer-percentile asks for one. An
// entry without a population block is refused naming the option.
inline adaptive::CalibrationEntry entry_for_c(const CalibrationOption& calibration, const adaptive::CalibrationChoice& chosen) {
  adaptive::CalibrationEntry entry = chosen.entry.value_or(adaptive::CalibrationEntry{});
  if (!chosen.entry) entry.ci95_lo = entry.ci95_hi = entry.c = chosen.c;
  if (calibration.observer_percentile <= 0) return entry;
  if (!(calibration.observer_percentile < 100))
    throw CLI::ValidationError("--adaptive.observer-percentile", "expected a percentile in (0, 100), got 100");
  adaptive::CAtPercentile at;
  try {
    if (!chosen.entry) throw std::invalid_argument(chosen.from + " has no population block");
    at = adaptive::c_at_observer_percentile(entry, calibration.observer_percentile);
  } catch (const std::invalid_argument& e) {
    throw CLI::ValidationError("--adaptive.observer-percentile", std::string(e.what()) + " (" + calibration.loaded.source + ")");
  }
  entry.c = at.c;
  entry.has_ci95 = std::isfinite(at.lo) && std::isfinite(at.hi);
  entry.ci95_lo = entry.has_ci95 ? std::min(at.lo, at.c) : at.c;
  entry.ci95_hi = entry.has_ci95 ? std::max(at.hi, at.c) : at.c;
  return entry;
}

// Sets settings.adaptive.c to the c of the settings' technique (its ci95 upper bound with
// ci_upper), unless --adaptive.c was given. Call it again whenever the technique changes.
inline void apply_calibration_for(const CalibrationOption& calibration, shadows::ShadowSettings& settings) {
  if (calibration.c_from_command_line) {
    settings.adaptive.c = calibration.command_line_c;
    return;
  }
  const adaptive::CalibrationChoice chosen = calibration.choice(settings);
  const adaptive::CalibrationEntry entry = entry_for_c(calibration, chosen);
  if (settings.adaptive.visibility > 0) {
    // c at the chosen detection probability on the entry's psychometric function, within the
    // range adaptive.c takes: far from the entry's criterion, or with a shallow slope, it leaves
    // every usable c (F 1e-15: 69 215 texels; criterion 1e-6 with slope 0.01 at 0.999: 0).
    const adaptive::CAtVisibility at = adaptive::c_at_visibility(entry, settings.adaptive.visibility);
    const double c = calibration.ci_upper ? at.hi : at.c;
    double lo = 0, hi = 0;
    for (const auto& row : shadows::settings_table(&settings.adaptive))
      if (row.key == "c") lo = row.min, hi = row.max;
    if (!(c >= lo && c <= hi)) {
      const adaptive::ThresholdDefinition& t = entry.definition();
      char line[400];
      std::snprintf(line, sizeof line,
                    "at F = %.6g the %s of %s (c %.6g at its criterion F = %.6g, %s slope %.6g) gives c = %.6g texels, outside "
                    "[%g, %g]; choose a visibility nearer its criterion",
                    settings.adaptive.visibility, chosen.from.c_str(), calibration.loaded.source.c_str(), entry.c, t.criterion_f,
                    t.family.c_str(), t.beta, c, lo, hi);
      throw CLI::ValidationError("--adaptive.visibility", line);
    }
    settings.adaptive.c = static_cast<float>(c);
    return;
  }
  settings.adaptive.c = static_cast<float>(calibration.ci_upper ? entry.ci95_hi : entry.c);
}

// For a window whose panel can switch the technique: re-applies the calibration when the technique
// or its kernel changed since the last call, so a c edited in the panel stays until then.
class CalibrationFollower {
 public:
  void update(const CalibrationOption& calibration, shadows::ShadowSettings& settings) {
    const std::string key = std::string(shadows::to_string(settings.technique)) + " " + shadows::variant_choice(settings);
    if (key == last_) return;
    if (!last_.empty()) apply_calibration_for(calibration, settings);
    last_ = key;
  }

 private:
  std::string last_;
};

// Reads the calibration file (throws adaptive::CalibrationError naming the file and the field,
// also for a technique the registry does not know) and applies it to `settings`. Call it before
// creating any output.
inline void apply_calibration(const CLI::App& app, CalibrationOption& calibration, shadows::ShadowSettings& settings,
                              bool ci_upper = false) {
  calibration.loaded = adaptive::load_calibration(calibration.file);
  for (std::size_t i = 0; i < calibration.loaded.entries.size(); ++i) {
    const adaptive::CalibrationEntry& entry = calibration.loaded.entries[i];
    const std::string at = calibration.loaded.source + ": entries[" + std::to_string(i) + "]";
    shadows::Technique technique{};
    try {
      technique = shadows::technique_from_string(entry.technique);
    } catch (const std::invalid_argument& e) {
      throw adaptive::CalibrationError(at + ".technique: " + e.what());
    }
    // A kernel the technique does not have would never be chosen and its entry would stand in as
    // the technique's fallback ("gauss" for pcf): refused.
    const std::vector<std::string> kernels = shadows::variant_choices(technique);
    if (!entry.kernel.empty() && std::find(kernels.begin(), kernels.end(), entry.kernel) == kernels.end()) {
      std::string known;
      for (const auto& k : kernels) known += (known.empty() ? "" : ", ") + k;
      throw adaptive::CalibrationError(at + ".kernel: '" + json_input::printable(entry.kernel) + "' is not a kernel of " + entry.technique +
                                       (known.empty() ? " (it has none: omit the field)" : " (known: " + known + ")"));
    }
  }
  const CLI::Option* explicit_c = app.get_option_no_throw("--adaptive.c");
  calibration.c_from_command_line = explicit_c && explicit_c->count() > 0;
  // An explicit c is taken as it is: a visibility beside it would be recorded and never used.
  if (const CLI::Option* visibility = app.get_option_no_throw("--adaptive.visibility");
      calibration.c_from_command_line && visibility && visibility->count() > 0)
    throw CLI::ValidationError("--adaptive.visibility", "not read: --adaptive.c gives c itself (the visibility sets c from the calibration "
                                                        "entry); give one of them");
  if (const CLI::Option* percentile = app.get_option_no_throw("--adaptive.observer-percentile");
      calibration.c_from_command_line && percentile && percentile->count() > 0)
    throw CLI::ValidationError("--adaptive.observer-percentile", "not read: --adaptive.c gives c itself (the percentile sets c from the "
                                                                 "calibration entry's population); give one of them");
  calibration.command_line_c = settings.adaptive.c;
  calibration.ci_upper = ci_upper;
  apply_calibration_for(calibration, settings);
}

// The line every renderer app prints before it renders with the adaptive rule: the c it uses for
// the settings' technique, where it came from, and what the fitter flagged ("c for pcf disk = 3.47
// texels: pcf disk entry (published) of data/calibration/default.json").
inline std::string calibration_line(const CalibrationOption& calibration, const shadows::ShadowSettings& settings) {
  const std::string kernel = shadows::variant_choice(settings);
  const std::string name = std::string(shadows::to_string(settings.technique)) + (kernel.empty() ? "" : " " + kernel);
  char c[32];
  std::snprintf(c, sizeof c, "%.3g", settings.adaptive.c);
  std::string line = "c for " + name + " = " + c + " texels";
  if (calibration.ci_upper && !calibration.c_from_command_line) line += " (the upper ci95 bound)";
  if (!calibration.c_from_command_line) {
    // What c means: the detection probability at which the staircase is still seen.
    const adaptive::CalibrationChoice chosen = calibration.choice(settings);
    const double criterion = chosen.entry ? chosen.entry->definition().criterion_f : adaptive::ThresholdDefinition{}.criterion_f;
    const adaptive::CalibrationEntry entry = entry_for_c(calibration, chosen);
    if (calibration.observer_percentile > 0) {
      // Asked like a visibility: whose c, from which population, with its interval.
      const adaptive::Population& p = *chosen.entry->population;
      char interval[80] = "interval open", who[400];
      if (entry.has_ci95) std::snprintf(interval, sizeof interval, "%.3g, %.3g", entry.ci95_lo, entry.ci95_hi);
      const double q = calibration.observer_percentile;  // 90th, 1st, 2nd, 3rd, 11th, 97.5th
      const long whole = std::lround(q);
      const char* suffix = q != static_cast<double>(whole) || (whole % 100 >= 11 && whole % 100 <= 13) ? "th"
                           : whole % 10 == 1                                                           ? "st"
                           : whole % 10 == 2                                                           ? "nd"
                           : whole % 10 == 3                                                           ? "rd"
                                                                                                       : "th";
      std::snprintf(who, sizeof who,
                    " for the %g%s-percentile observer (c %.3g [%s] at the entry's criterion; population of %d participants: mean c "
                    "%.3g, sd %.3g log10%s)",
                    q, suffix, entry.c, interval, p.participants, p.mean_c, p.sd_log10,
                    std::abs(calibration.observer_percentile - p.percentile) < 1e-9 ? ", the fitted percentile"
                                                                                    : ", from the mean and the spread");
      line += who;
    }
    char at[320];
    if (settings.adaptive.visibility > 0) {
      // The interval at F: c's and the slope's, and the psychometric family's spread (a study's
      // trials sit near the criterion; the tail is the family's, adaptive::c_at_visibility).
      const adaptive::CAtVisibility range = adaptive::c_at_visibility(entry, settings.adaptive.visibility);
      std::snprintf(at, sizeof at,
                    " at visibility F = %.3g (the entry's c %.3g is at its criterion F = %.3g), [%.3g, %.3g] over c, the slope and the "
                    "psychometric family (the family alone [%.3g, %.3g])",
                    settings.adaptive.visibility, entry.c, criterion, range.lo, range.hi, range.family_lo, range.family_hi);
      // An entry that states no slope (the published constant; predicted.json's image-observer
      // entries made before they recorded the observer's own) is read with QUEST's 3.5: said.
      if (entry.definition().beta_assumed)
        std::snprintf(at + std::strlen(at), sizeof at - std::strlen(at), ", slope %.3g assumed (the entry states none)",
                      entry.definition().beta);
    } else
      std::snprintf(at, sizeof at, " at the entry's criterion, detection probability F = %.3g", criterion);
    line += at;
  }
  line += ": " + calibration.source_of_c(settings);
  if (!calibration.c_from_command_line)
    if (const std::string w = calibration.choice(settings).warnings(); !w.empty()) line += "; " + w;
  return line;
}

// The record for report.json: {file, schema_version, technique, kernel, c (as used), ci95, entry,
// obtained_by, observers, fallback, from, source_of_c, flags, usable}.
inline nlohmann::json calibration_json(const CalibrationOption& calibration, const shadows::ShadowSettings& settings) {
  const adaptive::CalibrationChoice chosen = calibration.choice(settings);
  const std::string kernel = shadows::variant_choice(settings);
  nlohmann::json j = {{"file", calibration.loaded.source},
                      {"schema_version", calibration.loaded.schema_version},
                      {"technique", std::string(shadows::to_string(settings.technique))},
                      {"kernel", kernel.empty() ? nlohmann::json(nullptr) : nlohmann::json(kernel)},
                      {"c", settings.adaptive.c},
                      {"ci95", chosen.has_ci95 ? nlohmann::json{chosen.ci95_lo, chosen.ci95_hi} : nlohmann::json(nullptr)},  // null: none
                      {"entry", chosen.entry ? nlohmann::json(chosen.entry->label()) : nlohmann::json(nullptr)},
                      {"obtained_by", chosen.entry ? std::string(adaptive::method_name(chosen.entry->obtained_by)) : "published"},
                      {"observers", chosen.entry ? std::string(adaptive::method_description(chosen.entry->obtained_by)) : "published"},
                      {"fallback", chosen.fallback},
                      {"fallback_reason", chosen.fallback ? nlohmann::json(chosen.fallback_reason) : nlohmann::json(nullptr)},
                      {"would_match", chosen.fallback ? nlohmann::json(chosen.would_match) : nlohmann::json(nullptr)},
                      {"rotate", CalibrationOption::rotated(settings)},
                      {"from", chosen.from},
                      {"source_of_c", calibration.c_from_command_line ? "--adaptive.c" : "file"},
                      {"flags", chosen.entry ? chosen.entry->flags : std::vector<std::string>{}},
                      {"usable", !chosen.entry || chosen.entry->usable},
                      {"visibility", settings.adaptive.visibility > 0 ? nlohmann::json(settings.adaptive.visibility) : nlohmann::json("criterion")},
                      {"criterion_f", chosen.entry ? chosen.entry->definition().criterion_f : adaptive::ThresholdDefinition{}.criterion_f},
                      {"c_at_criterion", chosen.c},
                      {"observer_percentile", calibration.observer_percentile > 0 ? nlohmann::json(calibration.observer_percentile)
                                                                                  : nlohmann::json(nullptr)}};
  const adaptive::CalibrationEntry entry = calibration.c_from_command_line ? adaptive::CalibrationEntry{} : entry_for_c(calibration, chosen);
  if (calibration.observer_percentile > 0 && !calibration.c_from_command_line) {
    // The percentile observer's c at the entry's criterion and its interval (null: open).
    j["c_for_percentile"] = entry.c;
    j["ci95_for_percentile"] = entry.has_ci95 ? nlohmann::json{entry.ci95_lo, entry.ci95_hi} : nlohmann::json(nullptr);
  }
  if (settings.adaptive.visibility > 0 && !calibration.c_from_command_line) {
    const adaptive::CAtVisibility at = adaptive::c_at_visibility(entry, settings.adaptive.visibility);
    // Only an interval there is (of c, of an estimated slope, or the family's away from the
    // criterion): none is written as null.
    j["ci95_at_visibility"] = at.lo < at.hi ? nlohmann::json{at.lo, at.hi} : nlohmann::json(nullptr);
    j["family_at_visibility"] = {at.family_lo, at.family_hi};
  }
  if (chosen.entry && !chosen.entry->usable) j["unusable_because"] = chosen.entry->unusable_because;
  return j;
}

}  // namespace penumbra::apps
