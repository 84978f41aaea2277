#pragma once
// A frame study's fit (issue 46; the study: docs/study.md#frames-the-rules-own-frames): the
// threshold k* per patch and technique, per technique over its patches and over everything, each
// with a 95 % profile-likelihood interval: the multiple of the rule's c at which its frames are
// told from the reference at the criterion (QUEST's p_threshold, 82 % correct in 2AFC, F* = 0.6465
// with delta 0.01).
//
// The intensity is u = log10(1 / k), so the threshold u* means k* = 10^-u*, exactly as u* means c
// in the edge study (study_fit.h); the models are model_fit.h's: the log-Weibull with a shared
// slope and lapse across the groups of one fit, the threshold on F, QUEST's criterion. k* < 1: the
// rule's frames are told from the reference only with a map smaller than the rule's (its c is
// larger than scenes need here); k* > 1: they are told apart at the rule's own c, and the product's
// constant is too small for scenes.
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "data/dataset.h"
#include "fit/model_fit.h"
#include "fit/study_fit.h"

namespace penumbra::analysis {

struct FrameThreshold {
  std::string technique;  // "" when pooled over techniques
  std::string patch;      // "" when pooled over patches
  int trials = 0, participants = 0;
  FitResult fit;
  double k = NAN;
  Interval k_profile;     // 95 % (options.level) profile likelihood, from the threshold's
  double beta = NAN;      // the slope shared by the fit's groups
  bool usable = false;    // converged, interval closed, no flag of a threshold or slope at a bound
};

struct FrameStudyFit {
  double p_threshold = 0.82, guess = 0.5, quest_delta = 0.01, criterion_f = 0.6465;
  int sessions = 0, trials = 0, practice_rows_excluded = 0;
  std::vector<std::string> observer_kinds;  // the sessions' (session.json observer_kind), sorted, unique
  std::vector<std::string> notes;
  std::vector<FrameThreshold> patches;     // per technique and patch
  std::vector<FrameThreshold> techniques;  // per technique, over its patches (one threshold)
  FrameThreshold pooled;                   // over every technique and patch
};

// Whether the dataset holds a frame study's trials (rows of trial_log::Layout::frames); throws
// std::runtime_error when it mixes them with the edge study's.
bool is_frame_study(const Dataset& data);

// Throws std::invalid_argument for options a frame fit cannot take.
FrameStudyFit fit_frame_study(const Dataset& data, const StudyFitOptions& options);

nlohmann::json frame_report_json(const FrameStudyFit& fit, const std::vector<std::string>& inputs, const std::string& created_utc);
std::string frame_summary_text(const FrameStudyFit& fit);

}  // namespace penumbra::analysis
