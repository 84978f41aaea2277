#pragma once
// QUEST+ (Watson 2017, Journal of Vision 17(3):10) for two-outcome trials: a posterior over a grid
// of psychometric parameters (threshold, and optionally slope and lapse); each trial goes to the
// candidate stimulus that minimises the expected entropy of the next posterior (the first such
// stimulus on ties). Unlike QUEST it can estimate the slope that the fitter otherwise assumes.

#include <functional>
#include <vector>

namespace penumbra::quest {

struct QuestPlusParameter {
  double threshold;
  double slope;
  double lapse;
};

// P(correct | stimulus, parameter). Must return a probability in [0, 1].
using QuestPlusLikelihood = std::function<double(double stimulus, const QuestPlusParameter& parameter)>;

// Every combination of the given values (threshold fastest).
std::vector<QuestPlusParameter> quest_plus_grid(const std::vector<double>& thresholds,
                                                const std::vector<double>& slopes,
                                                const std::vector<double>& lapses);

class QuestPlus {
 public:
  // An empty prior is uniform; otherwise one non-negative weight per parameter (normalised here).
  // Throws std::invalid_argument for empty grids, a prior of the wrong size or a likelihood
  // outside [0, 1].
  QuestPlus(std::vector<double> stimuli, std::vector<QuestPlusParameter> parameters,
            QuestPlusLikelihood p_correct, std::vector<double> prior = {});

  double next() const;                         // stimulus with the least expected entropy
  std::vector<double> expected_entropy() const;  // per candidate stimulus, in nats
  // Records a trial (response 1 = correct); the stimulus may be any value, not only a candidate.
  void update(double stimulus, int response);

  QuestPlusParameter posterior_mean() const;  // marginal means
  QuestPlusParameter posterior_mode() const;  // the first most probable grid point
  double threshold_sd() const;                // sd of the threshold marginal

  const std::vector<double>& stimuli() const { return stimuli_; }
  const std::vector<QuestPlusParameter>& parameters() const { return parameters_; }
  const std::vector<double>& posterior() const { return posterior_; }
  std::size_t trial_count() const { return trial_count_; }

 private:
  std::vector<double> stimuli_;
  std::vector<QuestPlusParameter> parameters_;
  QuestPlusLikelihood p_correct_;
  std::vector<double> posterior_;
  std::vector<double> table_;  // P(correct) per (stimulus, parameter), stimulus-major
  std::size_t trial_count_ = 0;
};

}  // namespace penumbra::quest
