#pragma once
// The windows of `penumbra-study calibrate-display`: full-screen grey levels, one after another,
// with the photometer's reading typed in for each; or a 1-px black/white checkerboard beside a
// grey patch whose level the arrow keys move until the two look alike. Both draw 8-bit values as
// they are (no sRGB framebuffer, pixel copies 1:1), so what is measured is the monitor's own
// transfer. Status lines on stdout ("showing level 64 (3 of 9)", "grey level 186") are for the
// operator's terminal and the GUI test.
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "display/display_calibration.h"

namespace penumbra::study_gui {

struct CalibrationScreen {
  int monitor = 0;       // GLFW index, full screen at its current video mode
  std::string windowed;  // "WxH": a window instead (testing)
};

struct MeasuredLevels {
  bool accepted = false;                   // Enter on the review; false: stopped (Escape, the window closed)
  std::vector<display::Reading> readings;  // accepted: one per level; stopped: those read so far
  display::Model model = display::Model::gamma;  // the model chosen on the review
  nlohmann::json monitor;                  // name, video mode, full screen or not
};
// Shows each level full screen (a small entry box in the lower left corner, away from the
// photometer's spot at the centre) and takes the luminance typed for it (Enter), by the rules of
// display::TypedReadings, starting from `kept` (readings of an earlier window). Up/Down select
// another level, to read it again. `keep` is called with every reading so far after each one
// taken (the caller writes them to `kept_file`, named on screen), so a stop or a crash loses
// nothing. Then the review of every reading with the model fitted: Up/Down select a level,
// Backspace reads it again, Tab switches between the gamma and the table model, Enter accepts.
// Escape or closing the window stops (accepted false).
MeasuredLevels measure_levels(const std::vector<int>& levels, display::Model model, const std::vector<display::Reading>& kept,
                              const std::string& kept_file, const std::function<void(const std::vector<display::Reading>&)>& keep,
                              const CalibrationScreen& screen);

struct CheckerboardMatch {
  int level = 128;
  nlohmann::json monitor;
};
// Left half: a 1-px checkerboard of levels 0 and 255; right half: a uniform grey. Up/Right and
// Down/Left move the grey by one level, Page Up/Down by ten, Enter accepts it, Escape stops.
std::optional<CheckerboardMatch> match_checkerboard(const CalibrationScreen& screen, int start_level = 128);

}  // namespace penumbra::study_gui
