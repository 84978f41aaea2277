#include "shard/shard.h"

#include <algorithm>
#include <charconv>
#include <cstdio>
#include <map>
#include <stdexcept>

#include "json/json_input.h"

namespace penumbra::shard {

namespace {

constexpr std::size_t kMaxShards = 1000000;  // far above any array a scheduler runs

// A whole decimal number, nothing else; false for anything else.
bool whole(std::string_view text, std::size_t& out) {
  if (text.empty() || text.size() > 9) return false;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), out);
  return ec == std::errc{} && end == text.data() + text.size();
}

}  // namespace

Shard parse(std::string_view text, std::string_view option) {
  const std::string opt(option), shown = json_input::printable(text, 40);
  const std::size_t slash = text.find('/');
  Shard shard;
  if (slash == std::string_view::npos || !whole(text.substr(0, slash), shard.index) || !whole(text.substr(slash + 1), shard.count))
    throw std::invalid_argument(opt + ": '" + shown + "' is not I/N (shard I of N, 0 <= I < N, as 0/4)");
  if (shard.count < 1 || shard.count > kMaxShards)
    throw std::invalid_argument(opt + ": " + shown + ": N must be 1 to " + std::to_string(kMaxShards));
  if (shard.index >= shard.count)
    throw std::invalid_argument(opt + ": " + shown + ": I must be below N (the shards are 0/" + std::to_string(shard.count) + " to " +
                                std::to_string(shard.count - 1) + "/" + std::to_string(shard.count) + ")");
  return shard;
}

std::vector<std::string> without_options(const std::vector<std::string>& args, std::initializer_list<std::string_view> names) {
  std::vector<std::string> out;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string_view arg = args[i];
    bool alone = false, joined = false;
    for (const std::string_view name : names) {
      alone = alone || arg == name;
      joined = joined || (arg.starts_with(name) && arg.size() > name.size() && arg[name.size()] == '=');
      const bool one_letter = name.size() == 2 && name[0] == '-' && name[1] != '-';
      joined = joined || (one_letter && arg.size() > 2 && arg.starts_with(name) && arg[2] != '-');
    }
    if (alone) ++i;  // and its value
    else if (!joined) out.push_back(args[i]);
  }
  return out;
}

std::vector<std::string> stored_args(const nlohmann::json& settings, const std::string& file) {
  if (!settings.contains("args") || !settings["args"].is_array()) throw std::runtime_error(file + ": settings.args: not a list of arguments");
  std::vector<std::string> args;
  for (const auto& a : settings["args"]) {
    if (!a.is_string()) throw std::runtime_error(file + ": settings.args: not a list of arguments");
    args.push_back(a.get<std::string>());
  }
  return args;
}

Argv::Argv(std::string_view tool, const std::vector<std::string>& args) : text_{std::string(tool)} {
  text_.insert(text_.end(), args.begin(), args.end());
  for (std::string& a : text_) pointers_.push_back(a.data());
}

std::string fingerprint(std::string_view settings) {
  std::uint64_t hash = 0xcbf29ce484222325ull;
  for (const char c : settings) {
    hash ^= static_cast<unsigned char>(c);
    hash *= 0x100000001b3ull;
  }
  char text[17];
  std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(hash));
  return text;
}

std::string part_text(std::string_view kind, std::string_view version, const Shard& shard, const nlohmann::json& settings,
                      const nlohmann::json& payload) {
  const nlohmann::json part = {{"kind", kind},
                               {"version", version},
                               {"fingerprint", fingerprint(json_input::dump(settings))},
                               {"shard", {{"index", shard.index}, {"count", shard.count}}},
                               {"settings", settings},
                               {"payload", payload}};
  return json_input::dump(part) + "\n";
}

Checked read_parts(const std::vector<std::filesystem::path>& paths, std::string_view kind, std::string_view version) {
  if (paths.empty()) throw std::runtime_error("no parts given");
  Checked checked;
  std::string first_fingerprint;
  std::map<std::size_t, std::filesystem::path> seen;  // shard index -> its part
  for (const std::filesystem::path& path : paths) {
    const std::string file = json_input::printable(path.string(), 200);
    const nlohmann::json j = json_input::read_file(path);
    const auto field = [&](const char* key, bool (nlohmann::json::*is)() const noexcept) -> const nlohmann::json& {
      if (!j.is_object() || !j.contains(key) || !(j[key].*is)())
        throw std::runtime_error(file + ": not a " + std::string(kind) + " (field " + key + " missing or of the wrong type)");
      return j[key];
    };
    if (field("kind", &nlohmann::json::is_string).get<std::string>() != kind)
      throw std::runtime_error(file + ": a " + json_input::printable(j["kind"].get<std::string>(), 60) + ", not a " + std::string(kind));
    const std::string made_by = field("version", &nlohmann::json::is_string).get<std::string>();
    if (made_by != version)
      throw std::runtime_error(file + ": made by " + json_input::printable(made_by, 80) + ", not by this build (" + std::string(version) +
                               "); merge the parts with the build that made them");
    const nlohmann::json& settings = field("settings", &nlohmann::json::is_object);
    const std::string print = fingerprint(json_input::dump(settings));
    if (field("fingerprint", &nlohmann::json::is_string).get<std::string>() != print)
      throw std::runtime_error(file + ": its settings do not match its fingerprint (edited after it was written?)");
    const nlohmann::json& shard_field = field("shard", &nlohmann::json::is_object);
    Part part{path, {}, field("payload", &nlohmann::json::is_object)};
    if (!shard_field.contains("index") || !shard_field["index"].is_number_unsigned() || !shard_field.contains("count") ||
        !shard_field["count"].is_number_unsigned())
      throw std::runtime_error(file + ": not a " + std::string(kind) + " (shard.index, shard.count: whole numbers)");
    part.shard = parse(std::to_string(shard_field["index"].get<std::size_t>()) + "/" + std::to_string(shard_field["count"].get<std::size_t>()),
                       file + ": shard");
    if (checked.parts.empty()) {
      first_fingerprint = print;
      checked.settings = settings;
    } else {
      const std::string first = json_input::printable(checked.parts.front().path.string(), 200);
      if (print != first_fingerprint)
        throw std::runtime_error(file + ": made with other settings than " + first + " (fingerprint " + print + ", not " + first_fingerprint + ")");
      if (part.shard.count != checked.parts.front().shard.count)
        throw std::runtime_error(file + ": shard " + part.shard.text() + ", but " + first + " is one of " +
                                 std::to_string(checked.parts.front().shard.count));
    }
    if (const auto [at, fresh] = seen.emplace(part.shard.index, path); !fresh)
      throw std::runtime_error(file + ": shard " + part.shard.text() + " again (also " + json_input::printable(at->second.string(), 200) + ")");
    checked.parts.push_back(std::move(part));
  }
  const std::size_t count = checked.parts.front().shard.count;
  for (std::size_t i = 0; i < count; ++i)
    if (!seen.contains(i))
      throw std::runtime_error("shard " + std::to_string(i) + "/" + std::to_string(count) + " missing: none of the " +
                               std::to_string(paths.size()) + " parts given (" + json_input::printable(paths.front().string(), 200) +
                               (paths.size() > 1 ? ", ..." : "") + ") covers it");
  std::sort(checked.parts.begin(), checked.parts.end(), [](const Part& a, const Part& b) { return a.shard.index < b.shard.index; });
  return checked;
}

}  // namespace penumbra::shard
