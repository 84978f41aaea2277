#pragma once
// Simulated studies without GL, for tests, the benchmark and planning: each participant runs the
// study's procedure (per condition one QUEST per artifact size, interleaved at random, QUEST's
// quantile clamped to the intensity bounds, the radius clamped to what a stimulus can show)
// against the planted psychometric observer of study/observers. The rows are what penumbra-study
// would log for the same answers (no practice trials, fixed trial count per staircase).
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "data/dataset.h"
#include "log/trial_log.h"
#include "observers/psychometric_observer.h"
#include "quest/quest.h"

namespace penumbra::analysis {

struct SimulatedCondition {
  std::string pattern = "stair";
  double contrast = 1.0;
  observers::PlantedModel planted;  // c_true, family, slope, lapse, p_threshold
};

struct SimulatedStudy {
  int participants = 10;
  std::vector<double> artifact_px = {5, 10, 20};
  int trials_per_staircase = 40;
  std::vector<SimulatedCondition> conditions = {SimulatedCondition{}};
  // Participant i's c is c_true * 10^(z_i * participant_sd_log10), z_i standard normal.
  double participant_sd_log10 = 0.0;
  quest::QuestParams quest = {-0.5, 1.0, 0.82, 3.5, 0.01, 0.5, 0.01, {}};
  double intensity_min = -2.0, intensity_max = 1.0;
  int stimulus_size_px = 320;  // radius shown in [1, size / 2]
  std::uint64_t seed = 1;
};

struct SimulatedSession {
  std::string participant;
  double c_planted = 0;  // this participant's c (first condition's, times its spread)
  std::vector<trial_log::TrialRow> rows;
};

// Throws std::invalid_argument for a bad study (no participants, sizes <= 0, ...).
std::vector<SimulatedSession> simulate_study(const SimulatedStudy& study);

// The sessions as the fitter's input, without files (QUEST parameters as a session.json would hold).
Dataset as_dataset(const SimulatedStudy& study, const std::vector<SimulatedSession>& sessions);

// Writes each session as DIR/<participant>/{trials.csv, session.json} (the study's layout);
// returns the session directories.
std::vector<std::filesystem::path> write_sessions(const SimulatedStudy& study,
                                                  const std::vector<SimulatedSession>& sessions,
                                                  const std::filesystem::path& dir);

}  // namespace penumbra::analysis
