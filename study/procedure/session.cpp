#include "procedure/session.h"

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <ctime>
#include <stdexcept>

#include "io/atomic_file.h"
#include "io/safe_path.h"
#include "json/json_input.h"
#include "procedure/session_record.h"

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

Session Session::create(const StudyConfig& config, const fs::path& dir, const std::string& participant,
                        const nlohmann::json& extra, std::optional<std::uint64_t> seed) {
  if (const std::string bad = name_problem(participant); !bad.empty())
    throw std::runtime_error("participant '" + json_input::printable(participant) + "': " + bad);
  // Every program's output rule (io::check_output): not a link, in a folder that exists, new or
  // empty. The lock comes before the look inside, so a second process is told the directory is in
  // use, and a session already there is named as one.
  std::error_code ec;
  const bool made = !fs::exists(fs::symlink_status(dir, ec));
  if (made) io::check_output(dir, io::OutputKind::directory);
  else io::refuse_link(dir, "a session directory is named itself, not through a link");
  fs::create_directory(dir, ec);
  if (ec) throw std::runtime_error(dir.string() + ": cannot create the session directory: " + ec.message());
  trial_log::DirectoryLock lock(dir);
  if (fs::exists(fs::symlink_status(dir / "session.json", ec)) || fs::exists(fs::symlink_status(dir / "trials.csv", ec)))
    throw std::runtime_error(dir.string() + ": already holds a session; refusing to overwrite it (use --resume)");
  for (const auto& entry : fs::directory_iterator(dir, ec))
    if (entry.path().filename() != trial_log::DirectoryLock::kFileName)
      throw std::runtime_error(dir.string() + ": exists and is not empty; choose a new session directory");
  // A session that cannot be started (a full disk) leaves nothing behind: not half a session, not
  // a directory that the next try would refuse.
  try {
    return start(config, dir, participant, extra, std::move(lock), seed);
  } catch (...) {
    if (made) {
      fs::remove_all(dir, ec);
    } else {
      for (const char* name : {"trials.csv", "session.json", "session.lock"}) fs::remove(dir / name, ec);
    }
    throw;
  }
}

Session Session::start(const StudyConfig& config, const fs::path& dir, const std::string& participant,
                       const nlohmann::json& extra, trial_log::DirectoryLock lock, std::optional<std::uint64_t> seed) {
  const Randomization randomization = randomize(config, participant, seed);
  Session s(config, randomization);
  s.lock_ = std::move(lock);
  s.dir_ = dir;
  s.participant_ = participant;
  std::string stamp = utc_now();
  std::string compact;
  for (char c : stamp.substr(0, 19))
    if (c != '-' && c != ':') compact += c;
  s.session_id_ = participant + "-" + compact;
  s.session_json_ = {{"session_id", s.session_id_},
                     {"participant", participant},
                     {"created_utc", stamp},
                     {"software", {{"name", "penumbra-study"}, {"version", "0.1.0"}}},
                     {"seed", config.seed},
                     {"randomization", {{"seed", randomization.seed},
                                        {"seed_from", randomization.seed_from},
                                        {"round_order", randomization.round_order}}},
                     {"config", to_json(config)},
                     {"quest", quest_block(config)},
                     {"display", to_json(config)["display"]},
                     {"log", "trials.csv"},
                     {"ended_rounds", nlohmann::json::array()},
                     {"resumed_utc", nlohmann::json::array()}};
  if (const auto block = display_calibration_block(config)) s.session_json_["display_calibration"] = *block;
  for (auto it = extra.begin(); it != extra.end(); ++it) s.session_json_[it.key()] = it.value();
  s.write_session_json();
  s.writer_ = std::make_unique<trial_log::Writer>(dir / "trials.csv", true,
                                                  config.frames.enabled() ? trial_log::Layout::frames : trial_log::Layout::current);
  return s;
}

Session Session::resume(const fs::path& dir, const std::function<void(const Session&)>& accept) {
  const fs::path json_path = dir / "session.json", log_path = dir / "trials.csv";
  std::error_code ec;
  if (!fs::exists(fs::symlink_status(json_path, ec))) throw std::runtime_error(json_path.string() + ": no session to resume");
  trial_log::DirectoryLock lock(dir);
  // Nothing is written until session.json, the log and the caller's options all agree: a refused
  // resume leaves every byte as it was (and no lock file). session.json is small and flat; the
  // bounds refuse an edited one that would make resume allocate or write without bound. No file of
  // the directory is reached through a link.
  constexpr json_input::Limits limits{.max_bytes = 1 << 20, .max_depth = 8};
  nlohmann::json json = json_input::parse(io::read_file(json_path, limits.max_bytes, io::Links::refuse), json_path.string(), limits);
  const SessionRecord record = check_session_json(json, json_path.string());
  const trial_log::ReadResult log = trial_log::read(log_path);
  Session s(record.config, record.randomization);
  s.lock_ = std::move(lock);
  s.session_json_ = std::move(json);
  s.dir_ = dir;
  s.session_id_ = record.session_id;
  s.participant_ = record.participant;
  s.procedure_ = replay_log(record, log.rows, log_path.string());
  if (accept) accept(s);
  check_display_calibration_file(record.config, json_path.string());
  // Only now may the torn last line (the trial on screen when the process died) be cut.
  s.writer_ = std::make_unique<trial_log::Writer>(log_path, false);
  if (log.torn_tail) s.writer_->cut_to(log.complete_bytes);
  s.session_json_["resumed_utc"].push_back(utc_now());
  s.write_session_json();
  return s;
}

trial_log::TrialRow Session::make_row(const TrialPlan& plan, const std::string& response, double rt_ms,
                                      bool correct) const {
  const Staircase& sc = procedure_.staircase(plan);
  trial_log::TrialRow r;
  r.session_id = session_id_;
  r.participant = participant_;
  r.utc_time = utc_now();
  r.condition_index = plan.round;
  r.round_position = procedure_.round_position(plan.round) + 1;
  r.trial = plan.trial;
  r.staircase = plan.staircase_name;
  r.task = config().task;
  r.intensity = plan.intensity;
  r.target = plan.target;
  r.response = response;
  r.correct = correct ? 1 : 0;
  r.rt_ms = std::round(rt_ms * 1000.0) / 1000.0;  // as the log writes it: to the microsecond
  r.quest_mean = sc.quest.mean();
  r.quest_sd = sc.quest.sd();
  r.practice = plan.practice ? 1 : 0;
  r.clamped = plan.clamped ? 1 : 0;
  r.stimulus_seed = plan.stimulus.seed;
  if (config().frames.enabled()) {
    const FramesConfig& f = config().frames;
    r.technique = plan.stimulus.technique;
    r.scene = f.scene;
    r.path_frame = f.patches.at(static_cast<std::size_t>(plan.staircase)).path_frame;
    r.k = plan.k;
    r.requested_k = plan.requested_k;
    return r;
  }
  r.pattern = stimuli::to_string(plan.stimulus.pattern);
  r.contrast = plan.stimulus.lit_linear;
  r.artifact_px = plan.stimulus.artifact_px;
  r.filter_radius_px = plan.stimulus.filter_radius_px;
  r.kernel = stimuli::to_string(plan.stimulus.kernel);
  r.requested_filter_radius_px = plan.requested_filter_radius_px;
  r.artifact_arcmin = config().display.arcmin(plan.stimulus.artifact_px);
  r.filter_radius_arcmin = config().display.arcmin(plan.stimulus.filter_radius_px);
  return r;
}

trial_log::TrialRow Session::record(const TrialPlan& plan, const std::string& response, double rt_ms,
                                    const std::optional<trial_log::FrameTiming>& timing) {
  if (plan.trial != trials_done()) throw std::logic_error("Session::record: plan is not for the next trial");
  const bool correct = correct_response(plan, response);
  procedure_.apply(plan, correct);
  trial_log::TrialRow row = make_row(plan, response, rt_ms, correct);
  row.timing = timing;
  writer_->append(row);
  return row;
}

void Session::end_round() {
  const int r = current_round();
  if (r >= static_cast<int>(rounds().size())) return;
  procedure_.end_round(r);
  session_json_["ended_rounds"].push_back({{"round", r}, {"after_trial", trials_done()}});
  write_session_json();
}

void Session::record_presentation(const nlohmann::json& presentation) {
  nlohmann::json entry = presentation;
  entry["utc"] = utc_now();
  if (!session_json_.contains("presentation") || !session_json_["presentation"].is_array())
    session_json_["presentation"] = nlohmann::json::array();
  session_json_["presentation"].push_back(entry);
  write_session_json();
}

void Session::write_session_json() const {
  io::write_file_atomic(dir_ / "session.json", json_input::dump(session_json_, 2) + "\n");
}

}  // namespace penumbra::procedure
