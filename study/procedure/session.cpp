#include "procedure/session.h"

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <ctime>
#include <fstream>
#include <set>
#include <algorithm>
#include <stdexcept>

#include "io/image_io.h"
#include "json/json_input.h"
#include "observers/random.h"

namespace penumbra::procedure {

namespace fs = std::filesystem;

std::string utc_now() {
  const auto now = std::chrono::system_clock::now();
  const std::time_t t = std::chrono::system_clock::to_time_t(now);
  const auto ms = std::chrono::duration_cast<std::chrono::milliseconds>(now.time_since_epoch()).count() % 1000;
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[96];
  std::snprintf(buf, sizeof buf, "%04d-%02d-%02dT%02d:%02d:%02d.%03dZ", tm.tm_year + 1900, tm.tm_mon + 1, tm.tm_mday,
                tm.tm_hour, tm.tm_min, tm.tm_sec, static_cast<int>(ms));
  return buf;
}

namespace {
std::string fmt(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%g", v);
  return b;
}

// Names go into every row of the log: no separators, no control bytes, and short (a megabyte
// participant string made each row a megabyte).
constexpr std::size_t kMaxName = 200;
std::string name_problem(const std::string& name) {
  if (name.empty() || name.size() > kMaxName ||
      std::any_of(name.begin(), name.end(), [](char c) { return static_cast<unsigned char>(c) < 0x20 || c == 0x7f || c == ',' || c == '"'; }))
    return "expected a non-empty name of at most " + std::to_string(kMaxName) + " bytes without , \" or control characters";
  return "";
}

// The QUEST block session.json records beside the config (read by the fitter).
nlohmann::json quest_block(const StudyConfig& config) {
  quest::Quest q(config.quest);
  return {{"t_guess", q.params().t_guess}, {"t_guess_sd", q.params().t_guess_sd},
          {"p_threshold", q.params().p_threshold}, {"beta", q.params().beta},
          {"delta", q.params().delta}, {"gamma", q.params().gamma},
          {"grain", q.params().grain}, {"dim", q.dim()},
          {"intensity", "log10(artifact_px / filter_radius_px)"}};
}

bool same(double a, double b) { return std::abs(a - b) <= 1e-9 * std::max({1.0, std::abs(a), std::abs(b)}); }

// session.json as resume reads it: every field checked for type, size and agreement with the
// config block, since each is carried into the continued rows (or read by the fitter).
struct SessionRecord {
  StudyConfig config;
  std::string session_id, participant;
  std::vector<std::pair<int, int>> ended;  // (round, after_trial)
};

SessionRecord check_session_json(const nlohmann::json& j, const std::string& file) {
  auto fail = [&](const std::string& field, const std::string& what) -> void {
    throw std::runtime_error(file + ": " + field + ": " + what);
  };
  if (!j.is_object()) fail("(top level)", "expected an object");
  static const std::set<std::string> known = {"session_id", "participant", "created_utc", "software", "seed", "config",
                                              "quest", "display", "log", "ended_rounds", "resumed_utc", "observer",
                                              "observer_seed", "config_file"};
  for (auto it = j.begin(); it != j.end(); ++it)
    if (!known.count(it.key())) fail(json_input::printable(it.key()), "unknown field");
  for (const char* key : {"session_id", "participant", "config", "seed", "quest", "display"})
    if (!j.contains(key)) fail(key, "missing");
  auto text = [&](const char* key, std::size_t max) {
    if (!j.contains(key)) return std::string();
    if (!j[key].is_string()) fail(key, "expected a string");
    const std::string v = j[key].get<std::string>();
    if (v.size() > max) fail(key, "longer than " + std::to_string(max) + " bytes");
    return v;
  };
  SessionRecord r;
  r.session_id = text("session_id", 2 * kMaxName);
  if (const std::string bad = name_problem(r.session_id); !bad.empty()) fail("session_id", bad);
  r.participant = text("participant", kMaxName);
  if (const std::string bad = name_problem(r.participant); !bad.empty()) fail("participant", bad);
  text("created_utc", 64);
  text("observer", 1000);
  text("config_file", 4096);
  if (j.contains("log") && j["log"] != "trials.csv") fail("log", "expected \"trials.csv\"");
  if (j.contains("observer_seed") && !j["observer_seed"].is_number_unsigned())
    fail("observer_seed", "expected a non-negative integer");
  if (j.contains("software") && !j["software"].is_object()) fail("software", "expected an object");
  r.config = parse_config(j["config"], file + " (config)");
  if (!j["seed"].is_number_unsigned() || j["seed"].get<std::uint64_t>() != r.config.seed)
    fail("seed", "expected the config's seed (" + std::to_string(r.config.seed) + ")");
  const nlohmann::json quest = quest_block(r.config);
  if (!j["quest"].is_object()) fail("quest", "expected an object");
  for (auto it = j["quest"].begin(); it != j["quest"].end(); ++it)
    if (!quest.contains(it.key())) fail("quest." + json_input::printable(it.key()), "unknown field");
  for (auto it = quest.begin(); it != quest.end(); ++it) {
    const auto found = j["quest"].find(it.key());
    const bool equal = found != j["quest"].end() &&
                       (it->is_number() ? found->is_number() && same(found->get<double>(), it->get<double>())
                                        : *found == *it);
    if (!equal) fail("quest." + it.key(), "differs from the config's QUEST (expected " + it->dump() + ")");
  }
  if (j["display"] != to_json(r.config)["display"]) fail("display", "differs from config.display");
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
  if (j.contains("resumed_utc")) {
    const auto& e = j["resumed_utc"];
    if (!e.is_array()) fail("resumed_utc", "expected an array of times");
    for (std::size_t i = 0; i < e.size(); ++i)
      if (!e[i].is_string() || e[i].get<std::string>().size() > 64)
        fail("resumed_utc[" + std::to_string(i) + "]", "expected a time (a string)");
  }
  return r;
}

}  // namespace

std::string Session::condition(int round) const {
  const auto& r = config_.rounds.at(static_cast<std::size_t>(round));
  return stimuli::to_string(r.pattern) + "/" + fmt(r.contrast);
}

void Session::init_staircases() {
  rounds_.clear();
  for (std::size_t r = 0; r < config_.rounds.size(); ++r) {
    std::vector<Staircase> round;
    for (double a : config_.artifact_px) round.push_back({"a" + fmt(a), a, quest::Quest(config_.quest), false, {}, {}});
    rounds_.push_back(std::move(round));
  }
  ended_rounds_.assign(config_.rounds.size(), false);
}

Session Session::create(const StudyConfig& config, const fs::path& dir, const std::string& participant,
                        const nlohmann::json& extra) {
  if (const std::string bad = name_problem(participant); !bad.empty())
    throw std::runtime_error("participant '" + json_input::printable(participant) + "': " + bad);
  fs::create_directories(dir);
  Session s;
  s.lock_ = trial_log::DirectoryLock(dir);
  if (fs::exists(dir / "session.json") || fs::exists(dir / "trials.csv"))
    throw std::runtime_error(dir.string() + ": already holds a session; refusing to overwrite it (use --resume)");
  s.config_ = config;
  s.dir_ = dir;
  s.participant_ = participant;
  std::string stamp = utc_now();
  std::string compact;
  for (char c : stamp.substr(0, 19))
    if (c != '-' && c != ':') compact += c;
  s.session_id_ = participant + "-" + compact;
  s.init_staircases();
  s.session_json_ = {{"session_id", s.session_id_},
                     {"participant", participant},
                     {"created_utc", stamp},
                     {"software", {{"name", "penumbra-study"}, {"version", "0.1.0"}}},
                     {"seed", config.seed},
                     {"config", to_json(config)},
                     {"quest", quest_block(config)},
                     {"display", to_json(config)["display"]},
                     {"log", "trials.csv"},
                     {"ended_rounds", nlohmann::json::array()},
                     {"resumed_utc", nlohmann::json::array()}};
  for (auto it = extra.begin(); it != extra.end(); ++it) s.session_json_[it.key()] = it.value();
  s.write_session_json();
  s.writer_ = std::make_unique<trial_log::Writer>(dir / "trials.csv", true);
  return s;
}

Session Session::resume(const fs::path& dir, const std::function<void(const nlohmann::json&, const StudyConfig&)>& accept) {
  const fs::path json_path = dir / "session.json", log_path = dir / "trials.csv";
  if (!fs::exists(json_path)) throw std::runtime_error(json_path.string() + ": no session to resume");
  Session s;
  s.lock_ = trial_log::DirectoryLock(dir);
  // Nothing is written until session.json, the log and the caller's options all agree: a refused
  // resume leaves every byte as it was. session.json is small and flat; the bounds refuse an edited
  // one that would make resume allocate or write without bound.
  s.session_json_ = json_input::read_file(json_path, {.max_bytes = 1 << 20, .max_depth = 8});
  const SessionRecord record = check_session_json(s.session_json_, json_path.string());
  s.dir_ = dir;
  s.config_ = record.config;
  s.session_id_ = record.session_id;
  s.participant_ = record.participant;
  s.init_staircases();

  const trial_log::ReadResult log = trial_log::read(log_path);
  auto apply_ended = [&](int trials_done) {
    for (const auto& [round, after] : record.ended)
      if (after == trials_done) s.ended_rounds_.at(static_cast<std::size_t>(round)) = true;
  };
  apply_ended(0);
  for (std::size_t i = 0; i < log.rows.size(); ++i) {
    const trial_log::TrialRow& row = log.rows[i];
    const std::string where = log_path.string() + ":" + std::to_string(i + 2) + ": ";
    const auto plan = s.next();
    if (!plan) throw std::runtime_error(where + "a trial after the session had finished");
    auto differs = [&](const char* column, const std::string& expected, const std::string& found) {
      throw std::runtime_error(where + "column '" + column + "': '" + json_input::printable(found) +
                               "' where session.json and the replayed procedure give '" +
                               json_input::printable(expected) + "'");
    };
    if (row.session_id != s.session_id_) differs("session_id", s.session_id_, row.session_id);
    if (row.participant != s.participant_) differs("participant", s.participant_, row.participant);
    if (row.task != s.config_.task) differs("task", s.config_.task, row.task);
    if (row.trial != plan->trial || row.staircase != plan->staircase_name || row.round != plan->round ||
        row.practice != (plan->practice ? 1 : 0) || row.target != plan->target ||
        row.stimulus_seed != plan->stimulus.seed || row.pattern != stimuli::to_string(plan->stimulus.pattern) ||
        row.kernel != stimuli::to_string(plan->stimulus.kernel) || !same(row.contrast, plan->stimulus.lit_linear) ||
        !same(row.artifact_px, plan->stimulus.artifact_px) ||
        !same(row.filter_radius_px, plan->stimulus.filter_radius_px) ||
        !same(row.requested_filter_radius_px, plan->requested_filter_radius_px) ||
        row.clamped != (plan->clamped ? 1 : 0))
      throw std::runtime_error(where + "does not match the replayed procedure (was the config or software changed?)");
    // The display as the rows recorded it: an edited size or distance changes every angle.
    if (!same(row.artifact_arcmin, s.config_.display.arcmin(row.artifact_px)) ||
        !same(row.filter_radius_arcmin, s.config_.display.arcmin(row.filter_radius_px)))
      differs("artifact_arcmin", fmt(s.config_.display.arcmin(row.artifact_px)), fmt(row.artifact_arcmin));
    s.apply(*plan, row.correct == 1);
    // The QUEST block as the rows recorded it: every posterior after the update.
    const quest::Quest& q = s.rounds_[static_cast<std::size_t>(plan->round)][static_cast<std::size_t>(plan->staircase)].quest;
    if (!same(row.quest_mean, q.mean()) || !same(row.quest_sd, q.sd()))
      differs("quest_mean", fmt(q.mean()), fmt(row.quest_mean));
    apply_ended(s.trials_done_);
  }
  if (accept) accept(s.session_json_, s.config_);
  // Only now may the torn last line (the trial on screen when the process died) be cut.
  if (log.torn_tail) fs::resize_file(log_path, log.complete_bytes);
  s.session_json_["resumed_utc"].push_back(utc_now());
  s.write_session_json();
  s.writer_ = std::make_unique<trial_log::Writer>(log_path, false);
  return s;
}

int Session::current_round() const {
  for (std::size_t r = 0; r < rounds_.size(); ++r) {
    if (ended_rounds_[r]) continue;
    for (const auto& sc : rounds_[r])
      if (!sc.done) return static_cast<int>(r);
  }
  return static_cast<int>(rounds_.size());
}

bool Session::break_due() const {
  return config_.break_every_trials > 0 && trials_done_ > 0 && trials_done_ % config_.break_every_trials == 0;
}

std::optional<TrialPlan> Session::next() const {
  TrialPlan p;
  p.trial = trials_done_;
  observers::Random random(observers::derive_seed(config_.seed, static_cast<std::uint64_t>(p.trial)));
  double artifact = 0, x = 0;
  if (practice_done_ < config_.practice_trials) {
    p.practice = true;
    p.round = 0;
    p.staircase = practice_done_ % static_cast<int>(config_.artifact_px.size());
    artifact = config_.artifact_px[static_cast<std::size_t>(p.staircase)];
    x = config_.practice_intensity;
    p.staircase_name = rounds_[0][static_cast<std::size_t>(p.staircase)].name;
    random.bits();  // the staircase draw a main trial makes, so both use the stream alike
  } else {
    p.round = current_round();
    if (p.round >= static_cast<int>(rounds_.size())) return std::nullopt;
    const auto& round = rounds_[static_cast<std::size_t>(p.round)];
    std::vector<int> open;
    for (std::size_t i = 0; i < round.size(); ++i)
      if (!round[i].done) open.push_back(static_cast<int>(i));
    p.staircase = open[random.bits() % open.size()];
    const Staircase& sc = round[static_cast<std::size_t>(p.staircase)];
    p.staircase_name = sc.name;
    artifact = sc.artifact_px;
    x = std::clamp(sc.quest.quantile(), config_.intensity_min, config_.intensity_max);
  }
  const auto& rc = config_.rounds[static_cast<std::size_t>(p.round)];
  p.requested_filter_radius_px = artifact / std::pow(10.0, x);
  const auto shown = stimuli::clamp_filter_radius(p.requested_filter_radius_px, config_.stimulus_size_px);
  p.clamped = shown.clamped;
  p.stimulus.pattern = rc.pattern;
  p.stimulus.artifact_px = artifact;
  p.stimulus.filter_radius_px = shown.filter_radius_px;
  p.stimulus.lit_linear = rc.contrast;
  p.stimulus.kernel = config_.kernel;
  p.stimulus.poisson_taps = config_.poisson_taps;
  p.stimulus.size_px = config_.stimulus_size_px;
  p.stimulus.transfer = config_.display.transfer;
  p.intensity = std::log10(artifact / shown.filter_radius_px);
  const bool first = random.uniform() < 0.5;
  p.target = config_.task == "2afc" ? (first ? "left" : "right") : (first ? "jagged" : "straight");
  p.stimulus.seed = random.bits() >> 12;  // fits a double and a JSON number exactly
  return p;
}

bool Session::correct_response(const TrialPlan& plan, const std::string& response) const {
  if (config_.task == "2afc") {
    if (response != "left" && response != "right") throw std::invalid_argument("2afc response must be left or right");
    return response == plan.target;
  }
  if (response != "yes" && response != "no") throw std::invalid_argument("yesno response must be yes or no");
  return (response == "yes") == (plan.target == "straight");
}

void Session::apply(const TrialPlan& plan, bool correct) {
  ++trials_done_;
  if (plan.practice) {
    ++practice_done_;
    return;
  }
  // yesno: a straight stimulus (catch trial) says nothing about the artifact's visibility; only
  // the jagged ones update QUEST, with "not straight" = detected.
  if (config_.task == "yesno" && plan.target == "straight") return;
  Staircase& sc = rounds_[static_cast<std::size_t>(plan.round)][static_cast<std::size_t>(plan.staircase)];
  sc.quest.update(plan.intensity, correct ? 1 : 0);
  sc.filter_radius_px.push_back(plan.stimulus.filter_radius_px);
  sc.correct.push_back(correct ? 1 : 0);
  const int n = static_cast<int>(sc.quest.trial_count());
  sc.done = n >= config_.max_trials || (n >= config_.min_trials && sc.quest.sd() < config_.sd_below);
}

trial_log::TrialRow Session::make_row(const TrialPlan& plan, const std::string& response, double rt_ms,
                                      bool correct) const {
  const Staircase& sc = rounds_[static_cast<std::size_t>(plan.round)][static_cast<std::size_t>(plan.staircase)];
  trial_log::TrialRow r;
  r.session_id = session_id_;
  r.participant = participant_;
  r.utc_time = utc_now();
  r.round = plan.round;
  r.trial = plan.trial;
  r.staircase = plan.staircase_name;
  r.pattern = stimuli::to_string(plan.stimulus.pattern);
  r.contrast = plan.stimulus.lit_linear;
  r.artifact_px = plan.stimulus.artifact_px;
  r.task = config_.task;
  r.intensity = plan.intensity;
  r.filter_radius_px = plan.stimulus.filter_radius_px;
  r.kernel = stimuli::to_string(plan.stimulus.kernel);
  r.target = plan.target;
  r.response = response;
  r.correct = correct ? 1 : 0;
  r.rt_ms = rt_ms;
  r.quest_mean = sc.quest.mean();
  r.quest_sd = sc.quest.sd();
  r.practice = plan.practice ? 1 : 0;
  r.requested_filter_radius_px = plan.requested_filter_radius_px;
  r.clamped = plan.clamped ? 1 : 0;
  r.artifact_arcmin = config_.display.arcmin(plan.stimulus.artifact_px);
  r.filter_radius_arcmin = config_.display.arcmin(plan.stimulus.filter_radius_px);
  r.stimulus_seed = plan.stimulus.seed;
  return r;
}

trial_log::TrialRow Session::record(const TrialPlan& plan, const std::string& response, double rt_ms) {
  if (plan.trial != trials_done_) throw std::logic_error("Session::record: plan is not for the next trial");
  const bool correct = correct_response(plan, response);
  apply(plan, correct);
  const trial_log::TrialRow row = make_row(plan, response, rt_ms, correct);
  writer_->append(row);
  return row;
}

void Session::end_round() {
  const int r = current_round();
  if (r >= static_cast<int>(rounds_.size())) return;
  ended_rounds_[static_cast<std::size_t>(r)] = true;
  session_json_["ended_rounds"].push_back({{"round", r}, {"after_trial", trials_done_}});
  write_session_json();
}

void Session::write_session_json() const { io::write_text(dir_ / "session.json", session_json_.dump(2) + "\n"); }

}  // namespace penumbra::procedure
