#pragma once
// QUEST (Watson & Pelli 1983) with the semantics of Psychtoolbox's Quest*.m, number for number:
// the same grids, the same interpolated threshold shift, the same quantile order, the same index
// arithmetic and edge clamping in the update, the same estimators. docs/quest.md lists every
// place where this class deliberately differs (all of them are inputs Psychtoolbox accepts
// silently and turns into NaN or garbage).
//
// Intensities are in the caller's log units (the study uses log10(artifact_px / filter_radius_px)).

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace penumbra::quest {

class Quest;
struct BetaAnalysis;
BetaAnalysis beta_analysis(const Quest& quest);

struct QuestParams {
  double t_guess = 0.0;     // prior mean of the threshold
  double t_guess_sd = 1.0;  // prior sd; +infinity gives a uniform prior
  double p_threshold = 0.82;
  double beta = 3.5;
  double delta = 0.01;
  double gamma = 0.5;
  double grain = 0.01;
  // Without a range the table has dim = 500 steps; with one, dim = 2 * ceil(range / grain / 2).
  std::optional<double> range;
};

// Table size QuestCreate derives from grain and range; throws std::invalid_argument for range <= 0.
int quest_dim(const QuestParams& params);

class Quest {
 public:
  // QuestCreate. Throws std::invalid_argument with a one-line reason for parameters that
  // Psychtoolbox rejects or cannot use. A gamma above pThreshold is reduced to 0.5 with a
  // warning, as Psychtoolbox does.
  explicit Quest(const QuestParams& params);
  // A table of an explicit size (QuestBetaAnalysis sets dim and grain directly); `range` is ignored.
  Quest(const QuestParams& params, int dim);

  // QuestUpdate: response 1 = correct, 0 = incorrect. An intensity outside the table is used at
  // the table's edge and leaves a warning. Throws for a non-finite intensity or a bad response.
  void update(double intensity, int response);

  // QuestRecompute: rebuilds the pdf from the prior and the trial history, normalising every 100
  // trials and at the end (not after each trial as update() does, so the last bits may differ).
  void recompute();

  double mean() const;                   // QuestMean
  double sd() const;                     // QuestSd
  double mode() const;                   // QuestMode: the first maximum of the pdf
  double quantile() const;               // QuestQuantile at the Pelli (1987) order
  double quantile(double order) const;   // throws for an order outside [0, 1]
  double p(double x) const;              // QuestP: psychometric table at x (clamped to the table)
  double pdf_at(double t) const;         // QuestPdf: pdf at the grid point nearest threshold t
  // QuestSimulate: correct response for a trial at t_test when the true threshold is t_actual,
  // decided by comparing the table probability with `uniform01` (a U[0,1) draw).
  bool simulate(double t_test, double t_actual, double uniform01) const;

  const QuestParams& params() const { return params_; }  // gamma as used (after any reduction)
  int dim() const { return dim_; }
  double x_threshold() const { return x_threshold_; }
  double quantile_order() const { return quantile_order_; }
  const std::vector<double>& x() const { return x_; }
  const std::vector<double>& pdf() const { return pdf_; }
  const std::vector<double>& x2() const { return x2_; }
  const std::vector<double>& p2() const { return p2_; }
  const std::vector<double>& intensities() const { return intensities_; }
  const std::vector<int>& responses() const { return responses_; }
  std::size_t trial_count() const { return responses_.size(); }
  // Warnings Psychtoolbox would print (gamma reduced, intensity out of range), oldest first.
  const std::vector<std::string>& warnings() const { return warnings_; }

 private:
  friend BetaAnalysis beta_analysis(const Quest& quest);
  void build_table();
  // Multiplies the pdf by the likelihood of `response` at `intensity`; true when the intensity
  // fell outside the table and was used at its edge.
  bool multiply_likelihood(double intensity, int response);
  void normalize();

  QuestParams params_;
  int dim_ = 0;
  double x_threshold_ = 0.0;
  double quantile_order_ = 0.0;
  std::vector<double> x_, pdf_, x2_, p2_;
  std::vector<double> s2_[2];  // likelihood of response 0 / 1, reversed along x2 (Psychtoolbox's s2)
  std::vector<double> intensities_;
  std::vector<int> responses_;
  std::vector<std::string> warnings_;
};

// Replays a history through update(): the exact state a live session had after these trials.
Quest replay(const QuestParams& params, const std::vector<double>& intensities,
             const std::vector<int>& responses);

// QuestBetaAnalysis: threshold and slope both free, over 16 slopes 2^(i/4), i = 1..16, on a
// coarse table (dim 250, grain 0.02), uniform prior over the slopes.
struct BetaAnalysis {
  double t;        // threshold at the most probable (threshold, beta) pair
  double sd;       // sd of the threshold at that pair's beta
  double beta;     // 1 / E[1/beta] (what Psychtoolbox prints and returns)
  double beta_sd;  // sd of beta
};
BetaAnalysis beta_analysis(const Quest& quest);

}  // namespace penumbra::quest
