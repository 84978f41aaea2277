#pragma once
// Splitting a tool's grid of independent renders into N parts that run anywhere (a lab's
// workstations through GNU parallel, a cluster's Slurm array; docs/cluster.md) and merging the
// parts back. The rule is fixed: the grid's items are numbered in the tool's own loop order and
// shard I of N takes every item whose number is I modulo N, so neighbouring (similar-cost) items
// spread over the shards. A part file records what it covers and what made it: the tool, the
// build's version line, a fingerprint of the settings and the shard; the merge refuses a part that
// is missing, given twice, or made with other settings or by another build, before it writes.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <initializer_list>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

namespace penumbra::shard {

struct Shard {
  std::size_t index = 0;  // I, 0-based
  std::size_t count = 1;  // N
  // Whether grid item `item` (its number in the tool's loop order) belongs to this shard.
  bool covers(std::size_t item) const { return item % count == index; }
  std::string text() const { return std::to_string(index) + "/" + std::to_string(count); }
};

// "I/N" with 0 <= I < N: the shard of `option` ("--shard"). Anything else throws
// std::invalid_argument "<option>: ...", one line naming the option.
Shard parse(std::string_view text, std::string_view option = "--shard");

// The command line `args` less the options `names` and their values: a part's settings leave out
// --shard, --part and where the output goes, so that the merge parses the rest again with its own
// output. A name given alone takes the next argument with it; NAME=VALUE, and -oVALUE for a
// one-letter name such as -o, is one argument.
std::vector<std::string> without_options(const std::vector<std::string>& args, std::initializer_list<std::string_view> names);

// The command line a part's settings carry as "args" (a list of strings): what the merge runs the
// tool with. Throws std::runtime_error "<file>: settings.args: ..." for anything else.
std::vector<std::string> stored_args(const nlohmann::json& settings, const std::string& file);

// A command line given as strings (without the tool's name, as the user's or a merge's stored
// one) as the argc and argv CLI11 parses, with `tool` in argv[0]. argv points into this object.
class Argv {
 public:
  Argv(std::string_view tool, const std::vector<std::string>& args);
  Argv(const Argv&) = delete;
  Argv& operator=(const Argv&) = delete;
  int argc() const { return static_cast<int>(pointers_.size()); }
  char** argv() { return pointers_.data(); }

 private:
  std::vector<std::string> text_;
  std::vector<char*> pointers_;
};

// A stable 16-hex-digit fingerprint (FNV-1a, 64 bits) of a settings text.
std::string fingerprint(std::string_view settings);

// One part file's header and its tool's own payload.
struct Part {
  std::filesystem::path path;
  Shard shard;
  nlohmann::json payload;
};

// The text of a part of `kind` ("penumbra-observer-curve part") for `shard`: the version line,
// the settings (what the tool needs to redo the merge, fingerprinted) and the payload.
std::string part_text(std::string_view kind, std::string_view version, const Shard& shard, const nlohmann::json& settings,
                      const nlohmann::json& payload);

// Reads and checks `paths` as the N parts of one sharded run of `kind` made by `version`: each is
// such a part, all carry the first one's settings and shard count, every shard 0..N-1 is there
// exactly once. Returns the parts ordered by shard and the settings they share. Throws
// std::runtime_error, one line naming the file at fault (or the missing shard).
struct Checked {
  std::vector<Part> parts;
  nlohmann::json settings;
};
Checked read_parts(const std::vector<std::filesystem::path>& paths, std::string_view kind, std::string_view version);

}  // namespace penumbra::shard
