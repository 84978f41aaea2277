#include "data/dataset.h"

#include <nlohmann/json.hpp>

#include "json/json_input.h"

#include <cstdio>
#include <fstream>
#include <set>
#include <stdexcept>

namespace penumbra::analysis {

namespace fs = std::filesystem;

std::string format_number(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%g", v);
  return b;
}

std::string condition_name(const std::string& pattern, double contrast) {
  return pattern + "/" + format_number(contrast);
}

namespace {

double number_field(const nlohmann::json& j, const std::string& file, const std::string& path, const char* key) {
  if (!j.contains(key) || !j[key].is_number())
    throw std::runtime_error(file + ": " + path + "." + key + ": expected a number");
  return j[key].get<double>();
}

// session.json's QUEST block and stopping rule; absent fields are an error only where present
// blocks are malformed (a bare log is fine, it just has no QUEST to recompute).
void read_session_json(const fs::path& path, SessionInfo& info) {
  const nlohmann::json j = json_input::read_file(path, {.max_bytes = 1 << 20, .max_depth = 8});
  const std::string file = path.string();
  if (!j.is_object()) throw std::runtime_error(file + ": expected an object");
  for (const char* key : {"session_id", "participant"}) {
    if (!j.contains(key) || !j[key].is_string()) throw std::runtime_error(file + ": " + key + ": expected a string");
  }
  info.session_id = j["session_id"].get<std::string>();
  info.participant = j["participant"].get<std::string>();
  if (j.contains("quest")) {
    const auto& q = j["quest"];
    if (!q.is_object()) throw std::runtime_error(file + ": quest: expected an object");
    quest::QuestParams p;
    p.t_guess = number_field(q, file, "quest", "t_guess");
    p.t_guess_sd = number_field(q, file, "quest", "t_guess_sd");
    p.p_threshold = number_field(q, file, "quest", "p_threshold");
    p.beta = number_field(q, file, "quest", "beta");
    p.delta = number_field(q, file, "quest", "delta");
    p.gamma = number_field(q, file, "quest", "gamma");
    p.grain = number_field(q, file, "quest", "grain");
    info.quest_dim = static_cast<int>(number_field(q, file, "quest", "dim"));
    if (info.quest_dim < 2) throw std::runtime_error(file + ": quest.dim: expected an integer >= 2");
    info.quest = p;
  }
  if (j.contains("config") && j["config"].is_object() && j["config"].contains("stopping")) {
    const auto& s = j["config"]["stopping"];
    if (s.is_object() && s.contains("sd_below")) info.sd_below = number_field(s, file, "config.stopping", "sd_below");
  }
}

}  // namespace

Dataset load_dataset(const std::vector<fs::path>& inputs) {
  if (inputs.empty()) throw std::runtime_error("no input: give session directories or trial CSV files");
  Dataset data;
  std::set<std::string> seen_ids;
  for (const fs::path& input : inputs) {
    if (!fs::exists(input)) throw std::runtime_error(input.string() + ": no such file or directory");
    SessionInfo info;
    fs::path log = input;
    fs::path json;
    if (fs::is_directory(input)) {
      log = input / "trials.csv";
      if (!fs::exists(log)) throw std::runtime_error(input.string() + ": not a session directory (no trials.csv)");
      json = input / "session.json";
    } else if (fs::exists(input.parent_path() / "session.json")) {
      json = input.parent_path() / "session.json";
    }
    if (!json.empty() && fs::exists(json)) read_session_json(json, info);
    info.log_file = log.string();
    const trial_log::ReadResult read = trial_log::read(log);
    info.torn_tail = read.torn_tail;
    const std::size_t index = data.sessions.size();
    int line = 1;
    for (const trial_log::TrialRow& row : read.rows) {
      ++line;
      const std::string where = info.log_file + ":" + std::to_string(line) + ": ";
      // The study numbers trials 0, 1, 2, ... across the session and appends one row per trial: any
      // other sequence is a duplicated, reordered or lost row (e.g. two processes on one session).
      if (row.trial != line - 2)
        throw std::runtime_error(where + "column 'trial': expected " + std::to_string(line - 2) + ", found " +
                                 std::to_string(row.trial) + " (rows duplicated, reordered or missing)");
      if (info.session_id.empty()) info.session_id = row.session_id;
      if (info.participant.empty()) info.participant = row.participant;
      if (row.session_id != info.session_id)
        throw std::runtime_error(where + "column 'session_id': '" + row.session_id + "' differs from the session's '" +
                                 info.session_id + "'");
      if (row.participant != info.participant)
        throw std::runtime_error(where + "column 'participant': '" + row.participant +
                                 "' differs from the session's '" + info.participant + "'");
      if (row.practice) {
        ++data.practice_rows;
        continue;
      }
      if (row.task == "yesno" && row.target == "straight") {
        ++data.catch_rows;
        data.catch_false_alarms += row.response == "no" ? 1 : 0;
        continue;
      }
      data.trials.push_back({row, index, line});
    }
    if (info.session_id.empty()) continue;  // an empty log (header only) adds nothing
    if (!seen_ids.insert(info.session_id).second)
      throw std::runtime_error(info.log_file + ": session '" + info.session_id + "' was given twice");
    data.sessions.push_back(info);
  }
  if (data.trials.empty()) throw std::runtime_error("no trials to fit (only headers or practice rows in the input)");
  return data;
}

}  // namespace penumbra::analysis
