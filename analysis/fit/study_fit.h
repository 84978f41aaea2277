#pragma once
// The whole analysis of a study's logs (issue 5): per staircase, per participant and per
// condition (pattern x contrast).
//
// Intensity is u = log10(artifact_px / filter_radius_px). The rule r_threshold(a) = c a means the
// threshold intensity is u = log10(a / (c a)) = -log10 c for every a, so:
//   linear model    one threshold u for all sizes and participants (+ shared slope and lapse):
//                   c = 10^-u, 95 % interval by profile likelihood, and a bootstrap over
//                   participants;
//   per-size model  one u_k per artifact size (same slope and lapse): c_k = 10^-u_k; the
//                   likelihood-ratio test against the linear model (K - 1 dof) is the linearity
//                   check;
//   power law       r = k a^p  <=>  u(a) = log10 a - log10 r = u_0 - (p - 1) log10(a / a_ref), with
//                   a_ref the geometric mean of the sizes: fitted as u_0 + s log10(a / a_ref),
//                   p = 1 - s; p = 1 is the linear model (LR test, 1 dof).
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "data/dataset.h"
#include "fit/model_fit.h"
#include "fit/multilevel_fit.h"

namespace penumbra::analysis {

struct StudyFitOptions {
  psychometric::Model family = psychometric::Model::log_weibull;
  std::optional<double> guess;       // default: the sessions' QUEST gamma (0.5 for 2afc), else 0.5
  std::optional<double> p_threshold;  // default: the sessions' QUEST pThreshold, else 0.82
  LapseSpec lapse;                    // joint fits; staircase fits hold lambda at the condition's
  double level = 0.95;
  int bootstrap = 1000;               // resamples over participants; 0 = none
  std::uint64_t seed = 1;
  int threads = 0;                    // 0: hardware concurrency; results do not depend on it
  double outlier_z = 3.0;             // participants farther than this (robust z of log10 c) are flagged
  // Progress of each long phase, in this order: "conditions" (each condition's joint fit, profile
  // interval, linearity and participant fits; total = 4 x conditions), "bootstrap" (every resample of
  // the participant bootstraps and of the worst case's), "staircases" (one fit each). Each phase
  // starts with done = 0 and ends with done = total; a phase with nothing to do is not reported.
  // Called from worker threads, one call at a time.
  std::function<void(const std::string& phase, int done, int total)> progress;
  bool accept_inconsistent = false;   // the logs were loaded with LoadOptions::accept_inconsistent
  bool pool = false;                  // the logs were loaded with LoadOptions::pool
  // The multilevel fit's observer percentile (MultilevelFit; penumbra-fit --observer-percentile 90).
  double observer_percentile = 0.9;
};

struct TrackPoint {
  int trial = 0;
  double intensity = 0, filter_radius_px = 0;
  int correct = 0;
  bool clamped = false;
};

struct StaircaseFit {
  std::string participant, session_id, condition, staircase;
  double artifact_px = 0;
  int round = 0;
  bool tail = false;  // its QUEST aimed at the config's quest.tail_p_threshold, not the criterion
  FitResult fit;  // u = fit.params.u[0]
  double c = NAN, c_lo = NAN, c_hi = NAN;  // 10^-u and its Wald interval
  // QUEST posterior after the last trial, recomputed from the log (when session.json has QUEST's
  // parameters) and as logged.
  bool quest_recomputed = false;
  double quest_mean = NAN, quest_sd = NAN;
  double logged_quest_mean = NAN, logged_quest_sd = NAN;
  bool quest_matches_log = true;
  bool converged = true;
  Flags flags;  // not_converged (QUEST sd above the study's sd_below, or an ill-conditioned fit), quest_replay_differs
  std::vector<TrackPoint> track;
};

struct SizeThreshold {
  double artifact_px = 0;
  int trials = 0;
  double u = NAN, se_u = NAN;
  double c = NAN, c_lo = NAN, c_hi = NAN;  // Wald interval from the per-size model
};

struct ParticipantFit {
  std::string participant;
  FitResult fit;
  double c = NAN, c_lo = NAN, c_hi = NAN;  // Wald
  double robust_z = NAN;                   // (log10 c - median) / robust spread over participants
  Flags flags;                             // far_from_rest, plus the fit's
};

struct Interval {
  double lo = NAN, hi = NAN;
  bool lo_open = false, hi_open = false;
};

struct BootstrapSummary {
  int resamples = 0;
  int flagged = 0;  // resamples whose fit ended at a bound or did not converge (kept, bounded)
  Interval c;       // percentile interval
  double sd_log10_c = NAN;
  std::vector<double> c_values;
};

struct ConditionFit {
  std::string condition, pattern;
  double contrast = 1;
  int trials = 0, participant_count = 0;
  std::vector<double> artifact_px;  // sorted
  ModelSpec spec;                   // the linear model's data and settings
  FitResult linear;
  double c = NAN;
  Interval c_profile, c_wald;
  BootstrapSummary bootstrap;
  // Linearity.
  bool linearity_tested = false;
  FitResult per_size;
  std::vector<SizeThreshold> sizes;
  double lr_linear_stat = NAN, lr_linear_dof = 0, lr_linear_p = NAN;
  bool power_law_tested = false;
  FitResult power;
  double a_ref_px = NAN, exponent = NAN, exponent_se = NAN, k_px = NAN;
  Interval exponent_wald;
  double lr_power_stat = NAN, lr_power_p = NAN;
  double beta = NAN;   // the linear model's slope (shared by the condition's participants and sizes)
  Interval beta_wald;  // its Wald 95 % interval, from the SE of log beta
  std::vector<ParticipantFit> participants;
  Flags flags;
};

// The c calibration.json takes: the worst case over conditions, without the selection bias of a
// plain maximum (with conditions of equal c, the largest of their estimates is biased upward by
// 3-4 % and its interval covers about 90 %) and without a significance gate (issue 48: pooling
// when an LR test said p >= 0.05 covered the worst condition's c in 25 of 40 studies with one
// condition 5 % above the rest).
//  - c: each condition's log10 c shrunk toward their precision-weighted mean by the
//    between-condition variance the data show (DerSimonian-Laird tau^2), and the largest of them
//    ("shrunken maximum"); where tau^2 is 0 the conditions' one c, the pooled fit ("pooled").
//  - ci95: the hull of the chosen condition's profile interval, the participant bootstrap of the
//    maximum (percentile, less the maximum's bias) and the population's worst-case interval of the
//    multilevel fit (the largest of the conditions' simultaneous intervals: it covers the largest
//    true c whenever each condition's interval covers its own, whatever the differences).
// The likelihood-ratio test of whether the conditions differ is reported, and decides nothing.
// With --condition, that condition's c with its profile and bootstrap intervals.
struct WorstCase {
  std::string method;     // single condition | pooled | shrunken maximum | chosen (--condition)
  std::string condition;  // the condition c is taken from, or "all conditions" (pooled)
  double c = NAN;
  Interval profile;       // trial-level: profile likelihood of the chosen estimate
  Interval bootstrap;     // participants resampled (percentile; bias-corrected for the maximum)
  Interval population;    // the multilevel fit's worst-case interval of the population mean c
  Interval ci95;          // what calibration.json's ci95 holds: the hull of the three above
  double tau_log10 = NAN; // between-condition sd of log10 c the shrinkage used (0: the pooled c)
  double lr_stat = NAN, lr_p = NAN;  // conditions differ? (dof = conditions - 1)
  int lr_dof = 0;
  double max_c = NAN, bias_log10 = NAN;  // the plain maximum and its bias estimated by the bootstrap
  int resamples = 0;
  // The psychometric function c is a threshold on: the fit c came from (the pooled model, or the
  // largest condition's).
  double beta = NAN, lapse = NAN;
  Interval beta_wald;
  Flags flags;  // of that fit
};

// What the thesis did (Kreuzer 2017, sec. 4.4 and 5.1): per participant and artifact size the
// radius of QUEST's final estimate, their mean per size, and a line through the origin r = c a
// per condition (least squares) -- beside the model fit, to say how far they differ.
struct ThesisEstimate {
  std::string condition;
  double c = NAN;                          // slope of the line through the origin
  std::vector<double> artifact_px, mean_radius_px;  // the points it was fitted to
  int staircases = 0;
};

struct StudyFit {
  StudyFitOptions options;
  double p_threshold = 0.82;
  double quest_delta = 0.01;  // the sessions' QUEST delta
  // The detection probability F at every threshold and c (lapse free): QUEST's criterion,
  // psychometric::criterion_f(p_threshold, guess, quest_delta), 0.6465 for 2AFC at 0.82.
  double criterion_f = 0.6465;
  double guess = 0.5;
  std::string task = "2afc";  // of the trials fitted (2afc | yesno)
  // yes/no: each participant's detections have their own guess rate, the false-alarm rate of
  // their catch (straight) trials, (false alarms + 0.5) / (catch trials + 1) so that none is 0;
  // a participant without catch trials takes `guess` (noted). Thresholds stay at criterion_f.
  struct FalseAlarms {
    int catch_trials = 0, false_alarms = 0;
    double rate = NAN;  // the guess rate used
  };
  std::map<std::string, FalseAlarms> false_alarms;
  // participant → pixels per degree at the screen centre of the display their session.json
  // records (procedure::Display::pixels_per_degree), for converting radii to visual angle.
  std::map<std::string, double> pixels_per_degree;
  int sessions = 0, trials = 0, practice_rows_excluded = 0;
  std::vector<std::string> notes;  // torn logs, missing session.json, ...
  std::vector<Inconsistency> inconsistencies;  // logs fitted although inconsistent (--accept-inconsistent)
  std::vector<std::string> pooled_differences;  // setups pooled although they differ (--pool)
  std::vector<ConditionFit> conditions;
  std::vector<StaircaseFit> staircases;
  MultilevelFit population;              // participants as random effects on log c (fit/multilevel_fit.h)
  WorstCase worst;                       // the entry's c (calibration_condition applies --condition)
  std::vector<ThesisEstimate> thesis;    // the thesis's own estimate per condition
};

// Throws std::invalid_argument for bad options.
StudyFit fit_study(const Dataset& data, const StudyFitOptions& options);

// A condition's c at detection probability `visibility` (docs/fit.md's c(F)) on its fitted
// function (the linear model's threshold and slope, in the fit's family), with the Wald interval of
// log10 c(F) from their joint covariance (delta method, `level`). The threshold and the slope are
// correlated wherever the trials do not sit at F*, so this is narrower than the corners of their two
// intervals (adaptive::c_at_visibility's, which a calibration entry allows, lacking the covariance)
// and narrows when a tail design (quest.tail_p_threshold) puts trials near `visibility`. Within the
// family: a refit with another family moves it (docs/fit.md). An empty interval when the fit has no
// covariance. Throws std::invalid_argument for a visibility outside (0, 1) or a bad condition index.
struct CAtVisibilityFit {
  double c = NAN;
  Interval ci;
};
CAtVisibilityFit condition_c_at_visibility(const StudyFit& fit, std::size_t condition, double visibility);

// Bootstrap over participants of the linear model: `participants[i]` holds participant i's groups.
BootstrapSummary bootstrap_participants(const ModelSpec& base, const std::vector<std::vector<Group>>& participants,
                                        const Parameters& start, int resamples, std::uint64_t seed, int threads,
                                        double level, const std::function<void()>& one_done = {});

// The entry's c over the study's conditions (WorstCase); `groups` holds each condition's groups by
// participant, in fit.conditions' order.
WorstCase worst_case(const StudyFit& fit, const std::vector<std::map<std::string, std::vector<Group>>>& groups,
                     const StudyFitOptions& options, int threads, const std::function<void()>& one_done = {});
// The multilevel fit of the study's conditions (fit/multilevel_fit.h): `groups` as for worst_case.
MultilevelFit population_fit(const StudyFit& fit, const std::vector<std::map<std::string, std::vector<Group>>>& groups,
                             const StudyFitOptions& options);
// The thesis's estimate per condition (ThesisEstimate), from fit.staircases' QUEST means.
std::vector<ThesisEstimate> thesis_estimates(const StudyFit& fit);

// The stimulus level of a logged intensity in the family's x units (the ratio for the Weibull).
double model_x(psychometric::Model family, double intensity);

}  // namespace penumbra::analysis
