#pragma once
// Input of `penumbra-fit psychometric`: one data set as CSV, either counts per level
// (`level,n_correct,n_total`) or one row per trial (`level,correct` with correct 0 or 1). A header
// line naming those columns is optional; blank lines are skipped.
#include <filesystem>
#include <string>
#include <vector>

#include "fit/model_fit.h"

namespace penumbra::analysis {

enum class LevelFormat { counts, trials };

// Rows as read (trials are not merged). Throws std::runtime_error "<file>:<line>: column '<name>':
// <what> (found '<text>')" for malformed, non-finite or inconsistent values, and for a file without rows.
std::vector<BinomialRow> read_level_data(const std::filesystem::path& path, LevelFormat format);

}  // namespace penumbra::analysis
