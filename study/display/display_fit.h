#pragma once
// Making a display calibration: photometer readings (a CSV or typed in the window) fitted with the
// gamma model by Ceres, or a checkerboard match without a photometer. display_calibration.h
// holds the result.
#include <filesystem>
#include <string>
#include <vector>

#include "display/display_calibration.h"

namespace penumbra::display {

// The levels shown for `count` readings: 0 and 255 and the ones evenly between (rounded), e.g.
// 9 -> 0, 32, 64, ..., 223, 255. Throws std::invalid_argument outside [kMinReadings, 256].
std::vector<int> calibration_levels(int count);

// Luminances a monitor can have. Any desktop or lab monitor's black lies in [0, 5] cd/m² and its
// white in [20, 2000] cd/m² (HDR peaks aside); a value outside is asked about (the window) or warned
// about (a CSV), not refused: a bright projector or a dim laptop can be real.
inline constexpr double kPlausibleBlackMaxCdM2 = 5, kPlausibleWhiteMinCdM2 = 20, kPlausibleWhiteMaxCdM2 = 2000;
// A photometer reading as text (typed in the window, or a CSV field): a plain number with a decimal
// point, >= 0 and at most 100000 cd/m². Throws std::invalid_argument saying what is wrong, e.g.
// "'8,1': a decimal comma; type a point (8.1)".
double parse_luminance(const std::string& text);
// What is implausible about a reading of `level` (black over 5 cd/m², white outside [20, 2000]),
// "" if nothing.
std::string implausible_reading(int level, double luminance_cd_m2);
// The same for a fitted model's black and white levels (`what`: "the gamma model's"); throws
// std::invalid_argument for an impossible one (black below 0, white not above black).
std::string check_fitted_levels(double black_cd_m2, double white_cd_m2, const std::string& what);

// A CSV of photometer readings: the header `level,luminance_cd_m2`, then one row per level
// (an integer 0..255, a luminance >= 0 in cd/m²), in any order. Throws std::runtime_error, one
// line naming the file, the line and the column ("r.csv:4: column 'luminance_cd_m2': 'n/a' is not
// a number"), or the file alone for what concerns all rows (too few, no black or white). Sorted by
// level. ReadingsSet::partial takes any number of rising readings (the readings file of a window
// stopped half way, to go on from), with the same checks of each row.
enum class ReadingsSet { calibration, partial };
std::vector<Reading> read_readings_csv(const std::filesystem::path& path, ReadingsSet set = ReadingsSet::calibration);
// Readings as the CSV above (header, one row per reading, by level, luminance as typed: %.17g
// would show 0.31 as 0.31000000000000000), the form the window keeps them in as they are typed.
std::string readings_csv(std::vector<Reading> readings);

// Readings (any order) -> a calibration of `model`: the gamma model L(v) = L_black + (L_white -
// L_black) (v/255)^gamma fitted by least squares in cd/m² (Ceres) with gamma in [0.5, 5] and
// black >= 0 as part of the model (where the free optimum has black below 0, the best fit with
// black at 0), its RMS residual, and the readings themselves (the table model interpolates them,
// and its black and white are the readings of levels 0 and 255). Throws std::invalid_argument as
// check_readings does (too few, not rising, not a luminance).
DisplayCalibration fit_readings(std::vector<Reading> readings, Model model);
// What to know about a gamma fit before using it, "" if nothing: its black held at the bound 0
// (the curve through the other readings passes below 0), or a curve that misses the readings by
// more than kGammaMissWarning of the range RMS, where the table model follows them.
inline constexpr double kGammaMissWarning = 0.02;  // a photometer's own accuracy is a few %
std::string gamma_fit_note(const DisplayCalibration& gamma_fit);

// Without a photometer: a 1-px checkerboard of levels 0 and 255 averages to half way between
// black and white, so the grey level m that matches it has relative luminance 0.5:
// (m / 255)^gamma = 0.5, gamma = ln 0.5 / ln(m / 255). Throws std::invalid_argument outside 1..254
// or where the gamma would leave [0.5, 5].
double checkerboard_gamma(int matched_level);
DisplayCalibration checkerboard_calibration(int matched_level);

}  // namespace penumbra::display
