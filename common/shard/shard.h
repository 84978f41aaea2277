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
