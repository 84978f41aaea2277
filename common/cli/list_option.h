#pragma once
// One comma list for every tool's options (--resolution 512,1024; --pattern stair,step): header
// only (CLI11). CLI11's own delimiter drops an empty item without a word ("64,,128" ran 64 and 128)
// and takes lists without end, so each list option goes through add_list_option instead:
//  - split by text::split_fields: an empty item (a doubled or trailing comma, "") is refused;
//  - at most kMaxListValues items over all its occurrences (each item is usually a whole render:
//    a 1000-entry --resolution ran for minutes);
//  - each item read by a ListItem (integers_in, numbers_in, non_negative_integers, names, one_of), so
//    "-1" never wraps to 2^64 - 1, and every number is read by the one grammar of decimal() (strtod
//    took ' 0.05' and '0x1p-4' where the integers refused ' 64');
//  - an item given twice is refused: each item is usually a whole render or stimulus named by its
//    value, so `--resolution 64,64` rendered hard-64 twice into one directory, the second over the first;
//  - repeating the option adds to the list (--pattern stair --pattern step).
// One wording for every refusal: "--OPTION: expected ONE, or at most 64 separated by commas, got 'TEXT'",
// and for a repeat "--OPTION: 'ITEM' is given twice (each item once), got 'TEXT'".
#include <CLI/CLI.hpp>

#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <algorithm>
#include <cerrno>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "text/fields.h"
#include "text/printable.h"

namespace penumbra::cli {

inline constexpr std::size_t kMaxListValues = 64;

// How one item of a list reads: `one` names a single item for the refusal ("an integer in [1, 4]"),
// `read` returns its value or nothing.
template <class T>
struct ListItem {
  std::string one;
  std::function<std::optional<T>(const std::string&)> read;
};

namespace detail {
template <class Int>
std::optional<Int> whole(const std::string& s) {
  Int v{};
  if (s.empty() || s.find_first_not_of("-0123456789") != std::string::npos) return std::nullopt;
  const auto [end, error] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (error != std::errc() || end != s.data() + s.size()) return std::nullopt;
  return v;
}
}  // namespace detail

// The one number grammar of the lists: an optional sign, decimal digits with an optional point, an
// optional exponent ("0.05", "-1", "+2.5e-3", ".5", "5."). No whitespace, no hexadecimal, no inf or
// nan, and nothing strtod would have to round to zero or infinity (ERANGE: "1e-400", "1e999").
inline std::optional<double> decimal(const std::string& s) {
  std::size_t i = 0;
  const auto digits = [&] {
    const std::size_t from = i;
    while (i < s.size() && s[i] >= '0' && s[i] <= '9') ++i;
    return i - from;
  };
  if (i < s.size() && (s[i] == '+' || s[i] == '-')) ++i;
  std::size_t mantissa = digits();
  if (i < s.size() && s[i] == '.') {
    ++i;
    mantissa += digits();
  }
  if (mantissa == 0) return std::nullopt;
  if (i < s.size() && (s[i] == 'e' || s[i] == 'E')) {
    ++i;
    if (i < s.size() && (s[i] == '+' || s[i] == '-')) ++i;
    if (digits() == 0) return std::nullopt;
  }
  if (i != s.size()) return std::nullopt;
  errno = 0;
  char* end = nullptr;
  const double v = std::strtod(s.c_str(), &end);  // the grammar above is a subset of strtod's "C" locale forms
  if (end != s.c_str() + s.size() || errno == ERANGE || !std::isfinite(v)) return std::nullopt;
  return v;
}

inline ListItem<int> integers_in(int lo, int hi) {
  return {"an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]", [lo, hi](const std::string& s) -> std::optional<int> {
            const auto v = detail::whole<int>(s);
            if (!v || *v < lo || *v > hi) return std::nullopt;
            return v;
          }};
}

// A number in [lo, hi] by decimal()'s grammar; with Bound::open, in (lo, hi] (a contrast of 0 draws
// no stimulus).
enum class Bound { closed, open };
inline ListItem<double> numbers_in(double lo, double hi, Bound low = Bound::closed) {
  char range[64];
  std::snprintf(range, sizeof range, "%s%g, %g]", low == Bound::open ? "(" : "[", lo, hi);
  return {std::string("a decimal number in ") + range, [lo, hi, low](const std::string& s) -> std::optional<double> {
            const std::optional<double> v = decimal(s);
            if (!v || *v < lo || *v > hi || (low == Bound::open && *v == lo)) return std::nullopt;
            return v;
          }};
}

// Digits only: no sign, at most 2^64 - 1.
inline ListItem<std::uint64_t> non_negative_integers() {
  return {"a non-negative integer (at most 2^64 - 1)", [](const std::string& s) -> std::optional<std::uint64_t> {
            if (s.find('-') != std::string::npos) return std::nullopt;
            return detail::whole<std::uint64_t>(s);
          }};
}

// Any non-empty text; what it names is checked where it is used (a technique, a scene, a pattern).
inline ListItem<std::string> names(std::string one) {
  return {std::move(one), [](const std::string& s) -> std::optional<std::string> { return s; }};
}

// One of `choices`, spelled exactly (--pattern stair,step): refused while parsing, so a wrong name
// is a wrong command line (exit 2) named by its option, like any other bad item. `one` is built
// from the choices: "stair or step", "pcf, pcss or all".
inline ListItem<std::string> one_of(std::vector<std::string> choices) {
  std::string one;
  for (std::size_t i = 0; i < choices.size(); ++i)
    one += (i == 0 ? "" : i + 1 == choices.size() ? " or " : ", ") + choices[i];
  return {std::move(one), [choices = std::move(choices)](const std::string& s) -> std::optional<std::string> {
            if (std::find(choices.begin(), choices.end(), s) == choices.end()) return std::nullopt;
            return s;
          }};
}

// `--option a,b,c` into `values` (its starting values are the default, shown in --help; the first
// occurrence replaces them). Refusals throw CLI::ValidationError while parsing.
template <class T>
CLI::Option* add_list_option(CLI::App& app, const std::string& option, std::vector<T>& values, const std::string& help, ListItem<T> item) {
  std::string shown;
  for (const T& v : values) {
    if (!shown.empty()) shown += ',';
    if constexpr (std::is_same_v<T, std::string>)
      shown += v;
    else
      shown += CLI::detail::to_string(v);
  }
  const std::string flag = option.substr(option.rfind(',') == std::string::npos ? 0 : option.rfind(',') + 1);
  return app
      .add_option_function<std::vector<std::string>>(
          option,
          [&values, item, flag](const std::vector<std::string>& occurrences) {
            std::vector<T> out;
            for (const std::string& text : occurrences) {
              const auto refuse = [&] {
                throw CLI::ValidationError(flag, "expected " + item.one + ", or at most " + std::to_string(kMaxListValues) +
                                                     " separated by commas, got '" + text::printable(text) + "'");
              };
              for (const std::string& field : text::split_fields(text)) {
                if (out.size() == kMaxListValues) refuse();
                const std::optional<T> v = field.empty() ? std::nullopt : item.read(field);
                if (!v) refuse();
                if (std::find(out.begin(), out.end(), *v) != out.end())
                  throw CLI::ValidationError(flag, "'" + text::printable(field) + "' is given twice (each item once), got '" +
                                                       text::printable(text) + "'");
                out.push_back(*v);
              }
            }
            values = std::move(out);
          },
          help)
      ->allow_extra_args(false)
      ->default_str(shown);
}

}  // namespace penumbra::cli
