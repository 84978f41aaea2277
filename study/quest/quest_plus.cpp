#include "quest/quest_plus.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

namespace penumbra::quest {
namespace {

void require(bool ok, const std::string& message) {
  if (!ok) throw std::invalid_argument(message);
}

void normalize(std::vector<double>& weights) {
  double total = 0.0;
  for (double w : weights) total += w;
  require(total > 0.0 && std::isfinite(total), "QUEST+: posterior has no mass (responses impossible under every parameter)");
  for (double& w : weights) w /= total;
}

// -sum p log p over the posterior prior * likelihood / evidence, without forming it.
double entropy_after(const std::vector<double>& prior, const double* likelihood, bool correct, double evidence) {
  if (evidence <= 0.0) return 0.0;
  double h = 0.0;
  for (std::size_t j = 0; j < prior.size(); ++j) {
    const double l = correct ? likelihood[j] : 1.0 - likelihood[j];
    const double post = prior[j] * l / evidence;
    if (post > 0.0) h -= post * std::log(post);
  }
  return h;
}

}  // namespace

std::vector<QuestPlusParameter> quest_plus_grid(const std::vector<double>& thresholds, const std::vector<double>& slopes,
                                                const std::vector<double>& lapses) {
  std::vector<QuestPlusParameter> grid;
  grid.reserve(thresholds.size() * slopes.size() * lapses.size());
  for (double lapse : lapses)
    for (double slope : slopes)
      for (double threshold : thresholds) grid.push_back({threshold, slope, lapse});
  return grid;
}

QuestPlus::QuestPlus(std::vector<double> stimuli, std::vector<QuestPlusParameter> parameters,
                     QuestPlusLikelihood p_correct, std::vector<double> prior)
    : stimuli_(std::move(stimuli)), parameters_(std::move(parameters)), p_correct_(std::move(p_correct)),
      posterior_(std::move(prior)) {
  require(!stimuli_.empty(), "QUEST+: no candidate stimuli");
  require(!parameters_.empty(), "QUEST+: empty parameter grid");
  if (posterior_.empty()) posterior_.assign(parameters_.size(), 1.0);
  require(posterior_.size() == parameters_.size(),
          "QUEST+: prior has " + std::to_string(posterior_.size()) + " weights for " +
              std::to_string(parameters_.size()) + " parameters");
  for (double w : posterior_) require(w >= 0.0 && std::isfinite(w), "QUEST+: prior weights must be finite and >= 0");
  normalize(posterior_);
  table_.resize(stimuli_.size() * parameters_.size());
  for (std::size_t s = 0; s < stimuli_.size(); ++s) {
    for (std::size_t j = 0; j < parameters_.size(); ++j) {
      const double p = p_correct_(stimuli_[s], parameters_[j]);
      require(p >= 0.0 && p <= 1.0, "QUEST+: likelihood outside [0, 1] at stimulus " + std::to_string(stimuli_[s]));
      table_[s * parameters_.size() + j] = p;
    }
  }
}

std::vector<double> QuestPlus::expected_entropy() const {
  const std::size_t n = parameters_.size();
  std::vector<double> expected(stimuli_.size());
  for (std::size_t s = 0; s < stimuli_.size(); ++s) {
    const double* likelihood = table_.data() + s * n;
    double p_correct = 0.0;
    for (std::size_t j = 0; j < n; ++j) p_correct += posterior_[j] * likelihood[j];
    const double p_incorrect = 1.0 - p_correct;
    expected[s] = p_correct * entropy_after(posterior_, likelihood, true, p_correct) +
                  p_incorrect * entropy_after(posterior_, likelihood, false, p_incorrect);
  }
  return expected;
}

double QuestPlus::next() const {
  const std::vector<double> expected = expected_entropy();
  return stimuli_[static_cast<std::size_t>(std::min_element(expected.begin(), expected.end()) - expected.begin())];
}

void QuestPlus::update(double stimulus, int response) {
  require(std::isfinite(stimulus), "QUEST+: stimulus must be finite");
  require(response == 0 || response == 1, "QUEST+: response must be 0 or 1");
  for (std::size_t j = 0; j < parameters_.size(); ++j) {
    const double p = p_correct_(stimulus, parameters_[j]);
    posterior_[j] *= response == 1 ? p : 1.0 - p;
  }
  normalize(posterior_);
  ++trial_count_;
}

QuestPlusParameter QuestPlus::posterior_mean() const {
  QuestPlusParameter mean{0.0, 0.0, 0.0};
  for (std::size_t j = 0; j < parameters_.size(); ++j) {
    mean.threshold += posterior_[j] * parameters_[j].threshold;
    mean.slope += posterior_[j] * parameters_[j].slope;
    mean.lapse += posterior_[j] * parameters_[j].lapse;
  }
  return mean;
}

QuestPlusParameter QuestPlus::posterior_mode() const {
  return parameters_[static_cast<std::size_t>(std::max_element(posterior_.begin(), posterior_.end()) -
                                              posterior_.begin())];
}

double QuestPlus::threshold_sd() const {
  const double mean = posterior_mean().threshold;
  double variance = 0.0;
  for (std::size_t j = 0; j < parameters_.size(); ++j) {
    const double d = parameters_[j].threshold - mean;
    variance += posterior_[j] * d * d;
  }
  return std::sqrt(variance);
}

}  // namespace penumbra::quest
