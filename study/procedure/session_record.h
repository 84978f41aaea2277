#pragma once
// A session directory as a record to be trusted only after checking: session.json (fields, sizes,
// agreement with its config block) and every trial-log row against the replayed procedure. Used by
// penumbra-study's --resume before it writes anything and by penumbra-fit before it fits. No GL.
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "log/trial_log.h"
#include "procedure/config.h"
#include "procedure/procedure.h"

namespace penumbra::procedure {

// Participant and session names go into every row of the log: no separators, no control bytes,
// and short (a megabyte participant string made each row a megabyte).
constexpr std::size_t kMaxName = 200;
// Empty when `name` is fine, else what was expected.
std::string name_problem(const std::string& name);

// The QUEST block session.json records beside the config (read by the fitter).
nlohmann::json quest_block(const StudyConfig& config);

// session.json's "display_calibration" for a config whose display transfer is measured: the
// file, its fingerprint and its content (so the session says exactly how it encoded its stimuli);
// nothing for an assumed transfer. Throws std::logic_error for a measured transfer not loaded.
std::optional<nlohmann::json> display_calibration_block(const StudyConfig& config);
// Resume: the calibration file the session names must still hold what the session recorded (a
// monitor recalibrated since would make the continued trials differ from the first ones).
// Throws std::runtime_error "<session.json>: display_calibration: ..." otherwise.
void check_display_calibration_file(const StudyConfig& recorded, const std::string& session_file);

// Who answered a session's trials: a closed set, session.json's "observer_kind". People and
// simulated observers are never pooled into one c without saying so (penumbra-fit).
enum class ObserverKind {
  person,        // a participant in the windows
  psychometric,  // a simulated observer with a planted psychometric function (--observer psychometric:...)
  image,         // the image observer, a model that looks at the stimuli (--observer image:...)
};
// "person", "psychometric-simulation", "image-observer": the values session.json holds.
const char* to_string(ObserverKind kind);
// In words for a line of output: "people", "psychometric simulation", "image observer".
const char* describe(ObserverKind kind, int count = 2);
// The kind of a headless run's --observer spec ("psychometric:...", "image:...").
ObserverKind observer_kind_of_spec(const std::string& spec);
// session.json's kind: "observer_kind" (anything outside the set is refused), or for sessions
// written before it, their "observer": absent or "participant" (the windows), "psychometric:...",
// "image:...". Throws std::runtime_error "<file>: observer_kind: ..." (or "observer: ...").
ObserverKind observer_kind(const nlohmann::json& session_json, const std::string& file);

struct SessionRecord {
  StudyConfig config;
  std::string session_id, participant;
  std::vector<std::pair<int, int>> ended;  // (round, after_trial): rounds the experimenter ended
  Randomization randomization;             // session.json's, or the config's for older sessions
  ObserverKind observer_kind = ObserverKind::person;
};

// session.json as written by Session::create. Throws std::runtime_error "<file>: <field>: <what>".
SessionRecord check_session_json(const nlohmann::json& j, const std::string& file);

// A row that the replayed procedure contradicts (or that follows the end of the session).
class LogMismatch : public std::runtime_error {
 public:
  LogMismatch(const std::string& what, int line_number, int logged_trial)
      : std::runtime_error(what), line(line_number), trial(logged_trial) {}
  int line;   // in the log (header = 1)
  int trial;  // as logged
};

// Feeds `rows` (the log `file`, in order) through the procedure of `record`, checking each row's
// identity, design, stimulus, target, display angles and QUEST posterior against the replay. Throws
// LogMismatch "<file>:<line>: column '<name>': '<found>' where session.json and the replayed
// procedure give '<expected>'" at the first row that differs; returns the replayed procedure.
Procedure replay_log(const SessionRecord& record, const std::vector<trial_log::TrialRow>& rows, const std::string& file);

}  // namespace penumbra::procedure
