#include "display/typed_readings.h"

#include <algorithm>
#include <cstdio>
#include <stdexcept>

namespace penumbra::display {

TypedReadings::TypedReadings(std::vector<int> levels, Model model, const std::vector<Reading>& kept)
    : levels_(std::move(levels)), model_(model), values_(levels_.size()) {
  if (levels_.empty()) throw std::invalid_argument("TypedReadings: no levels");
  for (const Reading& r : kept) {
    const auto it = std::find(levels_.begin(), levels_.end(), r.level);
    if (it == levels_.end()) throw std::invalid_argument("kept reading of level " + std::to_string(r.level) + ": not a level shown");
    values_[static_cast<std::size_t>(it - levels_.begin())] = r.luminance_cd_m2;
  }
  const auto unread = std::find(values_.begin(), values_.end(), std::nullopt);
  if (unread == values_.end()) {  // every level was read before: straight to the review
    selected_ = levels_.size() - 1;
    reviewing_ = true;
    review();
  } else {
    selected_ = static_cast<std::size_t>(unread - values_.begin());
  }
}

std::size_t TypedReadings::read_count() const {
  return static_cast<std::size_t>(std::count_if(values_.begin(), values_.end(), [](const auto& v) { return v.has_value(); }));
}

std::vector<Reading> TypedReadings::readings() const {
  std::vector<Reading> r;
  for (std::size_t i = 0; i < levels_.size(); ++i)
    if (values_[i]) r.push_back({levels_[i], *values_[i]});
  return r;
}

void TypedReadings::clear_entry() {
  field_.clear();
  message_.clear();
  to_confirm_.reset();
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
  // Luminance rises with the level: against the nearest level read below and above this one. The
  // neighbour may be the wrong one, so the message says how to read it again.
  auto refuse = [&](std::size_t other, const char* relation) {
    char b[240];
    std::snprintf(b, sizeof b, "%g is not %s level %d's %g: luminance must rise with the level (measure again, or select level %d with Up/Down and read it again)",
                  luminance, relation, levels_[other], *values_[other], levels_[other]);
    message_ = b;
    to_confirm_.reset();
    return Outcome::refused;
  };
  for (std::size_t i = selected_; i-- > 0;)
    if (values_[i]) {
      if (!(luminance > *values_[i])) return refuse(i, "above");
      break;
    }
  for (std::size_t i = selected_ + 1; i < levels_.size(); ++i)
    if (values_[i]) {
      if (!(luminance < *values_[i])) return refuse(i, "below");
      break;
    }
  if (const std::string odd = implausible_reading(level(), luminance); !odd.empty() && to_confirm_ != luminance) {
    message_ = odd + " Enter keeps it, or type another value.";
    to_confirm_ = luminance;
    field_ = typed;  // shown again, so that Enter confirms exactly this value
    return Outcome::confirm;
  }
  to_confirm_.reset();
  message_.clear();
  values_[selected_] = luminance;
  // The next level not read yet, after this one and then from the start; none: the review, with
  // this level's row selected.
  for (std::size_t k = 1; k < levels_.size(); ++k) {
    const std::size_t i = (selected_ + k) % levels_.size();
    if (!values_[i]) {
      selected_ = i;
      return Outcome::accepted;
    }
  }
  reviewing_ = true;
  review();
  return Outcome::accepted;
}

void TypedReadings::select(int step) {
  const long last = static_cast<long>(levels_.size()) - 1;
  selected_ = static_cast<std::size_t>(std::clamp(static_cast<long>(selected_) + step, 0L, last));
  clear_entry();
}

void TypedReadings::remeasure() {
  if (!reviewing_) return;
  reviewing_ = false;
  fitted_.reset();
  fit_problem_.clear();
  fit_warning_.clear();
  clear_entry();
}

void TypedReadings::set_model(Model model) {
  model_ = model;
  if (reviewing_) review();
}

void TypedReadings::review() {
  fitted_.reset();
  fit_problem_.clear();
  fit_warning_.clear();
  try {
    fitted_ = fit_readings(readings(), model_);
    fit_warning_ = check_fitted_levels(*fitted_->black_cd_m2, *fitted_->white_cd_m2,
                                       model_ == Model::gamma ? "the gamma model's" : "the table's");
    if (fit_warning_.empty()) fit_warning_ = gamma_fit_note(*fitted_);
  } catch (const std::invalid_argument& e) {
    fitted_.reset();
    fit_problem_ = e.what();
  }
}

}  // namespace penumbra::display
