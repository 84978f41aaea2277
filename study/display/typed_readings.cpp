#include "display/typed_readings.h"

#include <cstdio>
#include <stdexcept>

namespace penumbra::display {

TypedReadings::TypedReadings(std::vector<int> levels, Model model) : levels_(std::move(levels)), model_(model) {
  if (levels_.empty()) throw std::invalid_argument("TypedReadings: no levels");
}

TypedReadings::Outcome TypedReadings::enter() {
  if (reviewing()) return Outcome::refused;
  const std::string typed = field_;
  field_.clear();  // refused or not, the next reading starts from an empty box
  double luminance = 0;
  try {
    luminance = parse_luminance(typed);
  } catch (const std::invalid_argument& e) {
    message_ = e.what();
    to_confirm_.reset();
    return Outcome::refused;
  }
  if (!readings_.empty() && !(luminance > readings_.back().luminance_cd_m2)) {
    char b[200];
    std::snprintf(b, sizeof b, "%g is not above level %d's %g: luminance must rise with the level (measure again)", luminance,
                  readings_.back().level, readings_.back().luminance_cd_m2);
    message_ = b;
    to_confirm_.reset();
    return Outcome::refused;
  }
  if (const std::string odd = implausible_reading(level(), luminance); !odd.empty() && to_confirm_ != luminance) {
    message_ = odd + " Enter keeps it, or type another value.";
    to_confirm_ = luminance;
    field_ = typed;  // shown again, so that Enter confirms exactly this value
    return Outcome::confirm;
  }
  to_confirm_.reset();
  message_.clear();
  readings_.push_back({level(), luminance});
  if (reviewing()) review();
  return Outcome::accepted;
}

void TypedReadings::undo() {
  if (readings_.empty()) return;
  readings_.pop_back();
  fitted_.reset();
  fit_problem_.clear();
  fit_warning_.clear();
  message_.clear();
  field_.clear();
  to_confirm_.reset();
}

void TypedReadings::review() {
  try {
    fitted_ = fit_readings(readings_, model_);
    fit_warning_ = check_fitted_levels(*fitted_->black_cd_m2, *fitted_->white_cd_m2,
                                       model_ == Model::gamma ? "the gamma model's" : "the table's");
  } catch (const std::invalid_argument& e) {
    fitted_.reset();
    fit_problem_ = e.what();
  }
}

}  // namespace penumbra::display
