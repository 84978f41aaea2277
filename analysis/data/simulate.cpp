#include "data/simulate.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <stdexcept>

#include "data/dataset.h"
#include "sampling/random.h"

namespace penumbra::analysis {

namespace fs = std::filesystem;

namespace {

// A standard normal draw (Box–Muller) from the platform-independent uniforms.
double normal(sampling::Random& random) {
  const double u1 = 1.0 - random.uniform(), u2 = random.uniform();
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * 3.141592653589793 * u2);
}

std::string session_id_of(const std::string& participant) { return participant + "-sim"; }

}  // namespace

std::vector<SimulatedSession> simulate_study(const SimulatedStudy& study) {
  if (study.participants < 1) throw std::invalid_argument("simulate: at least one participant");
  if (study.artifact_px.empty()) throw std::invalid_argument("simulate: at least one artifact size");
  for (double a : study.artifact_px)
    if (!(a > 0)) throw std::invalid_argument("simulate: artifact sizes must be positive");
  if (study.trials_per_staircase < 1) throw std::invalid_argument("simulate: at least one trial per staircase");
  if (study.conditions.empty()) throw std::invalid_argument("simulate: at least one condition");
  quest::Quest validate(study.quest);
  std::vector<SimulatedSession> sessions;
  for (int p = 0; p < study.participants; ++p) {
    sampling::Random random(sampling::derive_seed(study.seed, static_cast<std::uint64_t>(p)));
    SimulatedSession session;
    char name[32];
    std::snprintf(name, sizeof name, "p%02d", p + 1);
    session.participant = name;
    const double spread = std::pow(10.0, normal(random) * study.participant_sd_log10);
    std::map<std::string, observers::PlantedModel> planted;
    for (const SimulatedCondition& c : study.conditions) {
      observers::PlantedModel m = c.planted;
      m.c_true *= spread;
      planted[condition_name(c.pattern, c.contrast)] = m;
    }
    session.c_planted = planted.at(condition_name(study.conditions[0].pattern, study.conditions[0].contrast)).c_true;
    observers::PsychometricObserver observer(planted, random.bits());
    int trial = 0;
    for (std::size_t round = 0; round < study.conditions.size(); ++round) {
      const SimulatedCondition& condition = study.conditions[round];
      const std::string name_of_condition = condition_name(condition.pattern, condition.contrast);
      std::vector<quest::Quest> staircases(study.artifact_px.size(), quest::Quest(study.quest));
      std::vector<int> open(study.artifact_px.size());
      for (std::size_t i = 0; i < open.size(); ++i) open[i] = static_cast<int>(i);
      while (!open.empty()) {
        const std::size_t pick = random.bits() % open.size();
        const int s = open[pick];
        quest::Quest& q = staircases[static_cast<std::size_t>(s)];
        const double a = study.artifact_px[static_cast<std::size_t>(s)];
        const double x = std::clamp(q.quantile(), study.intensity_min, study.intensity_max);
        const double requested = a / std::pow(10.0, x);
        const double shown = std::clamp(requested, 1.0, 0.5 * study.stimulus_size_px);
        const double intensity = std::log10(a / shown);
        const bool correct = observer.respond({name_of_condition, a, shown}).correct;
        q.update(intensity, correct ? 1 : 0);
        trial_log::TrialRow r;
        r.session_id = session_id_of(session.participant);
        r.participant = session.participant;
        r.utc_time = "2024-01-01T00:00:00.000Z";
        r.condition_index = static_cast<int>(round);
        r.round_position = static_cast<int>(round) + 1;  // the simulated study runs its conditions in order
        r.trial = trial++;
        r.staircase = "a" + format_number(a);
        r.pattern = condition.pattern;
        r.contrast = condition.contrast;
        r.artifact_px = a;
        r.task = "2afc";
        r.intensity = intensity;
        r.filter_radius_px = shown;
        r.kernel = "disk";
        const bool left = random.uniform() < 0.5;
        r.target = left ? "left" : "right";
        r.response = correct == left ? "left" : "right";
        r.correct = correct ? 1 : 0;
        r.rt_ms = 0;
        r.quest_mean = q.mean();
        r.quest_sd = q.sd();
        r.practice = 0;
        r.requested_filter_radius_px = requested;
        r.clamped = shown != requested ? 1 : 0;
        r.stimulus_seed = random.bits() >> 12;
        session.rows.push_back(r);
        if (static_cast<int>(q.trial_count()) >= study.trials_per_staircase) open.erase(open.begin() + pick);
      }
    }
    sessions.push_back(std::move(session));
  }
  return sessions;
}

Dataset as_dataset(const SimulatedStudy& study, const std::vector<SimulatedSession>& sessions) {
  Dataset data;
  const quest::Quest q(study.quest);
  for (const SimulatedSession& s : sessions) {
    SessionInfo info;
    info.session_id = session_id_of(s.participant);
    info.participant = s.participant;
    info.log_file = s.participant + "/trials.csv";
    info.quest = q.params();
    info.quest_dim = q.dim();
    info.observer = "psychometric:c=" + format_number(s.c_planted);
    info.observer_kind = "psychometric-simulation";
    const std::size_t index = data.sessions.size();
    data.sessions.push_back(info);
    int line = 1;
    for (const trial_log::TrialRow& r : s.rows) data.trials.push_back({r, index, ++line});
  }
  return data;
}

std::vector<fs::path> write_sessions(const SimulatedStudy& study, const std::vector<SimulatedSession>& sessions,
                                     const fs::path& dir) {
  std::vector<fs::path> dirs;
  const quest::Quest q(study.quest);
  for (const SimulatedSession& s : sessions) {
    const fs::path d = dir / s.participant;
    fs::create_directories(d);
    const nlohmann::json session = {
        {"session_id", session_id_of(s.participant)},
        {"participant", s.participant},
        {"software", {{"name", "penumbra-fit simulate"}, {"version", "0.1.0"}}},
        {"planted_c", s.c_planted},
        {"observer", "psychometric:c=" + format_number(s.c_planted)},
        {"observer_kind", "psychometric-simulation"},
        {"quest", {{"t_guess", q.params().t_guess}, {"t_guess_sd", q.params().t_guess_sd},
                   {"p_threshold", q.params().p_threshold}, {"beta", q.params().beta}, {"delta", q.params().delta},
                   {"gamma", q.params().gamma}, {"grain", q.params().grain}, {"dim", q.dim()},
                   {"intensity", "log10(artifact_px / filter_radius_px)"}}},
        {"log", "trials.csv"}};
    std::ofstream(d / "session.json") << session.dump(2) << "\n";
    std::ofstream log(d / "trials.csv", std::ios::trunc);
    log << trial_log::header_line();
    for (const trial_log::TrialRow& r : s.rows) log << trial_log::format_row(r);
    if (!log) throw std::runtime_error((d / "trials.csv").string() + ": cannot write");
    dirs.push_back(d);
  }
  return dirs;
}

}  // namespace penumbra::analysis
