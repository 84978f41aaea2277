#pragma once
// Command-line checks that CLI11's own let slip: CLI::Range compares with < and >, so NaN (every
// comparison false) passes it; an unsigned option takes "-1" as 2^64 - 1; a path may be "".
// Header only (CLI11).
#include <CLI/CLI.hpp>

#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

namespace penumbra::cli {

// A finite number in [lo, hi].
inline CLI::Validator finite_range(double lo, double hi) {
  char range[64];
  std::snprintf(range, sizeof range, "[%g, %g]", lo, hi);
  const std::string text = range;
  return CLI::Validator(
      [lo, hi, text](std::string& input) -> std::string {
        char* end = nullptr;
        const double v = std::strtod(input.c_str(), &end);
        if (input.empty() || end != input.c_str() + input.size() || !(v >= lo && v <= hi))
          return "expected a finite number in " + text;
        return {};
      },
      "FLOAT in " + text, "FINITE_RANGE");
}

// Digits only, no sign, and at most 2^64 - 1: nothing wraps, nothing saturates (CLI11 stored
// 18446744073709551616 and beyond as 18446744073709551615 without a word).
inline CLI::Validator non_negative_integer() {
  return CLI::Validator(
      [](std::string& input) -> std::string {
        std::uint64_t value = 0;
        const auto [end, error] = std::from_chars(input.data(), input.data() + input.size(), value);
        if (input.empty() || input.find_first_not_of("0123456789") != std::string::npos) return "expected a non-negative integer";
        if (error == std::errc::result_out_of_range || end != input.data() + input.size())
          return "expected a non-negative integer of at most 18446744073709551615 (2^64 - 1)";
        return {};
      },
      "UINT", "NON_NEGATIVE_INTEGER");
}

// A file or directory name: not empty (`-o ""` used to run the whole job and fail at the rename).
inline CLI::Validator path_given() {
  return CLI::Validator(
      [](std::string& input) -> std::string { return input.empty() ? "expected a path, got ''" : std::string(); },
      "PATH", "PATH_GIVEN");
}

}  // namespace penumbra::cli
