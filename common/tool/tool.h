#pragma once
// What every command-line tool says about itself, and where it finds the files it ships with.
//
// A tool finds its data (the default calibration, study configs, example scenes), the plot scripts
// and the documentation next to itself when it is installed — <prefix>/share/penumbra and
// <prefix>/share/doc/penumbra, located from the executable's own path, so an unpacked package
// (`dpkg -x`) or a prefix moved elsewhere works — and in the source tree when it runs from the
// build tree.
#include <filesystem>
#include <string>
#include <string_view>

namespace penumbra::tool {

// "0.1.0": the version of project() in the top-level CMakeLists.txt.
std::string_view version();
// The source tree's commit when the tool was built: "abc1234", "abc1234-dirty" (uncommitted
// changes), or "unknown" (built outside a git checkout).
std::string_view git_revision();
// "penumbra-render 0.1.0 (git abc1234)", what --version prints.
std::string version_line(std::string_view tool);

// True when the executable lies in an installed tree (<bindir>/../share/penumbra exists).
bool installed();
// A shipped data file, `relative` to the data directory ("calibration/default.json"):
// <prefix>/share/penumbra/<relative> installed, <source>/data/<relative> in the build tree.
std::filesystem::path data_file(std::string_view relative);
// A plot script ("plot_fit.py"): <prefix>/share/penumbra/scripts/ or <source>/scripts/.
std::filesystem::path script_file(std::string_view name);
// A documentation page ("study.md"): <prefix>/share/doc/penumbra/ or <source>/docs/.
std::filesystem::path docs_page(std::string_view page);

}  // namespace penumbra::tool
