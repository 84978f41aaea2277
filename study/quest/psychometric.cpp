#include "quest/psychometric.h"

namespace penumbra::psychometric {

std::optional<Model> parse_model(std::string_view name) {
  if (name == "weibull") return Model::weibull;
  if (name == "log-weibull" || name == "log_weibull" || name == "gumbel") return Model::log_weibull;
  if (name == "normal") return Model::normal;
  if (name == "logistic") return Model::logistic;
  return std::nullopt;
}

std::string_view model_name(Model model) {
  switch (model) {
    case Model::weibull:
      return "weibull";
    case Model::log_weibull:
      return "log-weibull";
    case Model::normal:
      return "normal";
    case Model::logistic:
      return "logistic";
  }
  return "unknown";
}

}  // namespace penumbra::psychometric
