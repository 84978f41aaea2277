// The tools' comma lists (cli/list_option.h: --resolution, --radii, --contrast, --pattern, --seeds,
// ...) as one command-line value: every item kind the apps use reads the same text. Each either
// refuses the whole value in one line or reads at most 64 items, none of them twice, each inside
// its range and, for numbers, exactly what strtod reads from text decimal() accepted.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <string>
#include <vector>

#include "cli/list_option.h"
#include "fuzz_target.h"

namespace {

template <class T>
void parse_as(std::string_view input, penumbra::cli::ListItem<T> item, std::vector<T>& values) {
  CLI::App app;
  penumbra::cli::add_list_option(app, "--list", values, "a list", std::move(item));
  std::vector<std::string> args = {"tool", "--list", std::string(input)};
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  penumbra::fuzz::expect_refusal_or_success([&] { app.parse(static_cast<int>(argv.size()), argv.data()); });
  if (values.size() > penumbra::cli::kMaxListValues) penumbra::fuzz::finding("more than 64 items", std::string(input));
  for (std::size_t i = 0; i < values.size(); ++i)
    if (std::find(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(i), values[i]) != values.begin() + static_cast<std::ptrdiff_t>(i))
      penumbra::fuzz::finding("an item read twice", std::string(input));
}

}  // namespace

PENUMBRA_FUZZ_TARGET(comma_list) {
  namespace cli = penumbra::cli;
  std::vector<int> ints;
  parse_as(input, cli::integers_in(1, 65536), ints);
  for (int v : ints)
    if (v < 1 || v > 65536) penumbra::fuzz::finding("an integer out of its range", std::to_string(v));
  std::vector<double> numbers;
  parse_as(input, cli::numbers_in(0, 1, cli::Bound::open), numbers);
  for (double v : numbers)
    if (!(v > 0 && v <= 1)) penumbra::fuzz::finding("a number out of its range", std::to_string(v));
  std::vector<std::uint64_t> seeds;
  parse_as(input, cli::non_negative_integers(), seeds);
  std::vector<std::string> patterns;
  parse_as(input, cli::one_of({"stair", "step"}), patterns);
  for (const std::string& p : patterns)
    if (p != "stair" && p != "step") penumbra::fuzz::finding("a name outside its choices", p);
  // The grammar: what it accepts strtod reads whole, to a finite value.
  const std::string text(input.substr(0, 200));
  if (const auto v = cli::decimal(text)) {
    char* end = nullptr;
    const double expected = std::strtod(text.c_str(), &end);
    if (end != text.c_str() + text.size() || !std::isfinite(*v) || *v != expected) penumbra::fuzz::finding("decimal() disagrees with strtod", text);
  }
}
