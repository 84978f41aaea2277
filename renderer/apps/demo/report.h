#pragma once
// What penumbra-demo says about a walk (measurement.h): the adaptive configuration against the
// engine family's Pareto front at equal error (stats/pareto.h), report.json's technique entry,
// and the printed tables.
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "apps/demo/measurement.h"
#include "stats/pareto.h"

namespace penumbra::demo {

// The adaptive configuration read against the engine front at equal error, the error being one of
// (ErrorMeasure): the mean FLIP of the lit frames against the target reference over the reference
// frames (the perceived difference, the headline's first line), PCSS's mean FLIP against the
// ray-traced sun, or the mean RMSE of the visibility against the reference (the second line);
// time = frame ms (paired per frame along the path); memory = texels allocated for the maps (the
// same format within a technique).
struct FrontComparison {
  std::vector<std::size_t> front;  // series indices, error ascending
  stats::FrontReading reading;     // indices into the series
  stats::RatioInterval ratio;      // engine at equal error / adaptive, per frame
};
// A virtual map's configuration read against the same front at its own error.
enum class ErrorMeasure {
  flip,             // mean FLIP against the target (PCF: the reference; PCSS: converged PCSS)
  flip_ray_traced,  // PCSS: mean FLIP against the ray-traced sun
  rmse,             // mean RMSE of the visibility against the reference
};
// "FLIP" or "RMSE" (the headline's "at FLIP 0.0071"), and what it is measured against.
const char* measure_label(ErrorMeasure m);
// A configuration's error by `m` (NaN where it was not measured).
double error_of(const Series& s, ErrorMeasure m);

struct VirtualReading {
  ErrorMeasure measure = ErrorMeasure::rmse;
  std::size_t series = 0;
  double error = 0;
  FrontComparison time, memory;
  FrontComparison shadow;  // on the shadow's cost: frame ms minus the unshadowed floor, per frame
};
struct EqualError {
  ErrorMeasure measure = ErrorMeasure::rmse;
  bool available = false;
  std::string why_not;             // when not available
  double adaptive_error = 0;
  std::vector<std::size_t> family;  // series indices of the engine family (the fixed map included)
  FrontComparison time, memory;
  FrontComparison shadow;  // on the shadow's cost (Series::shadow_ms); empty without a floor
  std::vector<VirtualReading> virtual_maps;  // each virtual configuration (Role::virtual_pages)
};
EqualError equal_error(const TechniqueRun& run, ErrorMeasure measure = ErrorMeasure::rmse);
// Every reading the run has: FLIP (when measured), FLIP against the ray-traced sun (PCSS), RMSE.
struct EqualErrors {
  EqualError flip, flip_ray_traced, rmse;
  // The readings to print, headline first.
  std::vector<const EqualError*> shown() const;
};
EqualErrors equal_errors(const TechniqueRun& run);
// "pcf    virtual rule at RMSE 0.0402: speedup ..., memory ratio ...", as headline() for the adaptive maps.
std::string virtual_headline(const TechniqueRun& run, const VirtualReading& v);

// The frame observer's verdict on the family: the cheapest timed configuration (by median frame
// time, and by memory allocated) it cannot tell from the target reference at the technique's
// criterion F at any reference frame; none when it tells every one apart.
struct Unseen {
  bool measured = false;
  double criterion_f = 0;
  std::optional<std::size_t> by_time, by_memory;  // series indices
  std::vector<std::size_t> unseen;                // every configuration it cannot tell apart
};
Unseen cheapest_unseen(const TechniqueRun& run);
// "pcf    the observer (F = 0.674) cannot tell 4 of 11 from the reference: cheapest fixed-2048 (32.8 ms) ..."
std::string unseen_line(const TechniqueRun& run, const Unseen& u);

// Mean RMSE against the reference over the reference frames (NaN without a reference).
double reference_rmse(const Series& s);

// The run's entry in report.json's "techniques" (settings and calibration are the caller's).
nlohmann::json technique_json(const TechniqueRun& run, const EqualErrors& eq);

// One line per technique for the head of the output: "pcf   at RMSE 0.0402 ...: speedup 1.19x
// [1.10, 1.25], memory ratio 0.50x [...]".
std::string headline(const TechniqueRun& run, const EqualError& eq);

// The single-map comparison (fixed vs adaptive) as one row of the table under the headline (text
// ending in a newline: printed by the run, carried by a shard's part to the merge).
std::string single_map_row(const TechniqueRun& run);
// Every configuration against the engine baseline and the reference, the thin casters, PCSS's
// clamped pixels and flicker along the path.
std::string tables(const TechniqueRun& run, const EqualErrors& eq);

}  // namespace penumbra::demo
