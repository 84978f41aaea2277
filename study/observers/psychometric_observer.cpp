#include "observers/psychometric_observer.h"

#include <cmath>
#include <stdexcept>
#include <utility>

namespace penumbra::observers {

double model_x(psychometric::Model model, const Stimulus& stimulus) {
  if (model == psychometric::Model::weibull) return stimulus.artifact_px / stimulus.filter_radius_px;
  return stimulus.intensity();
}

PsychometricObserver::PsychometricObserver(std::map<std::string, PlantedModel> conditions, std::uint64_t seed)
    : random_(seed) {
  if (conditions.empty()) throw std::invalid_argument("PsychometricObserver: no conditions");
  for (auto& [name, model] : conditions) {
    if (!(model.c_true > 0.0 && std::isfinite(model.c_true)))
      throw std::invalid_argument("PsychometricObserver: condition '" + name + "': c_true must be positive");
    if (!(model.slope > 0.0 && std::isfinite(model.slope)))
      throw std::invalid_argument("PsychometricObserver: condition '" + name + "': slope must be positive");
    // Threshold in the model's x: a / r at r = c a is 1 / c; its log10 is -log10(c).
    const double threshold_x =
        model.model == psychometric::Model::weibull ? 1.0 / model.c_true : -std::log10(model.c_true);
    if (!(model.lapse >= 0.0 && model.lapse < 1.0 - model.guess))
      throw std::invalid_argument("PsychometricObserver: condition '" + name + "': lapse must be in [0, 1 - guess)");
    const double alpha = psychometric::alpha_for_threshold(model.model, threshold_x, model.p_threshold, model.slope, model.guess,
                                                           psychometric::quest_lapse(model.quest_delta, model.guess));
    if (!std::isfinite(alpha))
      throw std::invalid_argument("PsychometricObserver: condition '" + name + "': the criterion F* of p_threshold " +
                                  std::to_string(model.p_threshold) + " is not in (0, 1)");
    conditions_.emplace(name, Planted{model, {alpha, model.slope, model.guess, model.lapse}});
  }
}

const PsychometricObserver::Planted& PsychometricObserver::planted(const std::string& condition) const {
  const auto it = conditions_.find(condition);
  if (it == conditions_.end())
    throw std::invalid_argument("PsychometricObserver: no planted model for condition '" + condition + "'");
  return it->second;
}

double PsychometricObserver::p_correct(const Stimulus& stimulus) const {
  if (!(stimulus.artifact_px > 0.0 && stimulus.filter_radius_px > 0.0))
    throw std::invalid_argument("PsychometricObserver: artifact_px and filter_radius_px must be positive");
  const Planted& p = planted(stimulus.condition);
  return psychometric::probability(p.model.model, model_x(p.model.model, stimulus), p.params);
}

Response PsychometricObserver::respond(const Stimulus& stimulus) {
  return {random_.uniform() < p_correct(stimulus)};
}

double PsychometricObserver::threshold_intensity(const std::string& condition) const {
  return -std::log10(planted(condition).model.c_true);
}

}  // namespace penumbra::observers
