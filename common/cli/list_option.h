#pragma once
// One comma list for every tool's options (--resolution 512,1024; --pattern stair,step): header
// only (CLI11). CLI11's own delimiter drops an empty item without a word ("64,,128" ran 64 and 128)
// and takes lists without end, so each list option goes through add_list_option instead:
//  - split by text::split_fields: an empty item (a doubled or trailing comma, "") is refused;
//  - at most kMaxListValues items over all its occurrences (each item is usually a whole render:
//    a 1000-entry --resolution ran for minutes);
//  - each item read by a ListItem (integers_in, numbers_in, non_negative_integers, names), so "-1" never
//    wraps to 2^64 - 1 and "nan" is no number;
//  - repeating the option adds to the list (--pattern stair --pattern step).
// One wording for every refusal: "--OPTION: expected ONE, or at most 64 separated by commas, got 'TEXT'".
#include <CLI/CLI.hpp>

#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
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

inline ListItem<int> integers_in(int lo, int hi) {
  return {"an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]", [lo, hi](const std::string& s) -> std::optional<int> {
            const auto v = detail::whole<int>(s);
            if (!v || *v < lo || *v > hi) return std::nullopt;
            return v;
          }};
}

// A finite number in [lo, hi] (strtod's forms, nothing after the number).
inline ListItem<double> numbers_in(double lo, double hi) {
  char range[64];
  std::snprintf(range, sizeof range, "[%g, %g]", lo, hi);
  return {std::string("a finite number in ") + range, [lo, hi](const std::string& s) -> std::optional<double> {
            char* end = nullptr;
            const double v = std::strtod(s.c_str(), &end);
            if (s.empty() || end != s.c_str() + s.size() || !std::isfinite(v) || v < lo || v > hi) return std::nullopt;
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
