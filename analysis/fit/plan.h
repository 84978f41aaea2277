#pragma once
// penumbra-fit plan (issue 48): how many participants and trials a study needs, by simulation.
// Each simulated study runs the study's procedure (data/simulate.h: per condition one QUEST per
// artifact size) for N participants whose c differ by a planted spread, with one condition a
// planted fraction above the others, and is fitted as penumbra-fit fits a real one (no bootstrap).
// Over the studies: the precision of the entry's c (half-width of its ci95, per cent), the power
// to detect the planted difference (the likelihood-ratio test of "conditions differ" at alpha),
// the coverage of the worst condition's planted c by the entry's ci95 and by the population's
// interval, and the entry's bias.
#include <cstdint>
#include <vector>

namespace penumbra::analysis {

struct PlanOptions {
  int participants = 10;
  int trials_per_staircase = 40;
  std::vector<double> artifact_px = {5, 10, 20};
  int conditions = 4;
  double c = 3.0;              // the planted c of the other conditions (texels per artifact)
  double difference = 0.10;    // the worst condition lies this fraction above the others
  double sd_log10 = 0.08;      // between-participant spread of log10 c
  double beta = 3.5, lapse = 0.02;
  double alpha = 0.05;         // the test's level for power
  int studies = 40;
  std::uint64_t seed = 1;
  int threads = 0;             // studies fitted side by side (0: all cores); results do not depend on it
};

struct PlanStudy {
  double entry_c = 0, ci_lo = 0, ci_hi = 0;
  double population_lo = 0, population_hi = 0;
  double lr_p = 1;
};

struct PlanResult {
  PlanOptions options;
  std::vector<PlanStudy> studies;
  double worst_c = 0;            // the worst condition's planted c
  double power = 0;              // fraction with lr_p < alpha
  double power_se = 0;           // its Monte Carlo standard error, sqrt(p (1 - p) / studies)
  double coverage = 0, coverage_population = 0;
  double median_half_width_percent = 0;  // of the entry's ci95, (hi / lo)^(1/2) - 1
  double bias_percent = 0;       // geometric mean of entry c / worst planted c, less 1
};

// Throws std::invalid_argument for fewer than 2 participants or conditions, no studies, a negative
// difference or spread.
PlanResult plan_study(const PlanOptions& options);

}  // namespace penumbra::analysis
