#include "tool/tool.h"

#include <system_error>

namespace penumbra::tool {
namespace {

namespace fs = std::filesystem;

// The installed tree, relative to the directory of the executable (from GNUInstallDirs, e.g.
// "../share/penumbra"), or empty when the executable does not lie in one.
const fs::path& installed_data_dir() {
  static const fs::path dir = [] {
    std::error_code ec;
    const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
    if (ec) return fs::path();
    const fs::path data = (exe.parent_path() / PENUMBRA_DATA_FROM_BINDIR).lexically_normal();
    return fs::is_directory(data, ec) ? data : fs::path();
  }();
  return dir;
}

}  // namespace

std::string_view version() { return PENUMBRA_VERSION; }

std::string version_line(std::string_view tool) {
  return std::string(tool) + " " + std::string(version()) + " (git " + std::string(git_revision()) + ")";
}

bool installed() { return !installed_data_dir().empty(); }

fs::path data_file(std::string_view relative) {
  return installed() ? installed_data_dir() / relative : fs::path(PENUMBRA_SOURCE_DIR) / "data" / relative;
}

fs::path script_file(std::string_view name) {
  return installed() ? installed_data_dir() / "scripts" / name : fs::path(PENUMBRA_SOURCE_DIR) / "scripts" / name;
}

fs::path docs_page(std::string_view page) {
  return installed() ? (installed_data_dir() / PENUMBRA_DOCS_FROM_DATADIR / page).lexically_normal()
                     : fs::path(PENUMBRA_SOURCE_DIR) / "docs" / page;
}

}  // namespace penumbra::tool
