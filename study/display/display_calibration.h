#pragma once
// A monitor's measured transfer: 8-bit level -> luminance, as display-calibration.json holds it
// (data/display/display-calibration.schema.json). The study's stimuli are linear light as a
// fraction of the display's range; `encode` gives the 8-bit level whose luminance is that
// fraction of the way from black to white on *this* monitor, so a contrast stated in linear light
// holds on it. No GL, no Ceres: the procedure and the fitter read it; display_fit.h makes one.
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace penumbra::json_input {
struct ObjectSpec;
}

namespace penumbra::display {

inline constexpr int kSchemaVersion = 1;
inline constexpr int kMinReadings = 5;  // the gamma model has three parameters; two readings are left to judge it
inline constexpr double kMaxLuminanceCdM2 = 1e5;  // above any display; the CSV, the window and the file share it

struct Reading {
  int level = 0;                // 8-bit display value shown full screen
  double luminance_cd_m2 = 0;   // what the photometer read
};

enum class Model {
  gamma,  // L(v) = L_black + (L_white - L_black) (v / 255)^gamma
  table,  // the readings, interpolated monotonically (Fritsch–Carlson) between measured levels
};
std::string to_string(Model m);
Model parse_model(const std::string& s);  // throws std::invalid_argument naming gamma and table

struct DisplayCalibration {
  Model model = Model::gamma;
  std::string method = "photometer";  // photometer | checkerboard-match
  double gamma = 2.2;                 // the gamma model's exponent (also fitted for a table)
  std::optional<double> black_cd_m2, white_cd_m2;  // none for a checkerboard match (no photometer)
  std::vector<Reading> points;        // by level, strictly increasing in level and luminance
  std::optional<double> residual_rms_cd_m2;  // of the gamma model against the readings
  std::optional<int> matched_level;   // checkerboard-match: the grey level that matched the checkerboard
  std::string created_utc;
  std::string source;                 // where the readings came from (the CSV, "typed in the window", ...)
  nlohmann::json monitor;             // name and video mode when known, else null

  // The fraction of the way from black to white, (L(v) - L(0)) / (L(255) - L(0)), of level v in
  // [0, 255] under the model.
  double relative_luminance(double level) const;
  // The 8-bit level whose relative luminance is nearest to `linear` (clamped to [0, 1]): the
  // error is at most half the luminance step between neighbouring levels there.
  std::uint8_t encode(double linear) const;
};

// Throws std::invalid_argument naming what is wrong with readings a calibration cannot come from:
// fewer than kMinReadings, no level 0 or 255, a level twice, a luminance outside [0, 100000]
// cd/m², or luminance that does not rise with the level (named by level). The one check of
// readings for every path: the CSV, the window, and a calibration file read back.
void check_readings(const std::vector<Reading>& sorted_by_level);

nlohmann::json to_json(const DisplayCalibration& c);
// Throws std::runtime_error "<file>: <field>: <what>".
DisplayCalibration parse_calibration(const nlohmann::json& j, const std::string& file);
// The fields parse_calibration reads, as data/display/display-calibration.schema.json states them.
const json_input::ObjectSpec& calibration_fields();
DisplayCalibration load_calibration(const std::filesystem::path& path);
// Writes atomically (a temporary in the same folder, then renamed over `path`).
void write_calibration(const std::filesystem::path& path, const DisplayCalibration& c);

// A short fingerprint of the calibration's content (FNV-1a 64 over its canonical JSON, in hex):
// session.json records it, resume and the fitter compare it.
std::string fingerprint(const nlohmann::json& calibration_json);

}  // namespace penumbra::display
