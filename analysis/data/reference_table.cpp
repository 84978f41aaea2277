#include "data/reference_table.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>
#include <stdexcept>

#include "json/json_input.h"

namespace penumbra::analysis {

const ReferenceEntry* ReferenceTable::find(const std::string& pattern, double contrast, double artifact_px) const {
  for (const ReferenceEntry& e : entries)
    if (e.pattern == pattern && std::abs(e.contrast - contrast) < 1e-9 && std::abs(e.artifact_px - artifact_px) < 1e-9)
      return &e;
  return nullptr;
}

ReferenceTable load_reference_table(const std::filesystem::path& path) {
  const nlohmann::json j = json_input::read_file(path, {.max_bytes = 16 << 20, .max_depth = 16});
  ReferenceTable table;
  table.file = path.string();
  if (!j.is_object() || !j.contains("entries") || !j["entries"].is_array())
    throw std::runtime_error(table.file + ": entries: expected an array (written by penumbra-study reference)");
  for (std::size_t i = 0; i < j["entries"].size(); ++i) {
    const auto& e = j["entries"][i];
    const std::string where = table.file + ": entries[" + std::to_string(i) + "].";
    auto number = [&](const char* key) {
      if (!e.contains(key) || !e[key].is_number()) throw std::runtime_error(where + key + ": expected a number");
      return e[key].get<double>();
    };
    ReferenceEntry r;
    if (!e.contains("pattern") || !e["pattern"].is_string()) throw std::runtime_error(where + "pattern: expected a string");
    r.pattern = e["pattern"].get<std::string>();
    r.contrast = number("contrast");
    r.artifact_px = number("artifact_px");
    if (!e.contains("reference_filter_radius_px"))
      throw std::runtime_error(where + "reference_filter_radius_px: missing (a number or null)");
    if (!e["reference_filter_radius_px"].is_null()) {
      r.reference_px = number("reference_filter_radius_px");
      if (!(*r.reference_px > 0)) throw std::runtime_error(where + "reference_filter_radius_px: expected > 0");
    }
    if (e.contains("search") && e["search"].is_object() && e["search"].contains("r_max_px") &&
        e["search"]["r_max_px"].is_number())
      r.r_max_px = e["search"]["r_max_px"].get<double>();
    if (e.contains("monotone") && e["monotone"].is_boolean()) r.monotone = e["monotone"].get<bool>();
    table.entries.push_back(r);
  }
  return table;
}

}  // namespace penumbra::analysis
