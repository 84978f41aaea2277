#include "data/level_data.h"

#include <cmath>
#include <fstream>
#include <stdexcept>

#include "text/csv_row.h"
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
    std::vector<std::string> fields = split(line);
    if (number == 1 && fields == names) continue;
    const text::CsvRow f(path.string(), number, names, std::move(fields),
                         format == LevelFormat::counts ? "level,n_correct,n_total" : "level,correct");
    auto value = [&](std::size_t i) { return f.real(i); };
    auto fail = [&](std::size_t i, const std::string& what) { f.fail(i, what); };
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
