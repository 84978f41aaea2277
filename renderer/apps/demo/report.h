#pragma once
// What penumbra-demo says about a walk (measurement.h): the adaptive configuration against the
// engine family's Pareto front at equal error (stats/pareto.h), report.json's technique entry,
// and the printed tables.
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "apps/demo/measurement.h"
#include "stats/pareto.h"

namespace penumbra::demo {

// The adaptive configuration read against the engine front: error = mean RMSE of the visibility
// against the reference over the reference frames; time = frame ms (paired per frame along the
// path); memory = texels allocated for the maps (the same format within a technique).
struct FrontComparison {
  std::vector<std::size_t> front;  // series indices, error ascending
  stats::FrontReading reading;     // indices into the series
  stats::RatioInterval ratio;      // engine at equal error / adaptive, per frame
};
// A virtual map's configuration read against the same front at its own error.
struct VirtualReading {
  std::size_t series = 0;
  double error = 0;
  FrontComparison time, memory;
};
struct EqualError {
  bool available = false;
  std::string why_not;             // when not available
  double adaptive_error = 0;
  std::vector<std::size_t> family;  // series indices of the engine family (the fixed map included)
  FrontComparison time, memory;
  std::vector<VirtualReading> virtual_maps;  // each virtual configuration (Role::virtual_pages)
};
EqualError equal_error(const TechniqueRun& run);
// "pcf    virtual rule at RMSE 0.0402: speedup ..., memory ratio ...", as headline() for the adaptive maps.
std::string virtual_headline(const TechniqueRun& run, const VirtualReading& v);

// Mean RMSE against the reference over the reference frames (NaN without a reference).
double reference_rmse(const Series& s);

// The run's entry in report.json's "techniques" (settings and calibration are the caller's).
nlohmann::json technique_json(const TechniqueRun& run, const EqualError& eq);

// One line per technique for the head of the output: "pcf   at RMSE 0.0402 ...: speedup 1.19x
// [1.10, 1.25], memory ratio 0.50x [...]".
std::string headline(const TechniqueRun& run, const EqualError& eq);

// The single-map comparison (fixed vs adaptive) as one row of the table under the headline.
void print_single_map_row(const TechniqueRun& run);
// Every configuration against the engine baseline and the reference, the thin casters, PCSS's
// clamped pixels and flicker along the path.
void print_tables(const TechniqueRun& run, const EqualError& eq);

}  // namespace penumbra::demo
