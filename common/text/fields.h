#pragma once
// The fields of one line of the project's comma-separated files and lists (trials.csv, level
// data, photometer readings, the tools' comma lists): one split, so that "a,,b" and a trailing
// comma mean the same in every reader (header only).
#include <string>
#include <string_view>
#include <vector>

namespace penumbra::text {

// Every field as written: no quoting (none of these files quote), empty fields kept ("a,,b" ->
// "a", "", "b"; "a," -> "a", ""; "" -> one empty field), nothing trimmed.
inline std::vector<std::string> split_fields(std::string_view line, char separator = ',') {
  std::vector<std::string> fields;
  std::size_t start = 0;
  for (;;) {
    const std::size_t end = line.find(separator, start);
    fields.emplace_back(line.substr(start, end == std::string_view::npos ? std::string_view::npos : end - start));
    if (end == std::string_view::npos) return fields;
    start = end + 1;
  }
}

// `s` without leading and trailing spaces, tabs and carriage returns.
inline std::string trim(std::string_view s) {
  const auto first = s.find_first_not_of(" \t\r");
  if (first == std::string_view::npos) return {};
  return std::string(s.substr(first, s.find_last_not_of(" \t\r") - first + 1));
}

}  // namespace penumbra::text
