#pragma once
// calibration.json: the constant c of the rule r = c·a, one entry per technique (and kernel), as
// penumbra-fit writes it and data/calibration/calibration.schema.json describes it. c depends on
// the filter (a box of half-side r blurs more than a disk of radius r), so the adaptive rule looks
// up the entry of the technique it renders and says where its c came from.
//
//   {"schema_version": 2, "created_utc": "...", "source": "...",
//    "entries": [{"technique": "pcf", "kernel": "grid", "c": 3.1, "ci95": [2.8, 3.5],
//                 "condition": "step, full contrast", "obtained_by": "study",
//                 "participants": 5, "trials": 900, "source": "...", "per_condition": [...]}]}
//
// A version-1 file (no schema_version, one top-level "c") still loads, as the entry of PCF with
// any kernel: the only filter such files were measured with. Another schema_version is refused.
//
// No GL, study or Ceres: another engine can link `penumbra_adaptive` alone.
#include <cmath>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include <penumbra/published.h>

namespace penumbra::adaptive {

inline constexpr int kCalibrationSchemaVersion = 2;
// The kernel a PCF entry without one was measured with: the study's own filter, the disk
// (default.json's reading of the thesis assumes it; version-1 files were fitted on the study's).
inline constexpr std::string_view kAssumedPcfKernel = "disk";

// How an entry's c was obtained.
enum class CalibrationMethod {
  published,       // a value from the literature (data/calibration/default.json)
  study,           // penumbra-fit on the logs of human participants
  image_observer,  // penumbra-fit on logs answered by the image observer (a model prediction)
  simulated,       // penumbra-fit on logs answered by a psychometric observer with a planted c
  mixed,           // penumbra-fit --pool-observers: kinds of observer pooled on request
};
std::string_view method_name(CalibrationMethod m);  // as calibration.json holds it: study, image-observer, ...
// In words for a line of output: "people" for study, "psychometric simulation", "image observer", ...
std::string_view method_description(CalibrationMethod m);
std::optional<CalibrationMethod> method_from_name(std::string_view name);

// What an entry's c is a threshold of: the detection probability F (lapse free) at which an
// observer still sees the staircase, on the psychometric function the study fitted. c is not the
// radius that hides the artifact: at r = c a it is detected with probability `criterion_f` (in 2AFC
// at QUEST's 82 % correct, F* = 0.6465). With the slope, c at any other detection probability
// follows (c_at_visibility).
struct ThresholdDefinition {
  std::string task = "2afc";          // 2afc | yesno
  double guess = 0.5;                 // the task's guess rate (gamma)
  double criterion_f = 0.6465;        // detection probability F at c
  std::string family = "log-weibull"; // psychometric function: log-weibull, weibull, normal, logistic
  double beta = 3.5;                  // its slope, in the family's units (per log10 unit for log-weibull)
  double beta_lo = 3.5, beta_hi = 3.5;  // 95 % interval of the slope (= beta when assumed)
  double lapse = 0.0;                 // the fitted lapse (it lowers psi's asymptote, not c)
  bool beta_assumed = true;           // the slope was assumed (QUEST's), not fitted
};

// An entry's "population" block (penumbra-fit's multilevel fit, participants as random effects on
// log10 c; docs/fit.md): the population's mean c, the between-participant spread, and the c of one
// percentile of observers, each with its 95 % profile interval. NAN where the fit left a bound open.
struct Population {
  int participants = 0;
  std::string condition;  // the condition it speaks for ("the worst condition (stair/1)")
  double mean_c = NAN, mean_c_lo = NAN, mean_c_hi = NAN;
  double sd_log10 = NAN, sd_log10_lo = NAN, sd_log10_hi = NAN;
  double percentile = NAN;  // the observer percentile the fit was asked for, in (0, 100)
  double percentile_c = NAN, percentile_c_lo = NAN, percentile_c_hi = NAN;
};

struct CalibrationEntry {
  std::string technique;  // a registry name: pcf, vsm, rpcf, ...
  std::string kernel;     // the technique's kernel (pcf: grid, poisson) or "" for any
  double c = kPublishedC;
  // The 95 % interval; lo = hi = c when the entry has none (the published constant: the thesis gives
  // none), and has_ci95 says which, so that no zero-width interval is ever written or printed.
  double ci95_lo = kPublishedC;
  double ci95_hi = kPublishedC;
  bool has_ci95 = false;
  std::string condition;  // the condition c came from (e.g. "step, full contrast")
  CalibrationMethod obtained_by = CalibrationMethod::published;
  int participants = 0;  // 0: not stated
  long trials = 0;       // 0: not stated
  std::vector<std::string> flags;  // what the fitter flagged (one_participant, slope_at_upper_bound, ...)
  // false: penumbra-fit --allow-unusable wrote a fit it judged unusable (not converged, an open or
  // infinite interval, an implausible c); `unusable_because` says why. Read, used, and said loudly.
  bool usable = true;
  std::vector<std::string> unusable_because;
  // What c is a threshold of; absent in files written before (and in version-1 files): the
  // published design's is assumed then (2afc-equivalent criterion 0.6465, log-Weibull, slope 3.5).
  std::optional<ThresholdDefinition> threshold;
  const ThresholdDefinition& definition() const;
  // The multilevel fit's population; absent for a published constant, an image-observer prediction
  // and files written before penumbra-fit had it.
  std::optional<Population> population;

  // "pcf grid", or "pcf" for any kernel.
  std::string label() const { return kernel.empty() ? technique : technique + " " + kernel; }
};

// c at detection probability `visibility` for a threshold c at `criterion_f` on a psychometric
// function of `family` ("log-weibull", "weibull", "normal", "logistic") with slope `beta`: for the
// log-Weibull, c · (ln(1 - visibility) / ln(1 - criterion_f))^(-1/beta). A lower visibility needs a
// larger radius: with beta 3.5, bringing 2AFC down to 55 % correct (F 0.10) takes about 1.9 c.
// Throws std::invalid_argument for a visibility outside (0, 1) or an unknown family.
double c_at_visibility(double c, double criterion_f, double visibility, double beta, std::string_view family = "log-weibull");

// An entry's c at `visibility` with its interval: the entry's ci95 mapped through the slope's
// interval (the widest combination), and through the psychometric family (issue 48). A study's
// QUEST trials sit near the criterion, so the data fix the function's level and local slope there
// and say little of its shape in the tail: refitting the same data with another family moves c at
// F 0.1 by 14-20 % while c moves 1.5 %. So the interval is the hull over the families the fitter
// supports (log-Weibull, its Weibull on a / r being the same function, normal, logistic), each
// with the slope whose dF/dx at the criterion equals the entry's (family_slope).
// visibility = the entry's criterion gives c and ci95 back.
struct CAtVisibility {
  double c = kPublishedC, lo = kPublishedC, hi = kPublishedC;
  // The hull of the other families' c at `visibility` from the entry's c and slope alone (no
  // interval of either): how far the family alone moves it.
  double family_lo = kPublishedC, family_hi = kPublishedC;
};
CAtVisibility c_at_visibility(const CalibrationEntry& entry, double visibility);

// The c of the `percentile`-th observer (in (0, 100): 90 = a c that hides the artifact at the
// entry's criterion for 90 % of the population) from the entry's population block: the fitted
// percentile's own c and profile interval when `percentile` is the one the fit was asked for;
// otherwise mean_c · 10^(z sd_log10), z the normal quantile, with the interval the corners of the
// mean's and the spread's intervals (conservative: their joint region lies inside that box).
// `fitted` says which. Throws std::invalid_argument, naming the entry, for an entry without a
// population block or a percentile outside (0, 100).
struct CAtPercentile {
  double c = NAN, lo = NAN, hi = NAN;  // NAN bounds: the fit left that side open
  bool fitted = false;
};
CAtPercentile c_at_observer_percentile(const CalibrationEntry& entry, double percentile);

// The slope of family `to` whose dF/dx (x in log10 units) at detection probability `criterion_f`
// equals that of family `from` with slope `beta`: the same curve near the criterion. The Weibull's
// slope on a / r is the log-Weibull's on log10 of it. Throws std::invalid_argument for an unknown
// family.
double family_slope(std::string_view from, double beta, std::string_view to, double criterion_f);

// The c the rule uses for one technique, and where it came from, for output and reports.
struct CalibrationChoice {
  double c = kPublishedC;
  double ci95_lo = kPublishedC;  // = c when the entry has no interval (has_ci95)
  double ci95_hi = kPublishedC;
  bool has_ci95 = false;
  // The entry used (nullopt: the published value, the file having nothing that applies).
  std::optional<CalibrationEntry> entry;
  // True when the entry was measured for another technique, kernel or rotation than the one rendered.
  bool fallback = false;
  // One phrase: "pcf grid entry (people, 5 participants)", "pcf entry (published), not measured for
  // rpcf", "published PCF value, not measured for vsm".
  std::string from;
  // With fallback: why the entry does not match ("measured with the disk kernel (the study's, assumed:
  // the entry states none), not with grid") and what would ("a pcf grid entry"); "" otherwise.
  std::string fallback_reason, would_match;
  // What an operator must know before trusting c: "flags: one_participant", "NOT USABLE: not_converged"
  // ("" when the entry has neither).
  std::string warnings() const;
};

struct Calibration {
  int schema_version = kCalibrationSchemaVersion;  // as read: 1 for a single-c file
  std::vector<CalibrationEntry> entries;
  std::string source;  // the file it came from, or "built-in"

  // The entry for `technique` and `kernel` (kernel "" when the technique has none): the exact
  // entry, else the technique's entry for any kernel, else one for another kernel of the
  // technique, else the PCF entry, else the published value, each fallback saying so.
  // A PCF entry without a kernel (the published constant, version-1 files) was measured with the
  // study's filter, the disk (kAssumedPcfKernel): for grid or poisson it is a fallback.
  // `rotated`: the renderer rotates the kernel's taps per pixel (PCF poisson with pcf.rotate). No
  // entry is measured so (the study draws an unrotated disk and refuses pcf.rotate), so every entry
  // is then a fallback, said so with what would match (pcf.rotate false).
  CalibrationChoice choose(std::string_view technique, std::string_view kernel, bool rotated = false) const;
};

// Throws CalibrationError naming the file and field on bad input (one line).
class CalibrationError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};
Calibration load_calibration(const std::filesystem::path& path);

}  // namespace penumbra::adaptive
