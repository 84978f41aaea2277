#pragma once
// Strict JSON input shared by every reader of a file a person may have edited (scene files, study
// configs, session.json, calibration.json, reference tables): nlohmann's parser plus what it lets
// through silently. A duplicated key (nlohmann keeps the last one), nesting deeper than a file of
// ours ever needs, a file larger than any of ours, a number that overflows a double, malformed
// UTF-8 or syntax: each is one line "FILE: field.path: what" or "FILE:LINE:COLUMN: malformed JSON:
// what", with values shortened and control bytes escaped.
#include <cstddef>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

#include "text/printable.h"

namespace penumbra::json_input {

class JsonError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct Limits {
  std::size_t max_bytes = std::size_t{64} << 20;  // the scene files' own bound is far below
  int max_depth = 64;
};

// `text` as read from `file` (named in errors). Throws JsonError.
nlohmann::json parse(std::string_view text, const std::string& file, const Limits& limits = {});
// Reads and parses a regular file; a missing file, a directory or an unreadable one is a JsonError
// naming it.
nlohmann::json read_file(const std::filesystem::path& path, const Limits& limits = {});

// For error messages: control bytes and non-ASCII bytes escaped (\xNN), cut to about `max` bytes
// with the total length named, so a megabyte of input never becomes a megabyte of stderr.
using text::printable;

// The text of a file we write: invalid UTF-8 (a path or name from outside) becomes U+FFFD
// instead of nlohmann's type_error.316 after the work is done.
std::string dump(const nlohmann::json& j, int indent = -1);

// "a.b", "a[3]": the field path notation of every error.
std::string child(const std::string& path, std::string_view key);
std::string element(const std::string& path, std::size_t index);

}  // namespace penumbra::json_input
