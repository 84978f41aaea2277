#pragma once
// What penumbra-fit writes: calibration.json (the contract in docs/architecture.md, read by the
// renderer's adaptive::load_calibration), report.json (every number, for people and the plotting
// script) and a plain-text summary table.
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "data/dataset.h"
#include "data/reference_table.h"
#include "fit/model_fit.h"
#include "fit/study_fit.h"

namespace penumbra::analysis {

// A number, or null when it is not finite (JSON has no NaN).
nlohmann::json number(double v);
nlohmann::json to_json(const FitResult& fit, const ModelSpec& spec);

// The condition whose c goes into calibration.json: `wanted`, or the one with the largest c.
// Throws std::invalid_argument naming the conditions for an unknown `wanted`.
const ConditionFit& calibration_condition(const StudyFit& fit, const std::optional<std::string>& wanted);

// What the fitted c is an entry for in calibration.json: the technique and kernel of the study's
// filter, and how the answers were given (people: study; a simulated observer: image-observer or
// simulated).
struct CalibrationProvenance {
  std::string technique = "pcf";
  std::string kernel;                 // the stimulus kernel as logged (disk, grid, poisson)
  std::string obtained_by = "study";  // study, image-observer, simulated
  int participants = 0;               // distinct participant ids
};
// From the logs and session.json files; throws std::runtime_error naming two sessions that
// disagree in kernel or observer kind (they measure different things and are not pooled).
CalibrationProvenance calibration_provenance(const Dataset& data);

// calibration.json (schema_version 2, data/calibration/calibration.schema.json): one entry for
// the provenance's technique and kernel with the chosen condition's c and interval.
nlohmann::json calibration_json(const StudyFit& fit, const std::optional<std::string>& condition,
                                const std::string& created_utc, const std::vector<std::string>& inputs,
                                const CalibrationProvenance& provenance);
nlohmann::json report_json(const StudyFit& fit, const ReferenceTable* reference, const std::vector<std::string>& inputs,
                           const std::string& created_utc);
std::string summary_text(const StudyFit& fit, const ReferenceTable* reference,
                         const std::optional<std::string>& calibration_condition);

std::string utc_now();

}  // namespace penumbra::analysis
