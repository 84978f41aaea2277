#pragma once
// What every app does with an error: one line "<tool>: <message>" on stderr (text::one_line: no
// control bytes, no megabyte words) and a documented exit status, 2 for a command line that
// cannot be parsed (CLI11's ParseError, whose own exit codes are 100-plus and whose own message
// adds a second line), 1 for everything else (a bad file, a refused session, a failed write).
#include <CLI/CLI.hpp>

#include <iostream>
#include <optional>
#include <string_view>

#include "text/printable.h"

namespace penumbra::cli {

constexpr int kExitError = 1;
constexpr int kExitUsage = 2;

// Prints "<tool>: <message>" as one line and returns `status`.
inline int fail(std::string_view tool, std::string_view message, int status = kExitError) {
  std::cerr << tool << ": " << text::one_line(message) << "\n";
  return status;
}

// app.parse: nullopt to go on, or the status to leave with: 0 after --help (printed), 2 after a
// parse error (one line).
inline std::optional<int> parse(CLI::App& app, int argc, char** argv, std::string_view tool) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);  // --help, --help-all
    return fail(tool, e.what(), kExitUsage);
  }
  return std::nullopt;
}

}  // namespace penumbra::cli
