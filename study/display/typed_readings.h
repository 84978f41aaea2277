#pragma once
// The photometer readings an experimenter types into the calibration window, one per grey level,
// as a state machine without a window (study/gui/calibration_window.cpp draws it; tests type into
// it directly). Every reading goes through parse_luminance, the rule the CSV path uses: a decimal
// comma is refused with a word about the point, never dropped ("8,1" is not 81). The field empties
// after each reading, refused or not, so a new reading is never appended to a refused one. A
// reading that cannot be (not above the level below) is refused; one that is implausible for a
// monitor (display_fit.h) is taken only when Enter is pressed on it a second time. When every
// level is read, the review shows them all with the fitted model before anything is written.
#include <optional>
#include <string>
#include <vector>

#include "display/display_calibration.h"
#include "display/display_fit.h"

namespace penumbra::display {

class TypedReadings {
 public:
  TypedReadings(std::vector<int> levels, Model model);

  enum class Outcome { accepted, refused, confirm };
  // Enter: the field's text as the reading of the current level.
  Outcome enter();
  // Backspace on the review: the last level is read again.
  void undo();

  std::string& field() { return field_; }  // what the text box holds
  const std::string& message() const { return message_; }  // why the last entry was refused, or what to confirm
  bool reviewing() const { return readings_.size() == levels_.size(); }
  std::size_t current() const { return readings_.size(); }  // index of the level on screen
  int level() const { return levels_.at(readings_.size()); }
  const std::vector<int>& levels() const { return levels_; }
  const std::vector<Reading>& readings() const { return readings_; }
  // On the review: the fitted calibration, or why the readings give none (then nothing can be
  // written: Backspace and measure again).
  const std::optional<DisplayCalibration>& fitted() const { return fitted_; }
  const std::string& fit_problem() const { return fit_problem_; }
  const std::string& fit_warning() const { return fit_warning_; }  // an implausible fitted black or white

 private:
  void review();

  std::vector<int> levels_;
  Model model_;
  std::vector<Reading> readings_;
  std::string field_, message_;
  std::optional<double> to_confirm_;  // an implausible reading shown once: Enter again keeps it
  std::optional<DisplayCalibration> fitted_;
  std::string fit_problem_, fit_warning_;
};

}  // namespace penumbra::display
