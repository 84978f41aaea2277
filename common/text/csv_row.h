#pragma once
// One row of the project's comma-separated files (trials.csv, level data, photometer readings),
// typed field by field: one wording for every reader's errors,
//   FILE:LINE: expected N columns (NOTE), found M
//   FILE:LINE: column 'NAME': WHAT (found 'VALUE')
// with VALUE printable-escaped and shortened (text/printable.h). Header only; link penumbra_text.
#include <charconv>
#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "text/fields.h"
#include "text/printable.h"

namespace penumbra::text {

class CsvRow {
 public:
  // `fields` as split_fields gives them (trimmed or not: the caller's choice); their count must be
  // the names' ("expected 3 columns (level,n_correct,n_total), found 2"; no note: no parentheses).
  CsvRow(const std::string& file, int line, const std::vector<std::string>& names, std::vector<std::string> fields,
         const std::string& columns_note = {})
      : where_(file + ":" + std::to_string(line) + ": "), names_(names), fields_(std::move(fields)) {
    if (fields_.size() != names_.size())
      throw std::runtime_error(where_ + "expected " + std::to_string(names_.size()) + " columns" +
                               (columns_note.empty() ? "" : " (" + columns_note + ")") + ", found " + std::to_string(fields_.size()));
  }

  const std::string& operator[](std::size_t i) const { return fields_[i]; }
  std::size_t size() const { return fields_.size(); }
  // "FILE:LINE: ", for errors about the row as a whole.
  const std::string& where() const { return where_; }

  [[noreturn]] void fail(std::size_t i, const std::string& what) const {
    throw std::runtime_error(where_ + "column '" + names_[i] + "': " + what + " (found '" + printable(fields_[i]) + "')");
  }
  // A finite number, the whole field.
  double real(std::size_t i) const {
    double v = 0;
    const std::string& f = fields_[i];
    const auto [p, ec] = std::from_chars(f.data(), f.data() + f.size(), v);
    if (f.empty() || ec != std::errc() || p != f.data() + f.size() || !std::isfinite(v)) fail(i, "expected a finite number");
    return v;
  }
  // A whole number in [lo, hi].
  long integer(std::size_t i, long lo, long hi) const {
    long v = 0;
    const std::string& f = fields_[i];
    const auto [p, ec] = std::from_chars(f.data(), f.data() + f.size(), v);
    if (f.empty() || ec != std::errc() || p != f.data() + f.size() || v < lo || v > hi)
      fail(i, "expected an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
    return v;
  }
  std::uint64_t unsigned_integer(std::size_t i) const {
    std::uint64_t v = 0;
    const std::string& f = fields_[i];
    const auto [p, ec] = std::from_chars(f.data(), f.data() + f.size(), v);
    if (f.empty() || ec != std::errc() || p != f.data() + f.size()) fail(i, "expected an unsigned integer");
    return v;
  }
  // One of `allowed` exactly ("expected stair|step").
  std::string one_of(std::size_t i, std::initializer_list<const char*> allowed) const {
    for (const char* a : allowed)
      if (fields_[i] == a) return fields_[i];
    std::string list;
    for (const char* a : allowed) list += (list.empty() ? "" : "|") + std::string(a);
    fail(i, "expected " + list);
  }

 private:
  std::string where_;
  std::vector<std::string> names_;
  std::vector<std::string> fields_;
};

}  // namespace penumbra::text
