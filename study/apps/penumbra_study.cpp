// penumbra-study: the 2AFC study app (docs/study.md).
//   penumbra-study stimulus --pattern stair --artifact-px 10 --filter-radius-px 20 -o DIR
#include <CLI/CLI.hpp>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "apps/calibrate_display_command.h"
#include "apps/reference_command.h"
#include "io/atomic_file.h"
#include "io/safe_path.h"
#include "io/staged_dir.h"
#include "cli/checks.h"
#include "cli/main.h"
#include "gl/context.h"
#include "io/image_io.h"
#include "json/json_input.h"
#include "observers/image_observer.h"
#include "online/serve_command.h"
#include "observers/psychometric_observer.h"
#include "procedure/session.h"
#include "procedure/session_record.h"
#include "sampling/random.h"
#include "stimuli/frame_patch.h"
#include "stimuli/stimulus.h"
#ifdef PENUMBRA_STUDY_GUI
#include "gui/study_gui.h"
#endif

namespace fs = std::filesystem;
using namespace penumbra;

namespace {

// --config FILE, or the name of a config shipped with the tools ("default", "default-yesno.json"):
// a name that is no existing file and has no directory part is looked up in the data directory's
// studies/ (tool::data_file: <prefix>/share/penumbra/studies installed, data/studies in the source
// tree). Anything else is left as given, so a missing file is refused by its own name.
CLI::Validator shipped_config() {
  return CLI::Validator(
      [](std::string& input) -> std::string {
        std::error_code ec;  // a name too long for a file is no file, here and in studies/
        if (input.empty() || fs::path(input).has_parent_path() || fs::exists(input, ec)) return {};
        fs::path shipped = tool::data_file("studies/" + input);
        if (shipped.extension() != ".json") shipped += ".json";
        if (fs::is_regular_file(shipped, ec)) input = shipped.string();
        return {};
      },
      "", "SHIPPED_CONFIG");
}

// display-check: what the config's display geometry means for the stimuli, before any session. The
// config is read (and so checked: non-square pixels, a viewing distance under 20 cm, a stimulus
// larger than the screen are one error line each) and nothing is written.
int run_display_check(const fs::path& config_file) {
  const procedure::StudyConfig c = procedure::load_config(config_file);
  const procedure::Display& d = c.display;
  const double ppd = d.pixels_per_degree();
  std::printf("display: %d x %d px, %g x %g mm, viewing distance %g mm, transfer %s\n", d.width_px, d.height_px, d.width_mm,
              d.height_mm, d.viewing_distance_mm, stimuli::to_string(d.transfer).c_str());
  if (d.transfer.calibration)
    std::printf("calibration: %s (%s, model %s, gamma %.3f; 0.5 linear = level %d)\n", d.calibration_file.c_str(),
                d.transfer.calibration->method.c_str(), display::to_string(d.transfer.calibration->model).c_str(),
                d.transfer.calibration->gamma, stimuli::encode(0.5, d.transfer));
  std::printf("pixel: %.4f x %.4f mm (aspect %.3f); %.1f px per degree at the centre\n", d.width_mm / d.width_px,
              d.height_mm / d.height_px, (d.height_mm / d.height_px) / (d.width_mm / d.width_px), ppd);
  std::printf("screen: %.1f x %.1f deg\n", 2.0 * std::atan(0.5 * d.width_mm / d.viewing_distance_mm) * 180.0 / M_PI,
              2.0 * std::atan(0.5 * d.height_mm / d.viewing_distance_mm) * 180.0 / M_PI);
  std::printf("stimulus: %d px = %.2f deg%s\n", c.stimulus_size_px, d.arcmin(c.stimulus_size_px) / 60.0,
              c.task == "2afc" ? " (two side by side)" : "");
  std::printf("artifacts:");
  for (double a : c.artifact_px) std::printf(" %g px = %.2f arcmin;", a, d.arcmin(a));
  std::printf("\nlargest filter radius shown: %d px = %.1f arcmin\n", c.stimulus_size_px / 2, d.arcmin(c.stimulus_size_px / 2.0));
  return 0;
}

// prepare-frames: every frame a session of a frame study can show, rendered into the cache (the
// windows only read them; headless sessions render what they lack themselves).
int run_prepare_frames(const fs::path& config_file, const fs::path& cache_dir) {
  const procedure::StudyConfig config = procedure::load_config(config_file);
  if (!config.frames.enabled()) throw cli::UsageError("--config " + config_file.string() + ": not a frame study (no frames block)");
  const fs::path dir = cache_dir.empty() ? stimuli::default_frame_cache() : cache_dir;
  stimuli::FrameCache cache(dir);
  const std::vector<stimuli::FrameRequest> frames = stimuli::session_frames(config);
  for (std::size_t i = 0; i < frames.size(); ++i) {
    cache.frame(frames[i]);
    if (::isatty(STDERR_FILENO)) std::fprintf(stderr, "[%zu/%zu]\r", i + 1, frames.size());
  }
  std::printf("%zu frames of %s: %d rendered, %d in the cache %s already\n", frames.size(), config.name.c_str(), cache.renders(),
              cache.reads(), dir.string().c_str());
  return 0;
}

// The stimulus spec's errors name its fields ("size_px: expected 16..4096"); on the command line
// they name the option to change, and exit 2 (cli::exit_code).
template <class F>
auto as_option(const char* option, F&& f) {
  try {
    return f();
  } catch (const std::invalid_argument& e) {
    throw cli::UsageError(std::string(option) + ": " + e.what());
  }
}
void validate_options(const stimuli::StimulusSpec& spec) {
  static const std::map<std::string, std::string> option_of = {{"artifact_px", "--artifact-px"},
                                                               {"filter_radius_px", "--filter-radius-px"},
                                                               {"contrast", "--contrast"},
                                                               {"size_px", "--size-px"},
                                                               {"poisson_taps", "--taps"}};
  try {
    stimuli::validate(spec);
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    const auto it = option_of.find(what.substr(0, what.find(':')));
    if (it == option_of.end()) throw;
    throw cli::UsageError(it->second + what.substr(what.find(':')));
  }
}

int run_stimulus(const std::string& pattern, const std::string& kernel, const std::string& transfer,
                 const fs::path& display_calibration, stimuli::StimulusSpec spec, const fs::path& out) {
  spec.pattern = as_option("--pattern", [&] { return stimuli::parse_pattern(pattern); });
  spec.kernel = as_option("--kernel", [&] { return stimuli::parse_kernel(kernel); });
  spec.transfer = as_option("--transfer", [&] { return stimuli::parse_transfer(transfer); });
  if (!display_calibration.empty()) spec.transfer = stimuli::Transfer::measured(display::load_calibration(display_calibration));
  // The spec as given first, so a bad size is blamed on the size and not on the radius it clamps.
  validate_options(spec);
  const auto shown = stimuli::clamp_filter_radius(spec.filter_radius_px, spec.size_px);
  const double requested = spec.filter_radius_px;
  spec.filter_radius_px = shown.filter_radius_px;
  // DIR as a whole or not at all (a full disk left a new artifact.png beside an old line.png), and
  // only a new, empty or earlier stimulus directory: every program's output rule.
  io::StagedDirectory staged(out.string(), "stimulus.json");
  gl::HeadlessContext context;
  stimuli::StimulusRenderer renderer;
  const stimuli::StimulusPair pair = renderer.render(spec);
  io::write_png(staged.path() / "artifact.png", pair.artifact);
  io::write_png(staged.path() / "line.png", pair.line);
  nlohmann::json j = stimuli::to_json(spec, pair.geometry);
  if (!spec.technique.empty()) {
    j["technique"] = spec.technique;
    j["settings"] = shadows::to_json(stimuli::stimulus_settings(spec, pair.geometry.map_texels));
  }
  if (spec.transfer.calibration) {
    const nlohmann::json content = display::to_json(*spec.transfer.calibration);
    j["display_calibration"] = {{"file", fs::absolute(display_calibration).lexically_normal().string()},
                                {"fingerprint", display::fingerprint(content)}};
  }
  j["requested_filter_radius_px"] = requested;
  j["filter_radius_clamped"] = shown.clamped;
  j["intensity"] = std::log10(spec.artifact_px / spec.filter_radius_px);
  j["images"] = {{"artifact", "artifact.png"}, {"line", "line.png"}};
  j["renderer"] = context.info().renderer;
  io::write_file_atomic(staged.path() / "stimulus.json", json_input::dump(j, 2) + "\n");
  staged.commit();
  std::cout << "wrote " << (out / "artifact.png").string() << ", line.png, stimulus.json\n";
  return 0;
}

// "name:k=v,k=v" -> {k, v}; a key given twice is refused (the last would silently win).
std::vector<std::pair<std::string, double>> parse_key_values(const std::string& spec, const std::string& where) {
  std::vector<std::pair<std::string, double>> out;
  const std::string body = spec.substr(spec.find(':') == std::string::npos ? spec.size() : spec.find(':') + 1);
  std::size_t pos = 0;
  while (pos < body.size()) {
    const std::size_t comma = body.find(',', pos);
    const std::string kv = body.substr(pos, comma == std::string::npos ? std::string::npos : comma - pos);
    const std::size_t eq = kv.find('=');
    if (eq == std::string::npos) throw std::invalid_argument(where + ": '" + json_input::printable(kv) + "': expected key=value");
    const std::string value = kv.substr(eq + 1);
    std::size_t used = 0;
    double v = NAN;
    try {
      v = std::stod(value, &used);
    } catch (const std::exception&) {
    }
    if (used != value.size() || !std::isfinite(v))
      throw std::invalid_argument(where + ": '" + json_input::printable(kv) + "': expected a finite number");
    for (const auto& [k, _] : out)
      if (k == kv.substr(0, eq)) throw std::invalid_argument(where + ": " + json_input::printable(k) + " given twice");
    out.emplace_back(kv.substr(0, eq), v);
    if (comma == std::string::npos) break;
    pos = comma + 1;
  }
  return out;
}

// Removes "key=value" from "name:k=v,k=v" and returns the value, if the key is there.
std::optional<std::string> take_key(std::string& spec, const std::string& key) {
  const std::size_t colon = spec.find(':');
  if (colon == std::string::npos) return std::nullopt;
  for (std::size_t pos = colon + 1; pos < spec.size();) {
    std::size_t end = spec.find(',', pos);
    if (end == std::string::npos) end = spec.size();
    if (spec.compare(pos, key.size() + 1, key + "=") == 0) {
      std::string value = spec.substr(pos + key.size() + 1, end - pos - key.size() - 1);
      spec.erase(pos == colon + 1 ? pos : pos - 1, end - pos + 1);
      if (spec.back() == ':') spec.pop_back();
      return value;
    }
    pos = end + 1;
  }
  return std::nullopt;
}

// "psychometric:c=3.0,beta=3.5,lapse=0.02" -> the planted model (same for every condition).
observers::PlantedModel parse_psychometric(const std::string& spec, const std::string& where) {
  observers::PlantedModel m;
  m.slope = 3.5;
  for (const auto& [k, v] : parse_key_values(spec, where)) {
    if (k == "c") m.c_true = v;
    else if (k == "beta") m.slope = v;
    else if (k == "lapse") m.lapse = v;
    else if (k == "p_threshold") m.p_threshold = v;
    else throw std::invalid_argument(where + ": unknown parameter '" + json_input::printable(k) + "' (c, beta, lapse, p_threshold)");
  }
  return m;
}

// The simulated observer of a headless run, checked in full before any session is opened or
// created (a rejected --observer leaves nothing behind).
struct ObserverSetup {
  std::string spec;  // as given; recorded in session.json and restored by --resume
  bool image = false;
  bool frame = false;  // the frame observer (a frame study): metrics/frame_observer.h on each trial's patches
  double false_alarm = 0.05;  // yesno: the observer's rate of "jagged" for a straight edge
  observers::PlantedModel model;
  observers::ImageObserverParams image_params;
  metrics::FrameObserverParams frame_params;
};

// A frame study's observers: psychometric:k=..,beta=..,lapse=.. (a planted k*: the psychometric
// observer's threshold at intensity log10(1 / k*)) or frame[:ppd=..,weber=..,blur_arcmin=..].
ObserverSetup parse_frame_observer(const std::string& given, const procedure::StudyConfig& config, const std::string& where) {
  ObserverSetup setup;
  setup.spec = given;
  std::string spec = given;
  if (given.rfind("frame", 0) == 0 && (given.size() == 5 || given[5] == ':')) {
    setup.frame = true;
    auto& p = setup.frame_params;
    p.pixels_per_degree = config.display.pixels_per_degree();
    for (const auto& [k, v] : parse_key_values(spec, where)) {
      if (!(v > 0) && k != "blur_arcmin") throw std::invalid_argument(where + ": " + k + ": expected a number > 0");
      if (k == "ppd") p.pixels_per_degree = v;
      else if (k == "weber") p.weber = v;
      else if (k == "blur_arcmin") p.blur_sigma_arcmin = v;
      else if (k == "patch_deg") p.patch_deg = v;
      else if (k == "window_deg") p.window_deg = v;
      else if (k == "window_max_deg") p.window_max_deg = v;
      else if (k == "contrast_deg") p.contrast_deg = v;
      else if (k == "contrast_floor") p.contrast_floor = v;
      else throw std::invalid_argument(where + ": unknown frame observer parameter '" + json_input::printable(k) +
                                       "' (ppd, weber, blur_arcmin, patch_deg, window_deg, window_max_deg, contrast_deg, contrast_floor)");
    }
    return setup;
  }
  if (given.rfind("psychometric", 0) != 0)
    throw std::invalid_argument(where + " '" + json_input::printable(given) +
                                "': a frame study takes psychometric:k=..,beta=..,lapse=.. or frame[:ppd=..,weber=..]");
  const auto k = take_key(spec, "k");
  if (!k) throw std::invalid_argument(where + ": a frame study plants k (psychometric:k=1.5,...), the multiple of c at threshold");
  for (const auto& [key, v] : parse_key_values(spec, where))
    if (key == "c") throw std::invalid_argument(where + ": c: a frame study plants k, not c");
  setup.model = parse_psychometric(spec, where);
  try {
    setup.model.c_true = std::stod(*k);
  } catch (const std::exception&) {
    setup.model.c_true = -1;
  }
  if (!(setup.model.c_true > 0 && std::isfinite(setup.model.c_true))) throw std::invalid_argument(where + ": k: expected a number > 0");
  if (!(setup.model.lapse >= 0 && setup.model.lapse < 1 - setup.model.guess))
    throw std::invalid_argument(where + ": lapse: expected a rate in [0, 1 - guess)");
  return setup;
}

// `where` names the source in errors: "--observer", or "<session.json>: observer" on a resume.
ObserverSetup parse_observer(const std::string& given, const procedure::StudyConfig& config, const std::string& where = "--observer") {
  if (config.frames.enabled()) return parse_frame_observer(given, config, where);
  ObserverSetup setup;
  setup.spec = given;
  setup.image = given.rfind("image", 0) == 0;
  if (!setup.image && given.rfind("psychometric", 0) != 0)
    throw std::invalid_argument(where + " '" + json_input::printable(given) +
                                "': expected psychometric:c=..,beta=..,lapse=.. or image:noise=..,blur_arcmin=..");
  const bool yesno = config.task == "yesno";
  std::string observer_spec = given;
  if (const auto fa = take_key(observer_spec, "fa")) {
    try {
      setup.false_alarm = std::stod(*fa);
    } catch (const std::exception&) {
      setup.false_alarm = -1;
    }
    if (!(setup.false_alarm > 0 && setup.false_alarm < 0.5))
      throw std::invalid_argument(where + ": fa: expected a rate in (0, 0.5)");
  }
  if (setup.image) {
    auto& p = setup.image_params;
    p.pixels_per_degree = 60.0 / config.display.arcmin(1.0);
    p.false_alarm = setup.false_alarm;
    if (const auto criterion = take_key(observer_spec, "criterion")) {
      if (*criterion != "local" && *criterion != "global")
        throw std::invalid_argument(where + ": criterion: expected local or global");
      p.criterion = *criterion == "local" ? observers::StraightnessCriterion::local : observers::StraightnessCriterion::global;
    }
    for (const auto& [k, v] : parse_key_values(observer_spec, where)) {
      const bool positive = k == "ppd" || k == "weber" || k == "window";
      if (positive ? !(v > 0) : !(v >= 0))
        throw std::invalid_argument(where + ": " + k + ": expected a number " + (positive ? "> 0" : ">= 0"));
      if (k == "noise") p.noise_sd = v;
      else if (k == "blur_arcmin") p.blur_sigma_arcmin = v;
      else if (k == "ppd") p.pixels_per_degree = v;
      else if (k == "weber") p.weber = v;
      else if (k == "window") p.window_r = v;
      else throw std::invalid_argument(where + ": unknown image parameter '" + json_input::printable(k) +
                                       "' (noise, blur_arcmin, ppd, weber, window, fa, criterion=global)");
    }
    return setup;
  }
  observers::PlantedModel& model = setup.model;
  model = parse_psychometric(observer_spec, where);
  if (yesno) {
    // The same detection function F as in 2afc (threshold where F reaches the 2afc criterion F*),
    // with hits = fa + (1 - fa - lapse) F; a straight edge gets "jagged" with probability fa. The
    // p_threshold that gives that F* with the yes/no guess rate fa:
    const double f_star = psychometric::criterion_f(model.p_threshold, model.guess, model.quest_delta);
    model.guess = setup.false_alarm;
    model.p_threshold = setup.false_alarm + (1 - setup.false_alarm) * (1 - model.quest_delta) * f_star;
  }
  if (!(model.lapse >= 0 && model.lapse < 1 - model.guess))
    throw std::invalid_argument(where + ": lapse: expected a rate in [0, 1 - guess)");
  try {
    observers::PsychometricObserver probe({{"any", model}}, 0);
  } catch (const std::invalid_argument& e) {
    std::string what = e.what();
    if (const auto colon = what.rfind("': "); colon != std::string::npos) what = what.substr(colon + 3);
    throw std::invalid_argument(where + ": " + what);
  }
  return setup;
}

struct RunOptions {
  fs::path config, output, resume;
  fs::path display_calibration;  // replaces the config's display transfer (new sessions)
  std::optional<stimuli::Kernel> kernel;  // --kernel: replaces the config's stimulus kernel (new sessions)
  std::string observer = "psychometric:c=3.0,beta=3.5,lapse=0.02";
  std::string participant = "sim";
  fs::path frame_cache;  // a frame study's rendered frames (stimuli/frame_patch.h); empty: the default
  bool headless = false;
  int pace_ms = 0;
  int stop_after = 0;
  std::uint64_t observer_seed = 7;
  std::uint64_t seed = 0;  // --seed: the session's seed instead of the one derived from the participant id
  // Which options the command line gave (a resumed session takes the rest from session.json).
  bool participant_given = false, observer_given = false, observer_seed_given = false, seed_given = false;
  std::function<bool(const std::string&)> gui_given;  // whether the command line gave a window option
#ifdef PENUMBRA_STUDY_GUI
  study_gui::GuiOptions gui;
#endif
};

// --kernel on a config: one line naming the option (exit 2) for a technique without kernels.
void apply_kernel_option(const RunOptions& o, procedure::StudyConfig& config) {
  if (!o.kernel) return;
  try {
    procedure::set_stimulus_kernel(config, *o.kernel);
  } catch (const std::invalid_argument& e) {
    throw cli::UsageError("--kernel " + stimuli::to_string(*o.kernel) + ": " + e.what());
  }
}

// A resume continues the run session.json records: its config (the stimulus kernel too),
// participant, observer and observer seed. An option that says otherwise is refused, not ignored.
void check_resume_options(const RunOptions& o, const procedure::Session& s) {
  const nlohmann::json& session = s.session_json();
  if (!o.config.empty())
    throw std::invalid_argument("--config: not with --resume (the session's config is in its session.json)");
  if (!o.output.empty()) throw std::invalid_argument("-o: not with --resume (the session stays in its directory)");
  if (!o.display_calibration.empty())
    throw std::invalid_argument("--display-calibration: not with --resume (the session's calibration is in its session.json)");
  if (o.kernel) {
    procedure::StudyConfig probe = s.config();
    apply_kernel_option(o, probe);
    if (*o.kernel != s.config().kernel)
      throw cli::UsageError("--kernel " + stimuli::to_string(*o.kernel) + ": the session was run with the " +
                            stimuli::to_string(s.config().kernel) + " kernel (session.json); leave --kernel out to continue it");
  }
  const std::string participant = session.at("participant").get<std::string>();
  if (o.participant_given && o.participant != participant)
    throw std::invalid_argument("--participant '" + json_input::printable(o.participant) + "': the session is '" +
                                json_input::printable(participant) + "' (session.json)");
  if (o.seed_given) {
    const auto& z = session.contains("randomization") ? session["randomization"] : nlohmann::json();
    const std::uint64_t recorded = z.is_object() ? z.at("seed").get<std::uint64_t>() : session.at("seed").get<std::uint64_t>();
    if (o.seed != recorded)
      throw std::invalid_argument("--seed " + std::to_string(o.seed) + ": the session was run with seed " + std::to_string(recorded) +
                                  " (session.json)");
  }
}

// A config's stimulus technique against the renderer's tables, before any directory exists: the
// settings parse and the technique has an artifact-free partner.
void check_stimulus_technique(const procedure::StudyConfig& config, const fs::path& file) {
  if (config.technique.empty()) return;
  stimuli::StimulusSpec spec;
  spec.technique = config.technique;
  spec.technique_settings = config.technique_settings;
  std::string problem;  // "technique: ..." or "<section.key>: ..."
  try {
    problem = stimuli::partner_unavailable(stimuli::stimulus_settings(spec, 15));
  } catch (const std::invalid_argument& e) {
    problem = e.what();
  }
  if (problem.empty()) return;
  throw std::runtime_error(file.string() + ": stimulus." + (problem.rfind("technique: ", 0) == 0 ? "" : "settings.") + problem);
}

// A new session's config, checked in full before any directory exists.
procedure::StudyConfig new_session_config(const RunOptions& o) {
  if (o.config.empty() || o.output.empty()) throw std::invalid_argument("run: --config and -o are required (or --resume DIR)");
  procedure::StudyConfig config = procedure::load_config(o.config);
  if (!o.display_calibration.empty()) procedure::load_display_calibration(config, o.display_calibration);
  apply_kernel_option(o, config);
  check_stimulus_technique(config, o.config);
  return config;
}

// A resumed session (`accept` may refuse it before anything is written) or a new one of `config`
// in o.output; `extra` goes into the new session.json (who answers: observer_kind, observer, ...).
procedure::Session open_session(const RunOptions& o, const std::function<void(const procedure::Session&)>& accept) {
  return procedure::Session::resume(o.resume, [&](const procedure::Session& s) {
    check_resume_options(o, s);
    if (accept) accept(s);
  });
}
procedure::Session create_session(const RunOptions& o, const procedure::StudyConfig& config, nlohmann::json extra) {
  extra["config_file"] = o.config.string();
  return procedure::Session::create(config, o.output, o.participant, extra,
                                    o.seed_given ? std::optional<std::uint64_t>(o.seed) : std::nullopt);
}

// The intake screen's check of a typed id, before anything is written: the command line's rules
// for an id, a name that can be a directory (the session goes to <-o>/<id>), a row of the Latin
// square when the config counterbalances, and no session of that participant in the output folder
// yet (its directory, or another directory whose session.json names the id).
std::string intake_problem(const fs::path& root, const procedure::StudyConfig& config, const std::string& id,
                           std::optional<std::uint64_t> seed) {
  const std::string quoted = "participant '" + json_input::printable(id) + "'";
  if (const std::string bad = procedure::name_problem(id); !bad.empty()) return quoted + ": " + bad;
  if (id.front() == '.' || id.find('/') != std::string::npos || id.find('\\') != std::string::npos)
    return quoted + ": the id names the session directory: expected no / or \\ and no leading dot";
  try {
    procedure::randomize(config, id, seed);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  std::error_code ec;
  const fs::path dir = root / id;
  if (fs::exists(dir, ec)) return quoted + " already has a session directory: " + dir.string() + " (choose another id, or --resume it)";
  for (const auto& entry : fs::directory_iterator(root, ec)) {
    const fs::path json = entry.path() / "session.json";
    if (!fs::is_regular_file(json, ec)) continue;
    try {
      const nlohmann::json j = json_input::read_file(json, {.max_bytes = 1 << 20, .max_depth = 8});
      if (j.is_object() && j.value("participant", std::string()) == id)
        return quoted + " already has a session: " + entry.path().string() + " (choose another id, or --resume it)";
    } catch (const std::exception&) {
      // Not a session.json this check can read; the directory is not this id's, and Session::create refuses any clash.
    }
  }
  return "";
}

// The windows read a frame study's frames and never render them (their GL context is the
// participant's): every frame a session can show must be prepared first, or the session is refused
// before anything is opened or written.
fs::path frame_cache_of(const RunOptions& o) { return o.frame_cache.empty() ? stimuli::default_frame_cache() : o.frame_cache; }
[[maybe_unused]] void check_frames_prepared(const procedure::StudyConfig& config, const RunOptions& o) {
  if (!config.frames.enabled()) return;
  const stimuli::FrameCache cache(frame_cache_of(o), false);
  const std::vector<stimuli::FrameRequest> frames = stimuli::session_frames(config);
  std::size_t missing = 0;
  for (const stimuli::FrameRequest& f : frames) missing += cache.cached(f) ? 0 : 1;
  if (missing > 0)
    throw cli::UsageError("run: " + std::to_string(missing) + " of the " + std::to_string(frames.size()) + " frames of " + config.name +
                          " are not in the frame cache " + cache.dir().string() + "; render them first: penumbra-study prepare-frames --config " +
                          (o.config.empty() ? config.name : o.config.string()) + " --frame-cache " + cache.dir().string());
}

// A participant session in the windows (study/gui); the same Session, so the same log. Without
// --participant (a new session), the intake screen asks for the id and -o is the folder of sessions.
// Consent, when the config has a text for it, is asked before the session is created either way.
int run_participant(RunOptions o) {
#ifdef PENUMBRA_STUDY_GUI
  study_gui::SessionStart start;
  if (!o.resume.empty()) {
    // The session's own presentation options (window, admin panel, refresh rate), unless given
    // again: `--resume DIR` alone shows it as it was shown. Read-only here; the resume checks the rest.
    const fs::path json = o.resume / "session.json";
    if (fs::is_regular_file(json)) {
      const nlohmann::json recorded = json_input::read_file(json, {.max_bytes = 1 << 20, .max_depth = 8});
      if (recorded.is_object() && recorded.contains("presentation_options"))
        study_gui::reuse_presentation_options(o.gui, recorded["presentation_options"], o.gui_given, json.string());
    }
    start.resume = [&](const std::function<void(const procedure::Session&)>& accept) {
      return open_session(o, [&](const procedure::Session& s) {
        // A person may not answer a simulated session's trials (a finished one may be looked at).
        check_frames_prepared(s.config(), o);
        const procedure::ObserverKind kind = procedure::observer_kind(s.session_json(), (s.dir() / "session.json").string());
        if (kind != procedure::ObserverKind::person && s.next())
          throw std::invalid_argument(std::string("--resume: the session was answered by a ") + procedure::describe(kind) +
                                      "; continue it with --headless");
        accept(s);
      });
    };
    start.frame_cache = frame_cache_of(o);
    return study_gui::run_session(start, o.gui);
  }
  start.frame_cache = frame_cache_of(o);
  start.config = new_session_config(o);
  check_frames_prepared(start.config, o);
  start.intake = !o.participant_given;
  if (start.intake) {
    // -o is the folder of sessions: it may hold others, must not be a link, and its own folder must
    // exist (it is made with the first session, so declining consent leaves nothing behind).
    io::refuse_link(o.output, "the folder of sessions is named itself, not through a link");
    std::error_code ec;
    const fs::path above = o.output.lexically_normal().has_parent_path() ? o.output.lexically_normal().parent_path() : fs::path(".");
    if (fs::exists(o.output, ec) ? !fs::is_directory(o.output, ec) : !fs::is_directory(above, ec))
      throw std::invalid_argument("-o " + o.output.string() + ": " +
                                  (fs::exists(o.output, ec) ? "not a folder" : "its folder " + above.string() + " does not exist (create it first)"));
  }
  start.participant = o.participant_given ? o.participant : "";
  const std::optional<std::uint64_t> seed = o.seed_given ? std::optional<std::uint64_t>(o.seed) : std::nullopt;
  if (start.intake)
    start.id_problem = [root = o.output, config = start.config, seed](const std::string& id) { return intake_problem(root, config, id, seed); };
  start.create = [&](const std::string& participant, const nlohmann::json& consent) {
    RunOptions typed = o;
    typed.participant = participant;
    if (start.intake) {
      std::error_code ec;
      fs::create_directory(o.output, ec);  // the folder of sessions, with its first session
      typed.output = o.output / participant;
    }
    nlohmann::json extra = {{"observer_kind", procedure::to_string(procedure::ObserverKind::person)},
                            {"presentation_options", study_gui::presentation_options(o.gui)}};
    if (!consent.is_null()) extra["consent"] = consent;
    return create_session(typed, start.config, extra);
  };
  return study_gui::run_session(start, o.gui);
#else
  (void)o;
  throw std::runtime_error("run: this binary was built without the GUI (PENUMBRA_BUILD_GUI=OFF); only --headless runs");
#endif
}

int run_study(const RunOptions& o) {
  if (!o.headless) return run_participant(o);
  ObserverSetup setup;
  std::uint64_t observer_seed = o.observer_seed;
  std::optional<procedure::Session> opened;
  if (!o.resume.empty()) {
    opened.emplace(open_session(o, [&](const procedure::Session& s) {
      const nlohmann::json& session_json = s.session_json();
      const std::string file = (s.dir() / "session.json").string();
      if (procedure::observer_kind(session_json, file) == procedure::ObserverKind::person)
        throw std::invalid_argument("--headless: the session was answered by a person; resume it without --headless");
      std::string spec = o.observer;
      const std::string recorded = session_json.value("observer", std::string());
      if (!recorded.empty()) {
        if (o.observer_given && o.observer != recorded)
          throw std::invalid_argument("--observer '" + json_input::printable(o.observer) + "': the session was run with '" +
                                      json_input::printable(recorded) + "' (session.json); leave --observer out to continue it");
        spec = recorded;
      }
      if (session_json.contains("observer_seed")) {
        const std::uint64_t seed = session_json["observer_seed"].get<std::uint64_t>();
        if (o.observer_seed_given && o.observer_seed != seed)
          throw std::invalid_argument("--observer-seed " + std::to_string(o.observer_seed) + ": the session was run with " +
                                      std::to_string(seed) + " (session.json)");
        observer_seed = seed;
      }
      setup = parse_observer(spec, s.config(), o.observer_given || recorded.empty() ? "--observer" : file + ": observer");
    }));
  } else {
    const procedure::StudyConfig config = new_session_config(o);
    setup = parse_observer(o.observer, config);
    opened.emplace(create_session(o, config,
                                  {{"observer", o.observer},
                                   {"observer_kind", procedure::to_string(procedure::observer_kind_of_spec(o.observer))},
                                   {"observer_seed", o.observer_seed}}));
  }
  procedure::Session& session = *opened;
  const bool yesno = session.config().task == "yesno";
  const bool image_observer = setup.image;
  const double false_alarm = setup.false_alarm;
  const observers::PlantedModel model = setup.model;
  const observers::ImageObserverParams image_params = setup.image_params;
  const bool frames = session.config().frames.enabled();
  std::unique_ptr<stimuli::FrameCache> frame_cache;  // makes its own GL context at its first render
  if (frames && setup.frame) frame_cache = std::make_unique<stimuli::FrameCache>(frame_cache_of(o));
  std::unique_ptr<gl::HeadlessContext> context;
  std::unique_ptr<stimuli::StimulusRenderer> renderer;
  if (image_observer && !frames) {
    context = std::make_unique<gl::HeadlessContext>();
    renderer = std::make_unique<stimuli::StimulusRenderer>();
  }
  std::map<std::string, observers::PlantedModel> conditions;
  for (std::size_t r = 0; r < session.config().rounds.size(); ++r) conditions[session.condition(static_cast<int>(r))] = model;
  while (const auto plan = session.next()) {
    bool correct = false;
    const std::uint64_t trial_seed = sampling::derive_seed(observer_seed, static_cast<std::uint64_t>(plan->trial));
    if (frames && setup.frame) {
      const stimuli::PatchPair pair = stimuli::patch_pair(*frame_cache, session.config(), *plan);
      correct = sampling::Random(trial_seed).uniform() < stimuli::observe_pair(pair, setup.frame_params).p_detect_max * 0.5 + 0.5;
    } else if (frames) {
      // The planted k* is the psychometric observer's c: at "artifact" 1 and "radius" k its intensity is log10(1 / k).
      observers::PsychometricObserver observer(conditions, trial_seed);
      correct = observer.respond({session.condition(plan->round), 1.0, plan->k}).correct;
    } else if (image_observer) {
      const stimuli::StimulusPair pair = renderer->render(plan->stimulus);
      observers::ImageObserver eye(image_params, trial_seed);
      if (yesno) {
        const bool jagged = plan->target == "jagged";
        correct = eye.judges_jagged(jagged ? pair.artifact : pair.line, plan->stimulus, pair.geometry) == jagged;
      } else {
        const bool left_jagged = plan->target == "left";
        const io::Image8& left = left_jagged ? pair.artifact : pair.line;
        const io::Image8& right = left_jagged ? pair.line : pair.artifact;
        correct = eye.first_is_jagged(left, right, plan->stimulus, pair.geometry) == left_jagged;
      }
    } else if (yesno && plan->target == "straight") {
      correct = !(sampling::Random(trial_seed).uniform() < false_alarm);
    } else {
      observers::PsychometricObserver observer(conditions, trial_seed);
      correct = observer.respond({session.condition(plan->round), plan->stimulus.artifact_px,
                                  plan->stimulus.filter_radius_px}).correct;
    }
    std::string response;
    if (session.config().task == "2afc") response = correct == (plan->target == "left") ? "left" : "right";
    else response = correct == (plan->target == "straight") ? "yes" : "no";
    session.record(*plan, response, 0.0);
    if (o.stop_after > 0 && session.trials_done() >= o.stop_after) break;
    if (o.pace_ms > 0) std::this_thread::sleep_for(std::chrono::milliseconds(o.pace_ms));
  }
  std::cout << "session " << session.session_id() << ": " << session.trials_done() << " trials in "
            << session.dir().string() << "\n";
  std::printf("  seed %llu (from %s), rounds in the order", static_cast<unsigned long long>(session.randomization().seed),
              session.randomization().seed_from.c_str());
  for (const int r : session.randomization().round_order) std::printf(" %s", session.condition(r).c_str());
  std::printf("\n");
  if (frame_cache)
    std::printf("  frames: %d rendered, %d read from the cache %s\n", frame_cache->renders(), frame_cache->reads(),
                frame_cache->dir().string().c_str());
  if (frames && setup.frame) {  // every parameter, defaults included: what the answers came from
    const metrics::FrameObserverParams& p = setup.frame_params;
    std::printf("  frame observer: ppd %g, patch_deg %g, blur_arcmin %g, window_deg %g, window_max_deg %g, contrast_deg %g, "
                "contrast_floor %g, weber %g\n", p.pixels_per_degree, p.patch_deg, p.blur_sigma_arcmin, p.window_deg, p.window_max_deg,
                p.contrast_deg, p.contrast_floor, p.weber);
  }
  for (const int round : session.randomization().round_order) {
    const auto r = static_cast<std::size_t>(round);
    for (const auto& sc : session.rounds()[r]) {
      const double t = sc.quest.mean();
      if (frames) {
        std::printf("  round %d %-10s %-10s trials %3zu  threshold log10(1/k) %+.3f sd %.3f  -> k = %.2f\n", session.round_position(round) + 1,
                    session.condition(static_cast<int>(r)).c_str(), sc.name.c_str(), sc.quest.trial_count(), t, sc.quest.sd(),
                    std::pow(10.0, -t));
        continue;
      }
      std::printf("  round %d %-10s %-4s trials %3zu  threshold log10(a/r) %+.3f sd %.3f  -> r/a = %.2f\n", session.round_position(round) + 1,
                  session.condition(static_cast<int>(r)).c_str(), sc.name.c_str(), sc.quest.trial_count(), t,
                  sc.quest.sd(), std::pow(10.0, -t));
    }
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"penumbra-study: 2AFC shadow-artifact study (docs/study.md)"};
  cli::describe_tool(app, "penumbra-study", "study.md");
  app.require_subcommand(1);

  auto* stim = app.add_subcommand("stimulus", "render one stimulus pair (artifact and line) to PNG + JSON");
  stimuli::StimulusSpec spec;
  std::string pattern = "stair", kernel = "disk", transfer = "srgb";
  fs::path stim_out;
  stim->add_option("--pattern", pattern, "stair or step")->capture_default_str();
  stim->add_option("--artifact-px", spec.artifact_px, "shadow-map texel size on screen (px)")->required();
  stim->add_option("--filter-radius-px", spec.filter_radius_px, "filter radius (px); clamped to [1, size/2]")
      ->required()
      ->check(cli::finite_range(0, 1e6));
  stim->add_option("--contrast", spec.lit_linear, "lit level in linear light (1 = full, 0.5 = half)")->capture_default_str();
  stim->add_option("--kernel", kernel, "without --technique: the renderer's PCF kernel, disk (exact disk), grid (box) or poisson")->capture_default_str();
  stim->add_option("--taps", spec.poisson_taps, "Poisson taps")->capture_default_str();
  stim->add_option("--technique", spec.technique, "the renderer's technique that draws it (penumbra-render's names: pcf, rpcf, vsm, ...; without it, pcf with --kernel)");
  std::vector<std::string> stim_settings;
  stim->add_option("--set", stim_settings, "a technique setting KEY=VALUE by penumbra-render's keys (pcf.kernel=grid); repeatable");
  stim->add_option("--size-px", spec.size_px, "stimulus side (px)")->capture_default_str();
  stim->add_option("--transfer", transfer, "display transfer function: srgb, gamma2.2, linear")->capture_default_str();
  fs::path stim_calibration;
  stim->add_option("--display-calibration", stim_calibration,
                   "the monitor's measured transfer (display-calibration.json from calibrate-display) instead of --transfer")
      ->check(cli::path_given())
      ->excludes("--transfer");
  stim->add_option("--seed", spec.seed, "edge phase and orientation")->capture_default_str()->check(cli::non_negative_integer());
  stim->add_option("-o,--output", stim_out, "output directory")->required()->check(cli::path_given());

  auto* display_check = app.add_subcommand(
      "display-check", "print pixels per degree, the stimulus in degrees and the artifacts in arcmin for a config's display; "
                       "refuses implausible geometry (non-square pixels, viewing distance under 20 cm, stimulus larger than the screen)");
  fs::path display_config;
  std::vector<std::string> shipped;
  std::error_code no_dir;  // none listed
  for (const auto& entry : fs::directory_iterator(tool::data_file("studies"), no_dir))
    if (entry.path().extension() == ".json") shipped.push_back(entry.path().stem().string());
  std::sort(shipped.begin(), shipped.end());
  std::string shipped_configs = "a study config file, or the name of one shipped in " + tool::data_file("studies").string() + ":";
  for (const std::string& name : shipped) shipped_configs += " " + name;
  display_check->add_option("--config", display_config, shipped_configs)->required()->check(cli::path_given())->transform(shipped_config());
  auto* run = app.add_subcommand("run", "run a study session: a participant in the windows, or --headless with a simulated observer");
  RunOptions ro;
  run->add_option("--config", ro.config, shipped_configs)->check(cli::path_given())->transform(shipped_config());
  run->add_option("-o,--output", ro.output,
                  "new session directory (refused if it holds a session); in the windows without --participant, the folder "
                  "the session goes into as <folder>/<participant id>")
      ->check(cli::path_given());
  run->add_option("--resume", ro.resume, "continue the session in this directory")->check(cli::path_given());
  run->add_option("--observer", ro.observer,
                  "headless: the simulated observer, psychometric:c=..,beta=..,lapse=..[,p_threshold=..][,fa=..] (a planted "
                  "psychometric function) or image:noise=..,blur_arcmin=..[,ppd=..,weber=..,window=..,fa=..,criterion=global] "
                  "(the image observer, a model that looks at the stimuli)")
      ->capture_default_str();
  run->add_option("--observer-seed", ro.observer_seed, "seed of the simulated observer")
      ->capture_default_str()
      ->check(cli::non_negative_integer());
  run->add_option("--participant", ro.participant,
                  "participant id; in the windows without it the experimenter types it at the start screen; headless runs "
                  "default to 'sim'");
  run->add_option("--seed", ro.seed,
                  "the session's seed (target sides, staircase draws, edge phases, round order); default: derived from the "
                  "config's seed and the participant id, so each participant gets another sequence and the same one again")
      ->check(cli::non_negative_integer());
  run->add_option("--display-calibration", ro.display_calibration,
                  "the monitor's measured transfer (display-calibration.json from calibrate-display): replaces the config's "
                  "display.transfer / display.calibration for a new session")
      ->check(cli::path_given());
  std::string run_kernel;
  run->add_option("--kernel", run_kernel,
                  "the PCF kernel the stimuli are drawn with, disk, grid or poisson: the one your engine filters with, so "
                  "that the fitted c is its entry; replaces the config's stimulus.kernel (or its pcf.kernel setting) and is "
                  "recorded in session.json's config; refused for a technique without kernels");
  run->add_flag("--headless", ro.headless, "no window: the observer answers");
  run->add_option("--frame-cache", ro.frame_cache,
                  "a frame study's rendered frames, one PNG per settings fingerprint, shared by sessions (default: "
                  "$PENUMBRA_FRAME_CACHE, else $XDG_CACHE_HOME/penumbra/frames or ~/.cache/penumbra/frames)")
      ->check(cli::path_given());
  run->add_option("--pace-ms", ro.pace_ms, "wait after each simulated trial (tests of crash recovery)")
      ->check(CLI::Range(0, 60000));
  run->add_option("--stop-after", ro.stop_after, "headless: stop once the session has this many trials (resumable)")
      ->check(CLI::Range(0, 1000000));
#ifdef PENUMBRA_STUDY_GUI
  study_gui::add_options(*run, ro.gui);
#endif

  auto* prepare = app.add_subcommand("prepare-frames", "render every frame a frame study's sessions can show into the frame cache "
                                                      "(the windows read them; docs/study.md#frames-the-rules-own-frames--frames)");
  fs::path prepare_config, prepare_cache;
  prepare->add_option("--config", prepare_config, "a frame study's config (a file or a shipped name: frames-town, frames-demo)")
      ->required()
      ->check(cli::path_given())
      ->transform(shipped_config());
  prepare->add_option("--frame-cache", prepare_cache,
                      "the frame cache (default: $PENUMBRA_FRAME_CACHE, else $XDG_CACHE_HOME/penumbra/frames or ~/.cache/penumbra/frames)")
      ->check(cli::path_given());

  const study_app::ReferenceCommand reference(app);
  const study_app::CalibrateDisplayCommand calibrate_display(app);
  const study_app::ServeCommand serve(app, shipped_config());

  if (const auto status = cli::parse(app, argc, argv, "penumbra-study")) return *status;
  try {
    if (reference.parsed()) return reference.run();
    if (calibrate_display.parsed()) return calibrate_display.run();
    if (serve.parsed()) return serve.run();
    if (display_check->parsed()) return run_display_check(display_config);
    if (prepare->parsed()) return run_prepare_frames(prepare_config, prepare_cache);
    if (stim->parsed()) {
      stimuli::set_technique_settings(spec, stim_settings);
      return run_stimulus(pattern, kernel, transfer, stim_calibration, spec, stim_out);
    }
    ro.participant_given = run->count("--participant") > 0;
    ro.observer_given = run->count("--observer") > 0;
    ro.observer_seed_given = run->count("--observer-seed") > 0;
    ro.seed_given = run->count("--seed") > 0;
    if (run->count("--kernel") > 0) ro.kernel = as_option("--kernel", [&] { return stimuli::parse_kernel(run_kernel); });
    ro.gui_given = [run](const std::string& name) { return run->count(name) > 0; };
    if (run->parsed()) return run_study(ro);
  } catch (const std::exception& e) {
    return cli::fail("penumbra-study", e);
  }
  return 0;
}
