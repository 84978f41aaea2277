#include "data/level_data.h"

#include <charconv>
#include <cmath>
#include <fstream>
#include <stdexcept>

#include "json/json_input.h"
#include "text/fields.h"

namespace penumbra::analysis {

namespace {

constexpr double kMaxCount = 2147483647.0;

using text::trim;

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> f = text::split_fields(line);
  for (std::string& field : f) field = trim(field);
  return f;
}

}  // namespace

std::vector<BinomialRow> read_level_data(const std::filesystem::path& path, LevelFormat format) {
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error))
    throw std::runtime_error(path.string() + ": cannot read: " +
                             (std::filesystem::exists(path, error) ? "not a regular file" : "no such file"));
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path.string() + ": cannot open");
  const std::vector<std::string> names = format == LevelFormat::counts
                                             ? std::vector<std::string>{"level", "n_correct", "n_total"}
                                             : std::vector<std::string>{"level", "correct"};
  std::vector<BinomialRow> rows;
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (trim(line).empty()) continue;
    const std::vector<std::string> f = split(line);
    const std::string where = path.string() + ":" + std::to_string(number) + ": ";
    if (number == 1 && f == names) continue;
    if (f.size() != names.size())
      throw std::runtime_error(where + "expected " + std::to_string(names.size()) + " columns (" +
                               (format == LevelFormat::counts ? "level,n_correct,n_total" : "level,correct") +
                               "), found " + std::to_string(f.size()));
    auto value = [&](std::size_t i) {
      double v = 0;
      const auto [p, ec] = std::from_chars(f[i].data(), f[i].data() + f[i].size(), v);
      if (f[i].empty() || ec != std::errc() || p != f[i].data() + f[i].size() || !std::isfinite(v))
        throw std::runtime_error(where + "column '" + names[i] + "': expected a finite number (found '" +
                                 json_input::printable(f[i]) + "')");
      return v;
    };
    auto fail = [&](std::size_t i, const std::string& what) {
      throw std::runtime_error(where + "column '" + names[i] + "': " + what + " (found '" + json_input::printable(f[i]) + "')");
    };
    BinomialRow r;
    r.x = value(0);
    if (format == LevelFormat::counts) {
      r.n_correct = value(1);
      r.n_total = value(2);
      // The fit counts trials in an int: a count of 2^31 or more would wrap.
      if (r.n_total != std::floor(r.n_total) || r.n_total < 1 || r.n_total > kMaxCount)
        fail(2, "expected an integer in [1, 2147483647]");
      if (r.n_correct != std::floor(r.n_correct) || r.n_correct < 0 || r.n_correct > r.n_total)
        fail(1, "expected an integer in [0, n_total]");
    } else {
      r.n_correct = value(1);
      r.n_total = 1;
      if (r.n_correct != 0 && r.n_correct != 1) fail(1, "expected 0 or 1");
    }
    rows.push_back(r);
  }
  if (rows.empty()) throw std::runtime_error(path.string() + ": no data rows");
  return rows;
}

}  // namespace penumbra::analysis
