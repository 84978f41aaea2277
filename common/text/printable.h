#pragma once
// Text from outside (file contents, names, paths, command-line values) as it may appear in an
// error line or a file we write: checked for UTF-8, escaped and shortened, so a megabyte value or
// a control byte never reaches a terminal whole.
#include <cstddef>
#include <string>
#include <string_view>

namespace penumbra::text {

// UTF-8 without overlong forms, surrogates or code points above U+10FFFF.
bool valid_utf8(std::string_view s);

// Control bytes and non-ASCII bytes escaped (\xNN), cut to about `max` bytes with the total length
// named: for quoting a value.
std::string printable(std::string_view s, std::size_t max = 80);

// A whole message made safe for one line on stderr: every run of spaces becomes one space,
// whitespace at either end is dropped, words with control bytes (a newline or tab inside the message
// included: it may be part of a path) or invalid UTF-8 are escaped, words longer than
// `max_word` bytes are cut as printable() cuts them, and the line is cut after about `max_line`
// bytes. Valid UTF-8 stays as it is.
std::string one_line(std::string_view message, std::size_t max_word = 120, std::size_t max_line = 1000);

}  // namespace penumbra::text
