#include "procedure/session_record.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>

#include "json/json_fields.h"
#include "json/json_input.h"
#include "text/printable.h"

namespace penumbra::procedure {

namespace {

bool same(double a, double b) { return std::abs(a - b) <= 1e-9 * std::max({1.0, std::abs(a), std::abs(b)}); }

std::string fmt(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.10g", v);
  return b;
}

}  // namespace

std::string name_problem(const std::string& name) {
  if (name.empty() || name.size() > kMaxName || !text::valid_utf8(name) ||
      std::any_of(name.begin(), name.end(), [](char c) { return static_cast<unsigned char>(c) < 0x20 || c == 0x7f || c == ',' || c == '"'; }))
    return "expected a non-empty UTF-8 name of at most " + std::to_string(kMaxName) + " bytes without , \" or control characters";
  return "";
}

nlohmann::json quest_block(const StudyConfig& config) {
  quest::Quest q(config.quest);
  return {{"t_guess", q.params().t_guess}, {"t_guess_sd", q.params().t_guess_sd},
          {"p_threshold", q.params().p_threshold}, {"beta", q.params().beta},
          {"delta", q.params().delta}, {"gamma", q.params().gamma},
          {"grain", q.params().grain}, {"dim", q.dim()},
          {"intensity", config.frames.enabled() ? "log10(1 / k)" : "log10(artifact_px / filter_radius_px)"}};
}


std::optional<nlohmann::json> display_calibration_block(const StudyConfig& config) {
  const stimuli::Transfer& t = config.display.transfer;
  if (t.kind != stimuli::Transfer::Kind::measured) return std::nullopt;
  if (!t.calibration) throw std::logic_error("display_calibration_block: the calibration of a measured transfer is not loaded");
  const nlohmann::json content = display::to_json(*t.calibration);
  return nlohmann::json{{"file", config.display.calibration_file}, {"fingerprint", display::fingerprint(content)}, {"content", content}};
}

void check_display_calibration_file(const StudyConfig& recorded, const std::string& session_file) {
  const auto block = display_calibration_block(recorded);
  if (!block) return;
  const std::string& file = recorded.display.calibration_file;
  std::string now;
  try {
    now = display::fingerprint(display::to_json(display::load_calibration(file)));
  } catch (const std::exception& e) {
    throw std::runtime_error(session_file + ": display_calibration: the session's calibration cannot be read now (" + e.what() +
                             "); restore " + file + " as it was (fingerprint " + (*block)["fingerprint"].get<std::string>() +
                             ") to resume");
  }
  if (now != (*block)["fingerprint"])
    throw std::runtime_error(session_file + ": display_calibration: " + file + " changed since the session started (fingerprint " + now +
                             ", the session's " + (*block)["fingerprint"].get<std::string>() +
                             "): the monitor was recalibrated? Start a new session, or restore the file to resume");
}

const char* to_string(ObserverKind kind) {
  switch (kind) {
    case ObserverKind::person: return "person";
    case ObserverKind::psychometric: return "psychometric-simulation";
    case ObserverKind::image: return "image-observer";
  }
  return "";
}

const char* describe(ObserverKind kind, int count) {
  switch (kind) {
    case ObserverKind::person: return count == 1 ? "a person" : "people";
    case ObserverKind::psychometric: return "psychometric simulation";
    case ObserverKind::image: return "image observer";
  }
  return "";
}

ObserverKind observer_kind_of_spec(const std::string& spec) {
  // The frame observer (a frame study's) is the image observer on frames.
  return spec.rfind("image", 0) == 0 || spec.rfind("frame", 0) == 0 ? ObserverKind::image : ObserverKind::psychometric;
}

ObserverKind observer_kind(const nlohmann::json& j, const std::string& file) {
  if (j.contains("observer_kind")) {
    const nlohmann::json& v = j["observer_kind"];
    for (ObserverKind k : {ObserverKind::person, ObserverKind::psychometric, ObserverKind::image})
      if (v.is_string() && v.get<std::string>() == to_string(k)) return k;
    throw std::runtime_error(file + ": observer_kind: " + (v.is_string() ? "'" + json_input::printable(v.get<std::string>()) + "'" : v.dump(-1).substr(0, 40)) +
                             " is not one of person, psychometric-simulation, image-observer");
  }
  // Sessions written before observer_kind: the windows recorded "participant", headless runs the spec.
  if (!j.contains("observer")) return ObserverKind::person;
  if (!j["observer"].is_string()) throw std::runtime_error(file + ": observer: expected a string");
  const std::string spec = j["observer"].get<std::string>();
  if (spec.empty() || spec == "participant") return ObserverKind::person;
  if (spec.rfind("psychometric", 0) == 0 || spec.rfind("image", 0) == 0) return observer_kind_of_spec(spec);
  throw std::runtime_error(file + ": observer: '" + json_input::printable(spec) +
                           "': expected participant, psychometric:... or image:... (who answered cannot be told)");
}

// Every field checked for type, size and agreement with the config block, since each is carried
// into the continued rows (or read by the fitter).
SessionRecord check_session_json(const nlohmann::json& j, const std::string& file) {
  const json_input::Reader reader(file);
  auto fail = [&](const std::string& field, const std::string& what) -> void { reader.fail(field, what); };
  using json_input::Type;
  static const json_input::ObjectSpec spec{{
      {.name = "session_id", .type = Type::string, .required = true, .max_length = 2 * kMaxName},
      {.name = "participant", .type = Type::string, .required = true, .max_length = kMaxName},
      {.name = "created_utc", .type = Type::string, .max_length = 64},
      {.name = "software", .type = Type::object},
      {.name = "seed", .type = Type::any, .required = true},
      {.name = "config", .type = Type::any, .required = true},
      {.name = "quest", .type = Type::object, .required = true},
      {.name = "display", .type = Type::any, .required = true},
      {.name = "log", .type = Type::string, .choices = {"trials.csv"}, .noun = "log"},
      {.name = "ended_rounds", .type = Type::any},
      {.name = "resumed_utc", .type = Type::any},
      {.name = "observer", .type = Type::string, .max_length = 1000},
      {.name = "observer_seed", .type = Type::any},
      {.name = "config_file", .type = Type::string, .max_length = 4096},
      {.name = "randomization", .type = Type::object,
       .object = json_input::spec({{{.name = "seed", .type = Type::integer, .required = true, .min = 0},
                                    {.name = "seed_from", .type = Type::string, .required = true,
                                     .choices = {"participant", "--seed", "config"}, .noun = "seed_from"},
                                    {.name = "round_order", .type = Type::array, .required = true}}})},
      {.name = "presentation", .type = Type::any},
      {.name = "display_calibration", .type = Type::any},
      {.name = "observer_kind", .type = Type::any},
      {.name = "consent", .type = Type::object, .nullable = true},
      {.name = "presentation_options", .type = Type::object},
  }};
  reader.object(j, "", spec);
  for (const json_input::Field& f : spec.fields) reader.get(j, "", spec, f.name);
  auto text = [&](const char* key) {
    const auto* v = reader.get(j, "", spec, key);
    return v ? v->get<std::string>() : std::string();
  };
  SessionRecord r;
  r.session_id = text("session_id");
  if (const std::string bad = name_problem(r.session_id); !bad.empty()) fail("session_id", bad);
  r.participant = text("participant");
  if (const std::string bad = name_problem(r.participant); !bad.empty()) fail("participant", bad);
  r.observer_kind = observer_kind(j, file);
  if (j.contains("observer_seed") && !j["observer_seed"].is_number_unsigned())
    fail("observer_seed", "expected a non-negative integer, got " + json_input::describe(j["observer_seed"]));
  r.config = parse_config(j["config"], file + " (config)");
  if (!j["seed"].is_number_unsigned() || j["seed"].get<std::uint64_t>() != r.config.seed)
    fail("seed", "expected the config's seed (" + std::to_string(r.config.seed) + ")");
  const nlohmann::json quest = quest_block(r.config);
  json_input::ObjectSpec quest_fields{{}};
  for (auto it = quest.begin(); it != quest.end(); ++it) quest_fields.fields.push_back({.name = it.key()});
  reader.object(j["quest"], "quest", quest_fields);
  for (auto it = quest.begin(); it != quest.end(); ++it) {
    const auto found = j["quest"].find(it.key());
    const bool equal = found != j["quest"].end() &&
                       (it->is_number() ? found->is_number() && same(found->get<double>(), it->get<double>())
                                        : *found == *it);
    if (!equal) fail("quest." + it.key(), "differs from the config's QUEST (expected " + it->dump() + ")");
  }
  if (j["display"] != to_json(r.config)["display"]) fail("display", "differs from config.display");
  // A measured transfer: the calibration the stimuli were encoded with, recorded whole.
  if (r.config.display.transfer.kind == stimuli::Transfer::Kind::measured) {
    if (!j.contains("display_calibration")) fail("display_calibration", "missing (config.display.calibration names one)");
    const auto& d = j["display_calibration"];
    if (!d.is_object() || d.size() != 3 || !d.contains("file") || !d.contains("fingerprint") || !d.contains("content"))
      fail("display_calibration", "expected {\"file\", \"fingerprint\", \"content\"}");
    if (d["file"] != r.config.display.calibration_file) fail("display_calibration.file", "differs from config.display.calibration");
    const display::DisplayCalibration calibration = display::parse_calibration(d["content"], file + " (display_calibration.content)");
    if (!d["fingerprint"].is_string() || d["fingerprint"] != display::fingerprint(display::to_json(calibration)))
      fail("display_calibration.fingerprint", "not the fingerprint of display_calibration.content (session.json edited?)");
    r.config.display.transfer = stimuli::Transfer::measured(calibration);
  } else if (j.contains("display_calibration")) {
    fail("display_calibration", "only with a measured display transfer (config.display.calibration)");
  }
  r.randomization = config_randomization(r.config);
  if (j.contains("randomization")) {
    const auto& z = j["randomization"];  // its fields checked with the others above
    r.randomization.seed = z["seed"].get<std::uint64_t>();
    r.randomization.seed_from = z["seed_from"].get<std::string>();
    if (z["round_order"].size() != r.config.rounds.size())
      fail("randomization.round_order", "expected an array of the " + std::to_string(r.config.rounds.size()) + " round indices");
    r.randomization.round_order.clear();
    for (const auto& v : z["round_order"]) {
      if (!v.is_number_unsigned() || v.get<std::uint64_t>() >= r.config.rounds.size())
        fail("randomization.round_order", "expected round indices 0.." + std::to_string(r.config.rounds.size() - 1));
      r.randomization.round_order.push_back(v.get<int>());
    }
    try {
      check_round_order(r.config, r.randomization.round_order);
    } catch (const std::invalid_argument& e) {
      fail("randomization.round_order", e.what());
    }
    // A seed derived from the participant must be that participant's: an edited participant or seed
    // would otherwise carry a foreign trial sequence into the continued rows.
    if (r.randomization.seed_from == "participant" && r.randomization.seed != randomize(r.config, r.participant, std::nullopt).seed)
      fail("randomization.seed", "not the seed of participant '" + json_input::printable(r.participant) + "' with the config's seed " +
                                     std::to_string(r.config.seed) + " (session.json edited?)");
  }
  if (j.contains("ended_rounds")) {
    const auto& e = j["ended_rounds"];
    if (!e.is_array() || e.size() > r.config.rounds.size()) fail("ended_rounds", "expected an array of at most one entry per round");
    for (std::size_t i = 0; i < e.size(); ++i) {
      const std::string f = "ended_rounds[" + std::to_string(i) + "]";
      if (!e[i].is_object() || e[i].size() != 2 || !e[i].contains("round") || !e[i].contains("after_trial") ||
          !e[i]["round"].is_number_unsigned() || !e[i]["after_trial"].is_number_unsigned() ||
          e[i]["round"].get<std::uint64_t>() >= r.config.rounds.size() || e[i]["after_trial"].get<std::uint64_t>() > 1000000)
        fail(f, "expected {\"round\": 0.." + std::to_string(r.config.rounds.size() - 1) + ", \"after_trial\": n}");
      r.ended.emplace_back(e[i]["round"].get<int>(), e[i]["after_trial"].get<int>());
    }
  }
  if (j.contains("presentation")) {  // what the participant view really was; recorded, not replayed
    const auto& e = j["presentation"];
    if (!e.is_array() || e.size() > 10000) fail("presentation", "expected an array of at most 10000 entries");
    for (std::size_t i = 0; i < e.size(); ++i)
      if (!e[i].is_object() || e[i].dump().size() > 4096)
        fail("presentation[" + std::to_string(i) + "]", "expected an object (at most 4096 bytes)");
  }
  if (j.contains("resumed_utc")) {
    const auto& e = j["resumed_utc"];
    if (!e.is_array()) fail("resumed_utc", "expected an array of times");
    for (std::size_t i = 0; i < e.size(); ++i)
      if (!e[i].is_string() || e[i].get<std::string>().size() > 64)
        fail("resumed_utc[" + std::to_string(i) + "]", "expected a time (a string)");
  }
  return r;
}

Procedure replay_log(const SessionRecord& record, const std::vector<trial_log::TrialRow>& rows, const std::string& file) {
  Procedure p(record.config, record.randomization);
  auto apply_ended = [&](int trials_done) {
    for (const auto& [round, after] : record.ended)
      if (after == trials_done) p.end_round(round);
  };
  apply_ended(0);
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const trial_log::TrialRow& row = rows[i];
    const int line = static_cast<int>(i) + 2;
    const std::string where = file + ":" + std::to_string(line) + ": ";
    const auto plan = p.next();
    if (!plan) throw LogMismatch(where + "a trial after the session had finished", line, row.trial);
    // The first column that differs is named, in log order.
    auto expect = [&](bool equal, const char* column, const std::string& found, const std::string& expected) {
      if (equal) return;
      throw LogMismatch(where + "column '" + column + "': '" + json_input::printable(found) +
                            "' where session.json and the replayed procedure give '" +
                            json_input::printable(expected) + "'",
                        line, row.trial);
    };
    auto number = [&](double found, double expected, const char* column) {
      expect(same(found, expected), column, fmt(found), fmt(expected));
    };
    auto integer = [&](long long found, long long expected, const char* column) {
      expect(found == expected, column, std::to_string(found), std::to_string(expected));
    };
    const StudyConfig& c = record.config;
    expect(row.session_id == record.session_id, "session_id", row.session_id, record.session_id);
    expect(row.participant == record.participant, "participant", row.participant, record.participant);
    // Older logs name the condition in a column 'round' and have no round_position (0 here).
    integer(row.condition_index, plan->round, row.round_position > 0 ? "condition_index" : "round");
    if (row.round_position > 0) integer(row.round_position, p.round_position(plan->round) + 1, "round_position");
    integer(row.trial, plan->trial, "trial");
    expect(row.staircase == plan->staircase_name, "staircase", row.staircase, plan->staircase_name);
    if (c.frames.enabled()) {
      expect(row.technique == plan->stimulus.technique, "technique", row.technique, plan->stimulus.technique);
      expect(row.scene == c.frames.scene, "scene", row.scene, c.frames.scene);
      integer(row.path_frame, c.frames.patches.at(static_cast<std::size_t>(plan->staircase)).path_frame, "path_frame");
      expect(row.task == c.task, "task", row.task, c.task);
      number(row.k, plan->k, "k");
      number(row.requested_k, plan->requested_k, "requested_k");
      integer(row.clamped, plan->clamped ? 1 : 0, "clamped");
      expect(row.target == plan->target, "target", row.target, plan->target);
      integer(row.practice, plan->practice ? 1 : 0, "practice");
      expect(row.stimulus_seed == plan->stimulus.seed, "stimulus_seed", std::to_string(row.stimulus_seed),
             std::to_string(plan->stimulus.seed));
    } else {
      const std::string pattern = stimuli::to_string(plan->stimulus.pattern);
      expect(row.pattern == pattern, "pattern", row.pattern, pattern);
      number(row.contrast, plan->stimulus.lit_linear, "contrast");
      number(row.artifact_px, plan->stimulus.artifact_px, "artifact_px");
      expect(row.task == c.task, "task", row.task, c.task);
      number(row.filter_radius_px, plan->stimulus.filter_radius_px, "filter_radius_px");
      const std::string kernel = stimuli::to_string(plan->stimulus.kernel);
      expect(row.kernel == kernel, "kernel", row.kernel, kernel);
      expect(row.target == plan->target, "target", row.target, plan->target);
      integer(row.practice, plan->practice ? 1 : 0, "practice");
      number(row.requested_filter_radius_px, plan->requested_filter_radius_px, "requested_filter_radius_px");
      integer(row.clamped, plan->clamped ? 1 : 0, "clamped");
      // The display as the rows recorded it: an edited size or distance changes every angle.
      number(row.artifact_arcmin, c.display.arcmin(row.artifact_px), "artifact_arcmin");
      number(row.filter_radius_arcmin, c.display.arcmin(row.filter_radius_px), "filter_radius_arcmin");
      expect(row.stimulus_seed == plan->stimulus.seed, "stimulus_seed", std::to_string(row.stimulus_seed),
             std::to_string(plan->stimulus.seed));
    }
    p.apply(*plan, row.correct == 1);
    // Every posterior after the update: a changed response (or a row added, removed or moved
    // within its staircase) shows here.
    const quest::Quest& q = p.staircase(*plan).quest;
    number(row.quest_mean, q.mean(), "quest_mean");
    number(row.quest_sd, q.sd(), "quest_sd");
    apply_ended(p.trials_done());
  }
  return p;
}

}  // namespace penumbra::procedure
