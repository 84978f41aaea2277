#include "text/printable.h"

#include <cstdio>

namespace penumbra::text {

bool valid_utf8(std::string_view s) {
  for (std::size_t i = 0; i < s.size();) {
    const auto c = static_cast<unsigned char>(s[i]);
    if (c < 0x80) {
      ++i;
      continue;
    }
    int n = 0;
    unsigned cp = 0;
    if (c >= 0xc2 && c <= 0xdf) n = 1, cp = c & 0x1f;
    else if (c >= 0xe0 && c <= 0xef) n = 2, cp = c & 0x0f;
    else if (c >= 0xf0 && c <= 0xf4) n = 3, cp = c & 0x07;
    else return false;
    if (i + static_cast<std::size_t>(n) >= s.size()) return false;
    for (int k = 1; k <= n; ++k) {
      const auto d = static_cast<unsigned char>(s[i + static_cast<std::size_t>(k)]);
      if ((d & 0xc0) != 0x80) return false;
      cp = (cp << 6) | (d & 0x3f);
    }
    if ((n == 2 && (cp < 0x800 || (cp >= 0xd800 && cp <= 0xdfff))) || (n == 3 && (cp < 0x10000 || cp > 0x10ffff)))
      return false;
    i += static_cast<std::size_t>(n) + 1;
  }
  return true;
}

std::string printable(std::string_view s, std::size_t max) {
  std::string out;
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (out.size() >= max) {
      out += "... (" + std::to_string(s.size()) + " bytes)";
      break;
    }
    const auto c = static_cast<unsigned char>(s[i]);
    if (c < 0x20 || c >= 0x7f) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\x%02x", c);
      out += buf;
    } else {
      out += static_cast<char>(c);
    }
  }
  return out;
}

std::string one_line(std::string_view message, std::size_t max_word, std::size_t max_line) {
  // Only spaces separate words. A newline or tab inside a message is escaped like any control byte:
  // it may be part of a path ("a\nb.json"), and printed as a space it named another path. Those at
  // the ends (a library's closing newline) are dropped.
  auto blank = [](char c) { return c == ' ' || c == '\n' || c == '\r' || c == '\t' || c == '\v' || c == '\f'; };
  const std::size_t total = message.size();
  while (!message.empty() && blank(message.front())) message.remove_prefix(1);
  while (!message.empty() && blank(message.back())) message.remove_suffix(1);
  auto space = [](char c) { return c == ' '; };
  std::string out;
  std::size_t i = 0;
  while (i < message.size()) {
    if (space(message[i])) {
      while (i < message.size() && space(message[i])) ++i;
      if (!out.empty() && i < message.size()) out += ' ';
      continue;
    }
    std::size_t end = i;
    while (end < message.size() && !space(message[end])) ++end;
    const std::string_view word = message.substr(i, end - i);
    bool plain = word.size() <= max_word && valid_utf8(word);
    for (char c : word)
      if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) plain = false;
    if (plain) {
      out += word;
    } else if (word.size() <= max_word) {
      out += printable(word, std::string::npos);
    } else {
      // Cut, but keep the closing quote and colon of "'<value>':" so the line still reads.
      std::size_t tail = 0;
      while (tail < 3 && std::string_view("'\":,;)]").find(word[word.size() - 1 - tail]) != std::string_view::npos) ++tail;
      out += printable(word.substr(0, word.size() - tail), 80) + std::string(word.substr(word.size() - tail));
    }
    i = end;
    if (out.size() > max_line) {
      out.resize(max_line);
      while (!out.empty() && (static_cast<unsigned char>(out.back()) & 0xc0) == 0x80) out.pop_back();  // whole characters
      if (!out.empty() && static_cast<unsigned char>(out.back()) >= 0xc0) out.pop_back();
      return out + "... (" + std::to_string(total) + " bytes)";
    }
  }
  return out;
}

}  // namespace penumbra::text
