#pragma once
// Command-line helpers shared by the apps: options generated from a settings table,
// comma-separated number lists, the light-size override, and parsing with one-line errors.
// Errors are CLI::ValidationError naming the option.
#include <CLI/CLI.hpp>

#include <cmath>
#include <iostream>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "cli/checks.h"
#include "shadows/settings.h"

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

// "a,b,c" → numbers in [lo, hi]; integers only when T is integral. Throws CLI::ValidationError
// naming `option` and the accepted form.
template <class T>
std::vector<T> parse_list(const std::string& option, const std::string& text, T lo, T hi) {
  std::ostringstream expected;
  expected << (std::is_integral_v<T> ? "integers" : "numbers") << " in [" << lo << ", " << hi << "] separated by commas, got '" << text
           << "'";
  std::vector<T> out;
  std::size_t pos = 0;
  for (;;) {
    const std::size_t comma = text.find(',', pos);
    const std::string item = text.substr(pos, comma == std::string::npos ? std::string::npos : comma - pos);
    std::size_t used = 0;
    double v = NAN;
    try {
      v = std::stod(item, &used);
    } catch (...) {
      used = 0;
    }
    if (item.empty() || used != item.size() || !std::isfinite(v) || v < static_cast<double>(lo) || v > static_cast<double>(hi) ||
        (std::is_integral_v<T> && v != std::floor(v)))
      throw CLI::ValidationError(option, "expected " + expected.str());
    out.push_back(static_cast<T>(v));
    if (comma == std::string::npos) break;
    pos = comma + 1;
  }
  return out;
}

// --light-size: overrides the scene light's size; `size` < 0 (its default here) keeps the scene's.
inline void add_light_size_option(CLI::App& app, float& size) {
  app.add_option("--light-size", size,
                 "override the scene light's size: angular diameter in degrees (directional) or width in world units (spot)")
      ->check(cli::finite_range(0.0, 1e6));
}

// Parses the command line. Returns the exit status to leave with — 0 after --help, 2 after a
// parse error (one line "<tool>: <error>" on stderr) — or nullopt to go on.
inline std::optional<int> parse_command_line(CLI::App& app, int argc, char** argv, const char* tool) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::cerr << tool << ": " << e.what() << "\n";
    return 2;
  }
  return std::nullopt;
}

}  // namespace penumbra::apps
