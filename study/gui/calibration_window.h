#pragma once
// The windows of `penumbra-study calibrate-display`: full-screen grey levels, one after another,
// with the photometer's reading typed in for each; or a 1-px black/white checkerboard beside a
// grey patch whose level the arrow keys move until the two look alike. Both draw 8-bit values as
// they are (no sRGB framebuffer, pixel copies 1:1), so what is measured is the monitor's own
// transfer. Status lines on stdout ("showing level 64 (3 of 9)", "grey level 186") are for the
// operator's terminal and the GUI test.
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
  std::vector<display::Reading> readings;
  nlohmann::json monitor;  // name, video mode, full screen or not
};
// Shows each level full screen (a small entry box in the lower left corner, away from the
// photometer's spot at the centre) and takes the luminance typed for it (Enter), by the rules of
// display::TypedReadings; then the review of every reading with `model` fitted, where Enter accepts
// them and Backspace measures the last level again. Escape or closing the window: nothing (the
// caller writes nothing).
std::optional<MeasuredLevels> measure_levels(const std::vector<int>& levels, display::Model model, const CalibrationScreen& screen);

struct CheckerboardMatch {
  int level = 128;
  nlohmann::json monitor;
};
// Left half: a 1-px checkerboard of levels 0 and 255; right half: a uniform grey. Up/Right and
// Down/Left move the grey by one level, Page Up/Down by ten, Enter accepts it, Escape stops.
std::optional<CheckerboardMatch> match_checkerboard(const CalibrationScreen& screen, int start_level = 128);

}  // namespace penumbra::study_gui
