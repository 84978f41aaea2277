#pragma once
// What every app does with an error: one line "<tool>: <message>" on stderr (text::one_line: no
// control bytes, no megabyte words) and a documented exit status (docs/tools.md): 2 for a command
// line that cannot be used, 1 for everything else (a bad file, a refused session, a failed write).
// The command line is at fault for CLI11's ParseError (whose own exit codes are 100-plus and whose
// own message adds a second line), for a cli::UsageError, and for any error whose line begins with
// an option's name ("--observer: ...", "-o: ..."): the tools name the option first exactly when
// the command line, not a file, is what must change. One rule, here, for every tool: exit_code().
// And what every app says about itself: --version, and --help ending with its docs page.
#include <CLI/CLI.hpp>

#include <cctype>
#include <exception>
#include <iostream>
#include <optional>
#include <stdexcept>
#include <string_view>

#include "text/printable.h"
#include "tool/tool.h"

namespace penumbra::cli {

constexpr int kExitError = 1;
constexpr int kExitUsage = 2;

// --version ("penumbra-render 0.1.0 (git abc1234)") and a --help footer naming the tool's page of
// docs/ and the exit codes (docs/tools.md), with paths where this copy of the tool finds them
// (installed or in the source tree). Call it before adding subcommands: they copy the footer.
inline void describe_tool(CLI::App& app, std::string_view tool, std::string_view docs_page) {
  app.set_version_flag("--version", tool::version_line(tool), "print the version and git revision, and exit");
  app.footer("Documentation: " + tool::docs_page(docs_page).string() +
             "\nExit codes: 0 done, 1 bad input or data (one line on stderr), 2 unusable command line; " +
             tool::docs_page("tools.md").string());
}

// A command-line value that cannot be used, found after parsing (two options that contradict
// each other, a value the tool cannot do); its message need not start with the option's name.
class UsageError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

// The exit status for an error that ended a tool: kExitUsage when the command line is at fault
// (a UsageError, or a message that begins with an option's name), else kExitError.
inline int exit_code(const std::exception& e) {
  if (dynamic_cast<const UsageError*>(&e)) return kExitUsage;
  const std::string_view m = e.what();
  const bool names_option = m.size() >= 2 && m[0] == '-' && (m[1] == '-' ? m.size() > 2 && std::isalpha(static_cast<unsigned char>(m[2]))
                                                                          : std::isalpha(static_cast<unsigned char>(m[1])) != 0);
  return names_option ? kExitUsage : kExitError;
}

// Prints "<tool>: <message>" as one line and returns `status`.
inline int fail(std::string_view tool, std::string_view message, int status = kExitError) {
  std::cerr << tool << ": " << text::one_line(message) << "\n";
  return status;
}
// The same for an exception, with exit_code()'s status.
inline int fail(std::string_view tool, const std::exception& e) { return fail(tool, e.what(), exit_code(e)); }

// app.parse: nullopt to go on, or the status to leave with: 0 after --help or --version (printed),
// 2 after a parse error (one line).
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
