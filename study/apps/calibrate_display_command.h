#pragma once
// `penumbra-study calibrate-display`: the monitor's transfer measured (photometer readings from a
// CSV or typed in while the window shows each grey level) or estimated by matching a grey patch to
// a 1-px checkerboard, written as display-calibration.json for a study config's
// display.calibration (docs/study.md, "Display calibration"). Readings typed in the window are
// kept in `<output>.readings.csv` as they are typed (atomically), so a stop or a crash loses
// none: the next window on that output goes on from them, and `--luminances` can finish from it.
#include <CLI/CLI.hpp>

#include <filesystem>
#include <string>

namespace penumbra::study_app {

class CalibrateDisplayCommand {
 public:
  explicit CalibrateDisplayCommand(CLI::App& app);
  bool parsed() const { return command_->parsed(); }
  int run() const;  // throws with a one-line reason; nothing is written then

 private:
  CLI::App* command_;
  std::filesystem::path luminances_, output_ = "display-calibration.json";
  std::string model_ = "gamma";
  int levels_ = 9;
  bool checkerboard_ = false;
  int monitor_ = 0;
  std::string windowed_;
};

}  // namespace penumbra::study_app
