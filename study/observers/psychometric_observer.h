#pragma once
// A simulated observer that answers from a planted psychometric model. Its threshold is planted
// in filter-radius terms, the way the study reports it, and on the detection probability F (lapse
// free), as QUEST defines it: at artifact size a its F is the study's criterion
// F* = psychometric::criterion_f(p_threshold, guess, quest_delta) when filter_radius_px = c_true * a,
// i.e. at intensity log10(a / (c_true a)) = -log10(c_true) whatever a is. Its own lapse only lowers
// psi's upper asymptote: with lapse = quest_delta (1 - guess) psi is p_threshold there.

#include <cstdint>
#include <map>
#include <string>

#include <penumbra/observers/observer.h>
#include <penumbra/published.h>
#include <penumbra/psychometric/psychometric.h>
#include <penumbra/sampling/random.h>

namespace penumbra::observers {

struct PlantedModel {
  double c_true = kPublishedC;  // threshold filter radius in artifact sizes (texels)
  psychometric::Model model = psychometric::Model::log_weibull;
  double slope = 3.5;          // beta in the model's units (per log10 unit for the log models)
  double guess = 0.5;          // gamma
  double lapse = 0.0;          // lambda
  double p_threshold = 0.82;   // with quest_delta, the criterion F* at which c_true is the threshold
  double quest_delta = 0.01;   // QUEST's delta: F* = (p_threshold - guess) / ((1 - guess) (1 - delta))
};

class PsychometricObserver : public Observer {
 public:
  // One planted model per condition. Throws std::invalid_argument for a model whose psi never
  // reaches p_threshold or with c_true <= 0.
  PsychometricObserver(std::map<std::string, PlantedModel> conditions, std::uint64_t seed);

  Response respond(const Stimulus& stimulus) override;
  // The planted probability of a correct answer.
  double p_correct(const Stimulus& stimulus) const;
  // The planted threshold in QUEST intensity units, -log10(c_true).
  double threshold_intensity(const std::string& condition) const;

 private:
  struct Planted {
    PlantedModel model;
    psychometric::Params<double> params;
  };
  const Planted& planted(const std::string& condition) const;

  std::map<std::string, Planted> conditions_;
  sampling::Random random_;
};

// The model's x for a stimulus: the intensity for the log-unit models, the ratio
// artifact_px / filter_radius_px for the linear Weibull.
double model_x(psychometric::Model model, const Stimulus& stimulus);

}  // namespace penumbra::observers
