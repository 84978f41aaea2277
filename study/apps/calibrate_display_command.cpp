#include "apps/calibrate_display_command.h"

#include <algorithm>
#include <cstdio>
#include <iostream>

#include "cli/checks.h"
#include "display/display_fit.h"
#include "io/atomic_file.h"
#include "io/safe_path.h"
#include "json/json_input.h"
#include "procedure/session.h"
#ifdef PENUMBRA_STUDY_GUI
#include "gui/calibration_window.h"
#endif

namespace penumbra::study_app {

namespace fs = std::filesystem;

CalibrateDisplayCommand::CalibrateDisplayCommand(CLI::App& app) {
  command_ = app.add_subcommand(
      "calibrate-display",
      "measure the monitor's transfer (8-bit level -> luminance) for display.calibration: photometer readings from "
      "--luminances CSV or typed in while the window shows each grey level, or --checkerboard without a photometer");
  command_->add_option("--luminances", luminances_, "CSV of photometer readings: header level,luminance_cd_m2, one row per level (0 and 255 among them)")
      ->check(CLI::ExistingFile);
  command_->add_option("--model", model_, "gamma (L_black + (L_white - L_black) (v/255)^gamma, black >= 0) or table (the readings, monotone "
                  "interpolation); the window's review switches between them with Tab")
      ->capture_default_str();
  command_->add_option("--levels", levels_, "window: how many grey levels to show, 0 and 255 among them (9: 0, 32, 64, ..., 255; 17: steps of 16)")
      ->capture_default_str()
      ->check(CLI::Range(display::kMinReadings, 256));
  command_->add_flag("--checkerboard", checkerboard_,
                     "no photometer: match a grey patch to a 1-px black/white checkerboard with the arrow keys (gives a gamma)");
  command_->add_option("--monitor", monitor_, "window: the monitor to measure (GLFW index)")->capture_default_str()->check(CLI::Range(0, 16));
  command_->add_option("--windowed", windowed_, "window: WxH instead of full screen (testing)");
  command_->add_option("-o,--output", output_, "the calibration file written (atomically); the window keeps the readings typed in OUTPUT.readings.csv until it is written")->capture_default_str()->check(cli::path_given());
}

namespace {

// The readings typed in the window, kept beside the calibration as they are typed.
fs::path kept_readings_path(const fs::path& output) {
  fs::path kept = output;
  kept += ".readings.csv";
  return kept;
}

}  // namespace

int CalibrateDisplayCommand::run() const {
  const display::Model model = [&] {
    try {
      return display::parse_model(model_);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(std::string("--model: ") + e.what());
    }
  }();
  io::check_output(output_, io::OutputKind::file);  // before the window: a folder that exists, no link
  if (checkerboard_ && !luminances_.empty()) throw std::invalid_argument("--checkerboard: not with --luminances (readings need no match)");
  if (checkerboard_ && model != display::Model::gamma) throw std::invalid_argument("--model table: a checkerboard match gives a gamma, not a table");
  if (!luminances_.empty())
    for (const char* window_option : {"--levels", "--monitor", "--windowed"})
      if (command_->count(window_option))
        throw std::invalid_argument(std::string(window_option) + ": not with --luminances (the readings are in the file; " +
                                    window_option + " is for the window)");
  const fs::path kept = kept_readings_path(output_);
  bool consumed_kept = false;  // the kept readings are in the calibration written: the file goes
  display::DisplayCalibration calibration;
  if (!luminances_.empty()) {
    const std::vector<display::Reading> readings = display::read_readings_csv(luminances_);
    for (const display::Reading& r : readings)  // the window asks about these; a file can only be warned about
      if (const std::string odd = display::implausible_reading(r.level, r.luminance_cd_m2); !odd.empty())
        std::cerr << "penumbra-study: warning: " << luminances_.string() << ": " << odd << "\n";
    calibration = display::fit_readings(readings, model);
    calibration.source = "photometer readings from " + fs::absolute(luminances_).lexically_normal().string();
    std::error_code ec;
    consumed_kept = fs::equivalent(luminances_, kept, ec);  // finishing a stopped window's readings
  } else {
#ifdef PENUMBRA_STUDY_GUI
    const study_gui::CalibrationScreen screen{monitor_, windowed_};
    if (checkerboard_) {
      const auto match = study_gui::match_checkerboard(screen);
      if (!match) throw std::runtime_error("calibrate-display: stopped before a match was accepted; nothing written");
      calibration = display::checkerboard_calibration(match->level);
      calibration.source = "checkerboard match in the window";
      calibration.monitor = match->monitor;
    } else {
      // Readings kept by an earlier window on this output (stopped, or killed) are gone on from;
      // the file follows the output's rules (no link, a regular file) and is read as any CSV.
      io::check_output(kept, io::OutputKind::file);
      std::vector<display::Reading> earlier;
      std::vector<int> levels = display::calibration_levels(levels_);
      if (fs::exists(fs::symlink_status(kept))) {
        earlier = display::read_readings_csv(kept, display::ReadingsSet::partial);
        for (const display::Reading& r : earlier) levels.push_back(r.level);  // its levels are shown too
        std::sort(levels.begin(), levels.end());
        levels.erase(std::unique(levels.begin(), levels.end()), levels.end());
      }
      const auto measured = study_gui::measure_levels(
          levels, model, earlier, kept.string(),
          [&](const std::vector<display::Reading>& so_far) { io::write_file_atomic(kept, display::readings_csv(so_far)); }, screen);
      if (!measured.accepted)
        throw std::runtime_error(
            measured.readings.empty()
                ? "calibrate-display: stopped before any level was read; nothing written"
                : "calibrate-display: stopped with " + std::to_string(measured.readings.size()) + " of " + std::to_string(levels.size()) +
                      " levels read; the readings are kept in " + kept.string() + " (run again to go on from them, or finish with --luminances " +
                      kept.string() + ")");
      calibration = display::fit_readings(measured.readings, measured.model);
      calibration.source = "photometer readings typed in the window";
      calibration.monitor = measured.monitor;
      consumed_kept = true;
    }
#else
    throw std::runtime_error("calibrate-display: this binary was built without the GUI (PENUMBRA_BUILD_GUI=OFF); give --luminances FILE.csv");
#endif
  }
  if (calibration.method == "photometer") {
    if (const std::string odd = display::check_fitted_levels(*calibration.black_cd_m2, *calibration.white_cd_m2,
                                                              calibration.model == display::Model::gamma ? "the gamma model's" : "the table's");
        !odd.empty())
      std::cerr << "penumbra-study: warning: " << odd << "\n";
    if (const std::string note = display::gamma_fit_note(calibration); !note.empty()) std::cerr << "penumbra-study: note: " << note << "\n";
  }
  calibration.created_utc = procedure::utc_now();
  display::write_calibration(output_, calibration);
  if (calibration.method == "photometer")
    std::printf("gamma %.4f (black %.4g cd/m2, white %.4g cd/m2), RMS residual %.4g cd/m2 over %zu readings; model %s\n",
                calibration.gamma, *calibration.black_cd_m2, *calibration.white_cd_m2, *calibration.residual_rms_cd_m2,
                calibration.points.size(), display::to_string(calibration.model).c_str());
  else
    std::printf("gamma %.4f (the grey of level %d matched the checkerboard); model gamma\n", calibration.gamma, *calibration.matched_level);
  std::printf("wrote %s\n", output_.string().c_str());
  // Its readings are the calibration's points now; left, it would start the next calibration of
  // this output with them.
  if (consumed_kept && fs::is_regular_file(fs::symlink_status(kept))) {
    std::error_code ec;
    if (fs::remove(kept, ec)) std::printf("removed %s (its readings are in %s)\n", kept.string().c_str(), output_.string().c_str());
  }
  return 0;
}

}  // namespace penumbra::study_app
