#include "procedure/session.h"

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <ctime>
#include <fstream>
#include <stdexcept>

#include "io/image_io.h"
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
  if (participant.empty() || participant.find_first_of(",\"\n\r") != std::string::npos)
    throw std::runtime_error("participant '" + participant + "': expected a non-empty name without , \" or newlines");
  if (fs::exists(dir / "session.json") || fs::exists(dir / "trials.csv"))
    throw std::runtime_error(dir.string() + ": already holds a session; refusing to overwrite it (use --resume)");
  fs::create_directories(dir);
  Session s;
  s.config_ = config;
  s.dir_ = dir;
  s.participant_ = participant;
  std::string stamp = utc_now();
  std::string compact;
  for (char c : stamp.substr(0, 19))
    if (c != '-' && c != ':') compact += c;
  s.session_id_ = participant + "-" + compact;
  s.init_staircases();
  quest::Quest q(config.quest);
  s.session_json_ = {{"session_id", s.session_id_},
                     {"participant", participant},
                     {"created_utc", stamp},
                     {"software", {{"name", "penumbra-study"}, {"version", "0.1.0"}}},
                     {"seed", config.seed},
                     {"config", to_json(config)},
                     {"quest", {{"t_guess", q.params().t_guess}, {"t_guess_sd", q.params().t_guess_sd},
                                {"p_threshold", q.params().p_threshold}, {"beta", q.params().beta},
                                {"delta", q.params().delta}, {"gamma", q.params().gamma},
                                {"grain", q.params().grain}, {"dim", q.dim()},
                                {"intensity", "log10(artifact_px / filter_radius_px)"}}},
                     {"display", to_json(config)["display"]},
                     {"log", "trials.csv"},
                     {"ended_rounds", nlohmann::json::array()},
                     {"resumed_utc", nlohmann::json::array()}};
  for (auto it = extra.begin(); it != extra.end(); ++it) s.session_json_[it.key()] = it.value();
  s.write_session_json();
  s.writer_ = std::make_unique<trial_log::Writer>(dir / "trials.csv", true);
  return s;
}

Session Session::resume(const fs::path& dir) {
  const fs::path json_path = dir / "session.json", log_path = dir / "trials.csv";
  if (!fs::exists(json_path)) throw std::runtime_error(json_path.string() + ": no session to resume");
  Session s;
  {
    std::ifstream in(json_path);
    try {
      s.session_json_ = nlohmann::json::parse(in);
    } catch (const std::exception& e) {
      throw std::runtime_error(json_path.string() + ": not valid JSON: " + e.what());
    }
  }
  s.dir_ = dir;
  s.config_ = parse_config(s.session_json_.at("config"), json_path.string() + " (config)");
  s.session_id_ = s.session_json_.at("session_id").get<std::string>();
  s.participant_ = s.session_json_.at("participant").get<std::string>();
  s.init_staircases();
  std::vector<int> ended;
  for (const auto& e : s.session_json_.value("ended_rounds", nlohmann::json::array()))
    ended.push_back(e.at("after_trial").get<int>());
  std::vector<int> ended_round;
  for (const auto& e : s.session_json_.value("ended_rounds", nlohmann::json::array()))
    ended_round.push_back(e.at("round").get<int>());

  trial_log::ReadResult log = trial_log::read(log_path);
  if (log.torn_tail) fs::resize_file(log_path, log.complete_bytes);
  auto apply_ended = [&](int trials_done) {
    for (std::size_t k = 0; k < ended.size(); ++k)
      if (ended[k] == trials_done) s.ended_rounds_.at(static_cast<std::size_t>(ended_round[k])) = true;
  };
  apply_ended(0);
  for (std::size_t i = 0; i < log.rows.size(); ++i) {
    const trial_log::TrialRow& row = log.rows[i];
    const std::string where = log_path.string() + ":" + std::to_string(i + 2) + ": ";
    const auto plan = s.next();
    if (!plan) throw std::runtime_error(where + "a trial after the session had finished");
    if (row.session_id != s.session_id_) throw std::runtime_error(where + "session_id differs from session.json");
    if (row.trial != plan->trial || row.staircase != plan->staircase_name || row.round != plan->round ||
        row.practice != (plan->practice ? 1 : 0) || row.target != plan->target ||
        row.stimulus_seed != plan->stimulus.seed ||
        std::abs(row.filter_radius_px - plan->stimulus.filter_radius_px) > 1e-9 * plan->stimulus.filter_radius_px)
      throw std::runtime_error(where + "does not match the replayed procedure (was the config or software changed?)");
    s.apply(*plan, row.correct == 1);
    apply_ended(s.trials_done_);
  }
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
