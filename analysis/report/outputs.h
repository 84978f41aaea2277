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
// filter, and who answered (session.json's observer_kind): people (obtained_by "study"), a
// psychometric simulation ("simulated") or the image observer ("image-observer"); "mixed" only
// when kinds were pooled on request.
struct CalibrationProvenance {
  std::string technique = "pcf";
  std::string kernel;                 // the stimulus kernel as logged (disk, grid, poisson)
  std::string obtained_by = "study";  // study, image-observer, simulated, mixed
  std::string observers = "people";   // in words: people, psychometric simulation, image observer, or the kinds pooled
  std::vector<std::string> pooled_kinds;  // with pool_observers: each kind pooled, as "person (3 sessions)"
  int participants = 0;               // distinct participant ids
};
// From the logs and session.json files; throws std::runtime_error naming two sessions that
// disagree in technique, kernel or observer kind (they measure different things and are not
// pooled), unless `pool_observers` allows kinds to mix (recorded in the entry), and a log with no
// session.json (who answered it is not recorded).
CalibrationProvenance calibration_provenance(const Dataset& data, bool pool_observers = false);

// A c outside this range is taken for a failed fit, not a measurement: half an artifact of filter
// radius leaves its staircase unblurred, twenty is six times the published 3.47.
inline constexpr double kPlausibleCMin = 0.5, kPlausibleCMax = 20.0;
// Why a condition's fit must not be used as a calibration (empty if it may): it did not converge,
// its threshold or its slope sits at a bound (a slope at its upper bound is a step function: the
// interval then holds for an infinitely steep observer only), its interval is open or not
// finite, or c is implausible.
std::vector<std::string> unusable_because(const WorstCase& c);

// What calibration.json's entry takes: the study's worst case (StudyFit::worst), or with `wanted`
// (--condition) that condition's c with its profile and bootstrap intervals. Throws
// std::invalid_argument naming the conditions for an unknown `wanted`.
WorstCase entry_choice(const StudyFit& fit, const std::optional<std::string>& wanted);

// calibration.json (schema_version 2, data/calibration/calibration.schema.json): one entry for
// the provenance's technique and kernel with the chosen condition's c and interval; an unusable
// fit (unusable_because) is marked "usable": false with the reasons (penumbra-fit writes it only
// with --allow-unusable).
nlohmann::json calibration_json(const StudyFit& fit, const std::optional<std::string>& condition,
                                const std::string& created_utc, const std::vector<std::string>& inputs,
                                const CalibrationProvenance& provenance);
// Both say who answered (the provenance's observers) and, for the condition that goes into
// calibration.json, whether its fit is usable.
nlohmann::json report_json(const StudyFit& fit, const ReferenceTable* reference, const std::vector<std::string>& inputs,
                           const std::string& created_utc, const CalibrationProvenance& provenance);
std::string summary_text(const StudyFit& fit, const ReferenceTable* reference,
                         const std::optional<std::string>& calibration_condition, const CalibrationProvenance& provenance);

std::string utc_now();

}  // namespace penumbra::analysis
