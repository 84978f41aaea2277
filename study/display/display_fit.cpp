#include "display/display_fit.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

#include <ceres/ceres.h>

#include "solver/solver_options.h"
#include "text/csv_row.h"
#include "text/fields.h"
#include "text/printable.h"

namespace penumbra::display {

std::vector<int> calibration_levels(int count) {
  if (count < kMinReadings || count > 256)
    throw std::invalid_argument("--levels " + std::to_string(count) + ": expected " + std::to_string(kMinReadings) + "..256");
  std::vector<int> levels;
  for (int i = 0; i < count; ++i) levels.push_back(static_cast<int>(std::lround(255.0 * i / (count - 1))));
  return levels;
}

namespace {

using text::trim;

std::string fmt(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%g", v);
  return b;
}

}  // namespace

double parse_luminance(const std::string& text_in) {
  const std::string t = trim(text_in);
  const std::string quoted = "'" + text::printable(t) + "'";
  if (t.empty()) throw std::invalid_argument("no reading typed: a luminance in cd/m2, e.g. 85.2");
  // A decimal comma is the most likely slip of a European keyboard: never dropped, never guessed.
  if (t.find(',') != std::string::npos && t.find_first_not_of("0123456789,") == std::string::npos)
    throw std::invalid_argument(quoted + ": a decimal comma; type a point (" + [&] {
      std::string p = t;
      std::replace(p.begin(), p.end(), ',', '.');
      return p;
    }() + ")");
  char* end = nullptr;
  const double v = std::strtod(t.c_str(), &end);
  if (end != t.c_str() + t.size() || !std::isfinite(v) || t.find_first_of("xXpPnNiI") != std::string::npos)
    throw std::invalid_argument(quoted + " is not a number");
  if (!(v >= 0 && v <= kMaxLuminanceCdM2)) throw std::invalid_argument(quoted + " is not a luminance in [0, 100000] cd/m2");
  return v;
}

std::string implausible_reading(int level, double l) {
  if (level == 0 && l > kPlausibleBlackMaxCdM2)
    return "black (level 0) at " + fmt(l) + " cd/m2 is above any monitor's black (0.." + fmt(kPlausibleBlackMaxCdM2) +
           "): is the room lit, or the photometer off the screen?";
  if (level == 255 && (l < kPlausibleWhiteMinCdM2 || l > kPlausibleWhiteMaxCdM2))
    return "white (level 255) at " + fmt(l) + " cd/m2 is outside the range of monitors (" + fmt(kPlausibleWhiteMinCdM2) + ".." +
           fmt(kPlausibleWhiteMaxCdM2) + " cd/m2): a typing slip, or another unit?";
  if (l > kPlausibleWhiteMaxCdM2)
    return "level " + std::to_string(level) + " at " + fmt(l) + " cd/m2 is brighter than any monitor's white (" +
           fmt(kPlausibleWhiteMaxCdM2) + " cd/m2): a typing slip?";
  return "";
}

std::string check_fitted_levels(double black, double white, const std::string& what) {
  if (!(black >= 0))
    throw std::invalid_argument(what + " black level is " + fmt(black) +
                                " cd/m2, below 0: the readings do not follow the model near black (measure level 0 and the "
                                "darkest levels again, or use --model table)");
  if (!(white > black)) throw std::invalid_argument(what + " white level " + fmt(white) + " cd/m2 is not above its black " + fmt(black));
  std::string warning = implausible_reading(0, black);
  if (warning.empty()) warning = implausible_reading(255, white);
  return warning.empty() ? "" : what + " " + warning;
}

std::vector<Reading> read_readings_csv(const std::filesystem::path& path, ReadingsSet set) {
  const std::string file = path.string();
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw std::runtime_error(file + ": no such file");
  if (std::filesystem::file_size(path, ec) > (1u << 20)) throw std::runtime_error(file + ": larger than 1 MiB; expected at most 256 readings");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(file + ": cannot read");
  std::string line;
  int number = 0;
  std::map<int, std::pair<double, int>> by_level;  // level -> (luminance, line)
  bool header = false;
  while (std::getline(in, line)) {
    ++number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const std::string where = file + ":" + std::to_string(number) + ": ";
    if (line.find('\0') != std::string::npos || !text::valid_utf8(line)) throw std::runtime_error(where + "not text");
    std::vector<std::string> fields = text::split_fields(line);
    for (std::string& f : fields) f = trim(f);
    if (!header) {
      if (fields != std::vector<std::string>{"level", "luminance_cd_m2"})
        throw std::runtime_error(where + "expected the header 'level,luminance_cd_m2', found '" + text::printable(line) + "'");
      header = true;
      continue;
    }
    if (line.empty()) throw std::runtime_error(where + "empty line; expected 'level,luminance_cd_m2' values");
    static const std::vector<std::string> kColumns = {"level", "luminance_cd_m2"};
    const text::CsvRow row(file, number, kColumns, std::move(fields), "level,luminance_cd_m2");
    const std::string& lv = row[0];
    if (lv.empty() || lv.size() > 3 || lv.find_first_not_of("0123456789") != std::string::npos || std::stoi(lv) > 255)
      throw std::runtime_error(where + "column 'level': '" + text::printable(lv) + "' is not an 8-bit level (an integer 0..255)");
    const int level = std::stoi(lv);
    const std::string& lum = row[1];
    double luminance = 0;
    try {
      luminance = parse_luminance(lum);
    } catch (const std::invalid_argument& e) {
      throw std::runtime_error(where + "column 'luminance_cd_m2': " + e.what());
    }
    const auto [it, fresh] = by_level.try_emplace(level, luminance, number);
    if (!fresh)
      throw std::runtime_error(where + "column 'level': " + lv + " was read already on line " + std::to_string(it->second.second));
    if (by_level.size() > 256) throw std::runtime_error(where + "more than 256 readings");
  }
  if (!header) throw std::runtime_error(file + ": empty; expected the header 'level,luminance_cd_m2' and one row per level");
  // Luminance must rise with the level; the row that breaks it is named (by line, in level order).
  for (auto it = std::next(by_level.begin(), by_level.empty() ? 0 : 1); it != by_level.end(); ++it) {
    const auto& [level, reading] = *it;
    const auto& [prev_level, prev] = *std::prev(it);
    if (!(reading.first > prev.first)) {
      char b[256];
      std::snprintf(b, sizeof b, "%s:%d: column 'luminance_cd_m2': %g cd/m2 at level %d is not above %g at level %d (line %d); "
                    "luminance must rise with the level",
                    file.c_str(), reading.second, reading.first, level, prev.first, prev_level, prev.second);
      throw std::runtime_error(b);
    }
  }
  std::vector<Reading> readings;
  for (const auto& [level, reading] : by_level) readings.push_back({level, reading.first});
  if (set == ReadingsSet::partial) return readings;
  try {
    check_readings(readings);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(file + ": " + e.what());
  }
  return readings;
}

std::string readings_csv(std::vector<Reading> readings) {
  std::sort(readings.begin(), readings.end(), [](const Reading& a, const Reading& b) { return a.level < b.level; });
  std::string text = "level,luminance_cd_m2\n";
  for (const Reading& r : readings) {
    char b[48];
    const auto [end, ec] = std::to_chars(b, b + sizeof b, r.luminance_cd_m2);  // shortest that reads back the same double
    (void)ec;  // 48 characters hold any double
    text += std::to_string(r.level) + "," + std::string(b, end) + "\n";
  }
  return text;
}

namespace {

// One reading against the gamma model: predicted minus measured luminance, cd/m².
struct GammaResidual {
  double x;  // level / 255
  double luminance_cd_m2;
  template <class T>
  bool operator()(const T* black, const T* white, const T* gamma, T* residual) const {
    using std::pow;
    const T shape = x > 0 ? pow(T(x), gamma[0]) : T(0);  // x^gamma's derivative in gamma is 0 at x = 0, not 0 * -inf
    residual[0] = black[0] + (white[0] - black[0]) * shape - T(luminance_cd_m2);
    return true;
  }
};

}  // namespace

DisplayCalibration fit_readings(std::vector<Reading> readings, Model model) {
  std::sort(readings.begin(), readings.end(), [](const Reading& a, const Reading& b) { return a.level < b.level; });
  check_readings(readings);
  double black = readings.front().luminance_cd_m2, white = readings.back().luminance_cd_m2, gamma = 2.2;
  // No monitor emits less than nothing: black >= 0 is part of the model. Where the free optimum
  // lies below 0 (readings near black a little under the curve through the rest, e.g. 0.31, 9.2,
  // 41.5, 98.7, 181 cd/m² gave -0.0823), the fit is the best one with black at 0: white and gamma
  // fitted again with black held there. (A lower bound on black in one solve stopped on the bound
  // with a cost 0.05 % above that optimum: Ceres' projected steps crawl along an active bound.)
  auto solve = [&](bool black_at_zero) {
    ceres::Problem problem;
    for (const Reading& r : readings)
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<GammaResidual, 1, 1, 1, 1>(new GammaResidual{r.level / 255.0, r.luminance_cd_m2}),
                               nullptr, &black, &white, &gamma);
    if (black_at_zero) problem.SetParameterBlockConstant(&black);
    problem.SetParameterLowerBound(&gamma, 0, 0.5);
    problem.SetParameterUpperBound(&gamma, 0, 5.0);
    const ceres::Solver::Options options = solver::small_problem_options(1e-14);
    ceres::Solver::Summary summary;
    ceres::Solve(options, &problem, &summary);
    if (!summary.IsSolutionUsable() || !(white > black))
      throw std::invalid_argument("the gamma model does not fit these readings (" + summary.message + ")");
  };
  solve(false);
  if (black < 0) {
    black = 0;
    white = readings.back().luminance_cd_m2;
    gamma = 2.2;
    solve(true);
  }
  double sum = 0;
  for (const Reading& r : readings) {
    double residual = 0;
    GammaResidual{r.level / 255.0, r.luminance_cd_m2}(&black, &white, &gamma, &residual);
    sum += residual * residual;
  }
  // The table is the readings themselves: its black and white are what was measured. The gamma
  // model's come from the fit (black >= 0 by its bound; checked again as every model is).
  if (model == Model::table) {
    black = readings.front().luminance_cd_m2;
    white = readings.back().luminance_cd_m2;
  } else {
    (void)check_fitted_levels(black, white, "the gamma model's");
  }
  DisplayCalibration c;
  c.model = model;
  c.method = "photometer";
  c.gamma = gamma;
  c.black_cd_m2 = black;
  c.white_cd_m2 = white;
  c.points = std::move(readings);
  c.residual_rms_cd_m2 = std::sqrt(sum / static_cast<double>(c.points.size()));
  return c;
}

std::string gamma_fit_note(const DisplayCalibration& c) {
  if (c.model != Model::gamma || c.method != "photometer" || c.points.empty() || !c.black_cd_m2 || !c.white_cd_m2) return "";
  std::string note;
  if (*c.black_cd_m2 == 0 && c.points.front().luminance_cd_m2 > 0)
    note = "black held at 0 cd/m2 (the gamma curve through the other readings passes below 0 at level 0, read as " +
           fmt(c.points.front().luminance_cd_m2) + ")";
  const double range = *c.white_cd_m2 - *c.black_cd_m2;
  if (c.residual_rms_cd_m2 && *c.residual_rms_cd_m2 > kGammaMissWarning * range)
    note += (note.empty() ? "" : "; ") + std::string("the gamma model misses the readings by ") + fmt(*c.residual_rms_cd_m2) +
            " cd/m2 RMS (" + fmt(std::round(1000 * *c.residual_rms_cd_m2 / range) / 10) + " % of the range): the table model follows them";
  return note;
}

double checkerboard_gamma(int matched_level) {
  if (matched_level < 1 || matched_level > 254)
    throw std::invalid_argument("matched level " + std::to_string(matched_level) + ": expected 1..254 (a grey between black and white)");
  const double gamma = std::log(0.5) / std::log(matched_level / 255.0);
  if (!(gamma >= 0.5 && gamma <= 5))
    throw std::invalid_argument("matched level " + std::to_string(matched_level) + " means gamma " + std::to_string(gamma) +
                                ", outside [0.5, 5]: check that the checkerboard is shown 1:1 (no scaling)");
  return gamma;
}

DisplayCalibration checkerboard_calibration(int matched_level) {
  DisplayCalibration c;
  c.model = Model::gamma;
  c.method = "checkerboard-match";
  c.gamma = checkerboard_gamma(matched_level);
  c.matched_level = matched_level;
  return c;
}

}  // namespace penumbra::display
