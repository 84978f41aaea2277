#include "json/json_input.h"

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <set>
#include <sstream>
#include <vector>

namespace penumbra::json_input {

using nlohmann::json;

std::string dump(const json& j, int indent) { return j.dump(indent, ' ', false, json::error_handler_t::replace); }

std::string child(const std::string& path, std::string_view key) {
  return path.empty() ? std::string(key) : path + "." + std::string(key);
}
std::string element(const std::string& path, std::size_t index) { return path + "[" + std::to_string(index) + "]"; }

namespace {

struct Refusal {
  std::string path, what;
};

// Tracks the field path during the parse to name a duplicated key or a too-deep nesting.
class Check {
 public:
  explicit Check(int max_depth) : max_depth_(max_depth) {}
  bool operator()(int /*depth*/, json::parse_event_t event, json& parsed) {
    switch (event) {
      case json::parse_event_t::object_start:
      case json::parse_event_t::array_start:
        if (static_cast<int>(frames_.size()) >= max_depth_)
          throw Refusal{path(), "nested deeper than " + std::to_string(max_depth_) + " levels"};
        frames_.push_back({event == json::parse_event_t::array_start, 0, {}, {}});
        break;
      case json::parse_event_t::key: {
        Frame& f = frames_.back();
        f.key = parsed.get<std::string>();
        if (!f.keys.insert(f.key).second) throw Refusal{path(), "duplicate key"};
        break;
      }
      case json::parse_event_t::object_end:
      case json::parse_event_t::array_end:
        frames_.pop_back();
        element_done();
        break;
      case json::parse_event_t::value: element_done(); break;
    }
    return true;
  }

 private:
  struct Frame {
    bool array;
    std::size_t index;
    std::string key;
    std::set<std::string> keys;
  };
  void element_done() {
    if (!frames_.empty() && frames_.back().array) ++frames_.back().index;
  }
  std::string path() const {
    std::string p;
    for (const Frame& f : frames_) p = f.array ? element(p, f.index) : child(p, printable(f.key, 60));
    return p.empty() ? "(top level)" : p;
  }
  int max_depth_;
  std::vector<Frame> frames_;
};

// 1-based line and column of the 1-based byte position `byte` in `text`.
std::pair<std::size_t, std::size_t> line_column(std::string_view text, std::size_t byte) {
  const std::size_t pos = std::min(byte == 0 ? 0 : byte - 1, text.size());
  const std::size_t line =
      1 + static_cast<std::size_t>(std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(pos), '\n'));
  const std::size_t last_newline = text.rfind('\n', pos == 0 ? std::string_view::npos : pos - 1);
  const std::size_t column = last_newline == std::string_view::npos || pos == 0 ? pos + 1 : pos - last_newline;
  return {line, column};
}

// nlohmann's messages start with "[json.exception.x.n] " and repeat the position we print; the
// rest may quote the input (a token, a string's bytes).
std::string strip(std::string msg) {
  if (const auto p = msg.find("] "); msg.starts_with("[json.exception") && p != std::string::npos) msg.erase(0, p + 2);
  if (msg.starts_with("parse error at line"))
    if (const auto p = msg.find(": "); p != std::string::npos) msg.erase(0, p + 2);
  return printable(msg, 160);
}

}  // namespace

json parse(std::string_view text, const std::string& file, const Limits& limits) {
  if (text.size() > limits.max_bytes)
    throw JsonError(file + ": larger than " + std::to_string(limits.max_bytes) + " bytes (" +
                    std::to_string(text.size()) + ")");
  const auto where = [&](std::size_t byte) {
    const auto [line, column] = line_column(text, byte);
    return file + ":" + std::to_string(line) + ":" + std::to_string(column) + ": ";
  };
  try {
    return json::parse(text.begin(), text.end(), Check(limits.max_depth));
  } catch (const json::parse_error& e) {
    throw JsonError(where(e.byte) + "malformed JSON: " + strip(e.what()));
  } catch (const Refusal& r) {
    throw JsonError(file + ": " + r.path + ": " + r.what);
  } catch (const json::exception& e) {
    // Number overflow ("number overflow parsing '1e400'") carries no position: find the token.
    const std::string msg = strip(e.what());
    std::string prefix = file + ": ";
    if (const auto a = msg.find('\''), b = msg.rfind('\''); a != std::string::npos && b > a + 1)
      if (const auto at = text.find(msg.substr(a + 1, b - a - 1)); at != std::string_view::npos) prefix = where(at + 1);
    throw JsonError(prefix + "malformed JSON: " + msg);
  }
}

json read_file(const std::filesystem::path& path, const Limits& limits) {
  std::error_code ec;
  const std::string file = path.string();
  if (!std::filesystem::is_regular_file(path, ec))
    throw JsonError(file + ": cannot read: " +
                    (std::filesystem::exists(path, ec) ? "not a regular file" : "no such file"));
  const auto size = std::filesystem::file_size(path, ec);
  if (!ec && size > limits.max_bytes)
    throw JsonError(file + ": larger than " + std::to_string(limits.max_bytes) + " bytes (" + std::to_string(size) +
                    ")");
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  if (!in) throw JsonError(file + ": cannot read");
  return parse(text.str(), file, limits);
}

}  // namespace penumbra::json_input
