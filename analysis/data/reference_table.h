#pragma once
// Reads the reference filter sizes written by `penumbra-study reference` (study/stimuli/reference.h)
// so the fitter can show them beside the perceptual thresholds. No GL here: only the JSON.
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace penumbra::analysis {

struct ReferenceEntry {
  std::string pattern;
  double contrast = 1;
  double artifact_px = 0;
  std::optional<double> reference_px;  // empty: the images still differ at r_max
  double r_max_px = 0;
  bool monotone = true;
};

struct ReferenceTable {
  std::string file;  // the file(s) read, comma-separated
  std::vector<ReferenceEntry> entries;
  const ReferenceEntry* find(const std::string& pattern, double contrast, double artifact_px) const;
};

// Throws std::runtime_error "<file>: entries[i].<field>: <what>".
ReferenceTable load_reference_table(const std::filesystem::path& path);

}  // namespace penumbra::analysis
