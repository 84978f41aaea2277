#include "data/dataset.h"

#include <nlohmann/json.hpp>

#include "io/safe_path.h"
#include "json/json_input.h"
#include "procedure/session_record.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <map>
#include <optional>
#include <tuple>
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
// blocks are malformed (a bare log is fine, it just has no QUEST to recompute). Returns the file.
nlohmann::json read_session_json(const fs::path& path, SessionInfo& info) {
  // A session directory's file: never read through a link (trials.csv likewise, trial_log::read).
  constexpr json_input::Limits limits{.max_bytes = 1 << 20, .max_depth = 8};
  nlohmann::json j = json_input::parse(io::read_file(path, limits.max_bytes, io::Links::refuse), path.string(), limits);
  const std::string file = path.string();
  if (!j.is_object()) throw std::runtime_error(file + ": expected an object");
  for (const char* key : {"session_id", "participant"}) {
    if (!j.contains(key) || !j[key].is_string()) throw std::runtime_error(file + ": " + key + ": expected a string");
  }
  info.session_id = j["session_id"].get<std::string>();
  info.participant = j["participant"].get<std::string>();
  info.observer_kind = procedure::to_string(procedure::observer_kind(j, file));
  if (j.contains("observer")) info.observer = j["observer"].get<std::string>();  // a string: observer_kind checked it
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
    const double dim = number_field(q, file, "quest", "dim");
    if (!(dim >= 2 && dim <= 1e7 && dim == std::floor(dim)))
      throw std::runtime_error(file + ": quest.dim: expected an integer in [2, 1e7]");
    info.quest_dim = static_cast<int>(dim);
    try {
      quest::Quest probe(p, info.quest_dim);  // the parameters QUEST itself refuses, named here
    } catch (const std::exception& e) {
      throw std::runtime_error(file + ": quest: " + e.what());
    }
    info.quest = p;
  }
  // The setup, flattened: what must agree between sessions that are pooled.
  // Objects nest ("stimulus.settings.pcf.kernel"); arrays stay whole.
  std::function<void(const std::string&, const nlohmann::json&)> flatten = [&](const std::string& prefix, const nlohmann::json& block) {
    if (!block.is_object()) return;
    for (auto it = block.begin(); it != block.end(); ++it) {
      if (it->is_object()) flatten(prefix + it.key() + ".", *it);
      else info.setup[prefix + it.key()] = it->is_string() ? it->get<std::string>() : it->dump();
    }
  };
  if (j.contains("display")) flatten("display.", j["display"]);
  // A measured transfer is compared by what was measured, not by where the file was: sessions on
  // one monitor pool whatever the path, sessions of a recalibrated monitor do not.
  if (j.contains("display_calibration") && j["display_calibration"].is_object() &&
      j["display_calibration"].contains("fingerprint") && j["display_calibration"]["fingerprint"].is_string())
    info.setup["display.calibration"] = "fingerprint " + j["display_calibration"]["fingerprint"].get<std::string>();
  if (j.contains("quest")) flatten("quest.", j["quest"]);
  if (j.contains("config") && j["config"].is_object()) {
    const auto& config = j["config"];
    if (config.contains("stimulus")) flatten("stimulus.", config["stimulus"]);
    if (config.contains("frames")) flatten("frames.", config["frames"]);  // a frame study: scene, patches, reference, grid
    if (config.contains("task") && config["task"].is_string()) info.setup["task"] = config["task"].get<std::string>();
    if (config.contains("yesno_scoring")) {
      if (!config["yesno_scoring"].is_string() ||
          (config["yesno_scoring"] != "jagged_only" && config["yesno_scoring"] != "balanced"))
        throw std::runtime_error(file + ": config.yesno_scoring: expected jagged_only or balanced");
      info.yesno_scoring = config["yesno_scoring"].get<std::string>();
      info.setup["yesno_scoring"] = info.yesno_scoring;
    }
  }
  // A browser session's display as the participant measured it (the server scaled each stimulus
  // to stimulus_css_px CSS pixels, so one stimulus pixel spans stimulus_css_px / size_px of them).
  if (j.contains("presentation") && j["presentation"].is_array()) {
    const nlohmann::json* shown = nullptr;
    for (const auto& entry : j["presentation"])
      if (entry.is_object() && entry.value("kind", std::string()) == "browser" && entry.value("fits", false)) shown = &entry;
    if (shown) {
      const double ppd = number_field(*shown, file, "presentation[kind browser]", "pixels_per_degree");
      const double css = number_field(*shown, file, "presentation[kind browser]", "stimulus_css_px");
      const auto size = info.setup.find("stimulus.size_px");
      const double size_px = size == info.setup.end() ? NAN : std::strtod(size->second.c_str(), nullptr);
      if (!(ppd > 0 && ppd < 1e5) || !(css > 0 && css < 1e5))
        throw std::runtime_error(file + ": presentation[kind browser]: pixels_per_degree and stimulus_css_px: expected positive numbers");
      if (size_px > 0) info.browser_pixels_per_degree = ppd * size_px / css;
    }
  }
  if (j.contains("config") && j["config"].is_object() && j["config"].contains("quest") && j["config"]["quest"].is_object() &&
      j["config"]["quest"].contains("tail_p_threshold"))
    info.tail_p_threshold = number_field(j["config"]["quest"], file, "config.quest", "tail_p_threshold");
  if (j.contains("config") && j["config"].is_object() && j["config"].contains("stopping")) {
    const auto& s = j["config"]["stopping"];
    if (s.is_object() && s.contains("sd_below")) info.sd_below = number_field(s, file, "config.stopping", "sd_below");
  }
  return j;
}

std::string fmt(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.10g", v);
  return b;
}

// Without the study's config (a simulated or older session): what the design implies about any
// log, and the posterior of each staircase replayed from session.json's QUEST block.
void check_without_config(const SessionInfo& info, const std::vector<trial_log::TrialRow>& rows,
                          const std::function<void(int line, const trial_log::TrialRow&, const std::string&)>& fail) {
  std::map<int, std::pair<std::string, double>> round_condition;
  std::map<std::pair<int, std::string>, quest::Quest> staircases;
  int line = 1;
  for (const trial_log::TrialRow& row : rows) {
    ++line;
    const std::string name = "a" + format_number(row.artifact_px);
    if (row.staircase != name)
      fail(line, row, "column 'staircase': '" + json_input::printable(row.staircase) + "' where the design names the staircase of artifact_px " +
                          format_number(row.artifact_px) + " '" + name + "'");
    const auto [it, first] = round_condition.try_emplace(row.condition_index, row.pattern, row.contrast);
    if (!first && (it->second.first != row.pattern || it->second.second != row.contrast))
      fail(line, row, "column 'pattern': round " + std::to_string(row.condition_index) + " is " +
                          condition_name(it->second.first, it->second.second) + " in earlier rows, " +
                          condition_name(row.pattern, row.contrast) + " here");
    if (!info.quest) continue;
    auto q = staircases.try_emplace({row.condition_index, row.staircase}, *info.quest, info.quest_dim).first;
    // As the procedure updates: not on practice trials, not on yes/no catch (straight) trials.
    if (!row.practice && !(row.task == "yesno" && row.target == "straight"))
      q->second.update(row.intensity, row.correct);
    for (const auto& [column, logged, replayed] :
         {std::tuple{"quest_mean", row.quest_mean, q->second.mean()}, std::tuple{"quest_sd", row.quest_sd, q->second.sd()}})
      if (!(std::abs(logged - replayed) <= 1e-9 * std::max({1.0, std::abs(logged), std::abs(replayed)})))
        fail(line, row, std::string("column '") + column + "': '" + fmt(logged) +
                            "' where session.json's QUEST replayed over the log gives '" + fmt(replayed) + "'");
  }
}

// The first inconsistency of one log, or nothing.
std::optional<Inconsistency> check_log(const SessionInfo& info, const nlohmann::json& session_json,
                                       const fs::path& json_path, const std::vector<trial_log::TrialRow>& rows) {
  struct Found {
    Inconsistency inconsistency;
  };
  auto fail = [&](int line, const trial_log::TrialRow& row, const std::string& what) {
    throw Found{{info.log_file, line, row.trial, info.log_file + ":" + std::to_string(line) + ": " + what}};
  };
  try {
    // The study numbers trials 0, 1, 2, ... across the session and appends one row per trial: any
    // other sequence is a duplicated, reordered or lost row (e.g. two processes on one session).
    for (std::size_t i = 0; i < rows.size(); ++i)
      if (rows[i].trial != static_cast<int>(i))
        fail(static_cast<int>(i) + 2, rows[i],
             "column 'trial': expected " + std::to_string(i) + ", found " + std::to_string(rows[i].trial) +
                 " (rows duplicated, reordered or missing)");
    if (session_json.is_object() && session_json.contains("config")) {
      const procedure::SessionRecord record = procedure::check_session_json(session_json, json_path.string());
      try {
        procedure::replay_log(record, rows, info.log_file);
      } catch (const procedure::LogMismatch& e) {
        throw Found{{info.log_file, e.line, e.trial, e.what()}};
      }
    } else {
      check_without_config(info, rows, fail);
    }
  } catch (const Found& found) {
    return found.inconsistency;
  }
  return std::nullopt;
}

// Where a session's setup was read: its session.json (beside the log).
std::string setup_file(const SessionInfo& s) { return (fs::path(s.log_file).parent_path() / "session.json").string(); }

// One participant per session, and sessions measured the same way (SessionInfo::setup); with
// `pool` the differences are listed instead of refused.
void check_poolable(Dataset& data, bool pool) {
  std::map<std::string, const SessionInfo*> by_participant;
  for (const SessionInfo& s : data.sessions) {
    const auto [it, fresh] = by_participant.emplace(s.participant, &s);
    if (!fresh)
      throw std::runtime_error(s.log_file + ": participant '" + json_input::printable(s.participant) + "' also in " +
                               it->second->log_file + ": one session per participant (give each session its own participant id)");
  }
  if (data.sessions.size() < 2) return;
  std::set<std::string> keys;
  for (const SessionInfo& s : data.sessions)
    for (const auto& [k, v] : s.setup) keys.insert(k);
  const SessionInfo& first = data.sessions.front();
  auto value = [](const SessionInfo& s, const std::string& key) {
    const auto it = s.setup.find(key);
    return it == s.setup.end() ? std::string("(not recorded)") : it->second;
  };
  for (const std::string& key : keys) {
    std::string listed;
    for (const SessionInfo& s : data.sessions) {
      if (value(s, key) == value(first, key)) continue;
      if (!pool)
        throw std::runtime_error(setup_file(s) + ": " + key + ": " + json_input::printable(value(s, key)) + " where " + setup_file(first) +
                                 " has " + json_input::printable(value(first, key)) +
                                 ": sessions measured differently are not pooled (fit them separately, or --pool)");
      listed += (listed.empty() ? "" : ", ") + json_input::printable(value(s, key)) + " (" + setup_file(s) + ")";
    }
    if (!listed.empty())
      data.pooled_differences.push_back(key + ": " + json_input::printable(value(first, key)) + " (" + setup_file(first) + "), " + listed);
  }
}

}  // namespace

Dataset load_dataset(const std::vector<fs::path>& inputs, const LoadOptions& options) {
  if (inputs.empty()) throw std::runtime_error("no input: give session directories or trial CSV files");
  Dataset data;
  std::set<std::string> seen_ids;
  for (const fs::path& input : inputs) {
    if (options.progress) options.progress(static_cast<int>(&input - inputs.data()), static_cast<int>(inputs.size()));
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
    nlohmann::json session_json;
    std::error_code ec;
    if (!json.empty() && fs::exists(fs::symlink_status(json, ec))) session_json = read_session_json(json, info);
    info.log_file = log.string();
    const trial_log::ReadResult read = trial_log::read(log);
    info.torn_tail = read.torn_tail;
    const std::size_t index = data.sessions.size();
    int line = 1;
    for (const trial_log::TrialRow& row : read.rows) {
      ++line;
      const std::string where = info.log_file + ":" + std::to_string(line) + ": ";
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
        data.catch_trials.push_back({row, index, line});
        continue;
      }
      data.trials.push_back({row, index, line});
    }
    if (std::optional<Inconsistency> bad = check_log(info, session_json, json, read.rows)) {
      if (!options.accept_inconsistent) throw InconsistentLog(*bad);
      data.inconsistencies.push_back(*bad);
    }
    if (info.session_id.empty()) continue;  // an empty log (header only) adds nothing
    if (!seen_ids.insert(info.session_id).second)
      throw std::runtime_error(info.log_file + ": session '" + info.session_id + "' was given twice");
    data.sessions.push_back(info);
  }
  if (data.trials.empty()) {
    std::string named;
    for (const fs::path& input : inputs) named += (named.empty() ? "" : ", ") + input.string();
    throw std::runtime_error(named + ": no trials to fit (only headers, practice rows or catch trials)");
  }
  check_poolable(data, options.pool);
  if (options.progress) options.progress(static_cast<int>(inputs.size()), static_cast<int>(inputs.size()));
  return data;
}

}  // namespace penumbra::analysis
