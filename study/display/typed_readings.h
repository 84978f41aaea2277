#pragma once
// The photometer readings an experimenter types into the calibration window, one per grey level,
// as a state machine without a window (study/gui/calibration_window.cpp draws it; tests type into
// it directly). Every reading goes through parse_luminance, the rule the CSV path uses: a decimal
// comma is refused with a word about the point, never dropped ("8,1" is not 81). The field empties
// after each reading, refused or not, so a new reading is never appended to a refused one. A
// reading that cannot be (not above the level below it, not below the level above it, among those
// read) is refused; one that is implausible for a monitor (display_fit.h) is taken only when Enter
// is pressed on it a second time. Any level can be selected and read again, before the review or
// from it; after a reading the next unread level is shown. When every level is read, the review
// shows them all with the fitted model (gamma or table, switchable) before anything is written.
#include <optional>
#include <string>
#include <vector>

#include "display/display_calibration.h"
#include "display/display_fit.h"

namespace penumbra::display {

class TypedReadings {
 public:
  // `kept`: readings of an earlier window (its readings file), each of a level among `levels`.
  // Throws std::invalid_argument for no levels, or a kept reading of a level not among them.
  TypedReadings(std::vector<int> levels, Model model, const std::vector<Reading>& kept = {});

  enum class Outcome { accepted, refused, confirm };
  // Enter: the field's text as the reading of the selected level (replacing one read before).
  Outcome enter();
  // Up/Down: the level `step` levels away (clamped to the ends), while levels are read or on the
  // review's table. The field and any pending confirmation are dropped.
  void select(int step);
  // On the review: the selected level is shown and read again (the others are kept).
  void remeasure();
  // On the review: the model fitted and written, gamma or table.
  void set_model(Model model);

  std::string& field() { return field_; }  // what the text box holds
  const std::string& message() const { return message_; }  // why the last entry was refused, or what to confirm
  bool reviewing() const { return reviewing_; }
  std::size_t current() const { return selected_; }  // index of the level on screen (the review: the row selected)
  int level() const { return levels_.at(selected_); }
  const std::vector<int>& levels() const { return levels_; }
  // The reading of levels()[i], if read.
  const std::optional<double>& reading(std::size_t i) const { return values_.at(i); }
  std::size_t read_count() const;
  std::vector<Reading> readings() const;  // those read, by level
  Model model() const { return model_; }
  // On the review: the fitted calibration, or why the readings give none (then nothing can be
  // written: measure a level again, or switch the model).
  const std::optional<DisplayCalibration>& fitted() const { return fitted_; }
  const std::string& fit_problem() const { return fit_problem_; }
  // An implausible fitted black or white, a black held at 0, a gamma curve that misses the readings.
  const std::string& fit_warning() const { return fit_warning_; }

 private:
  void review();
  void clear_entry();

  std::vector<int> levels_;
  Model model_;
  std::vector<std::optional<double>> values_;  // per level
  std::size_t selected_ = 0;
  bool reviewing_ = false;
  std::string field_, message_;
  std::optional<double> to_confirm_;  // an implausible reading shown once: Enter again keeps it
  std::optional<DisplayCalibration> fitted_;
  std::string fit_problem_, fit_warning_;
};

}  // namespace penumbra::display
