#pragma once
// A study configuration (data/studies/*.json). Every field is checked on load; errors name the
// file and the field path, e.g. "default.json: stopping.min_trials: expected an integer >= 1".
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "quest/quest.h"
#include "stimuli/stimulus_spec.h"

namespace penumbra::procedure {

struct RoundConfig {
  stimuli::Pattern pattern = stimuli::Pattern::stair;
  double contrast = 1.0;  // lit level in linear light
  // A frame study's round: the renderer's technique whose frames it shows (penumbra-render's
  // names: pcf, pcss, ...); empty in the edge study.
  std::string technique;
};

// A frame study (config "frames", docs/study.md#frames-the-rules-own-frames): patches of frames
// the renderer draws, by the rule with its constant c scaled by k, against the same patch of a
// reference frame. One QUEST per patch within a round (a technique); the intensity is
// log10(1 / k), so detectability rises as k falls, as QUEST assumes, and a threshold u means
// k* = 10^-u, the way u means c in the edge study. QUEST's suggestion is rounded to a grid of k
// (k_grid): each frame is rendered once per grid value and cached (stimuli/frame_patch.h).
// A frame study's practice: k = 1/4, a map a quarter of the rule's size per side (log10 4).
inline constexpr double kFramePracticeIntensity = 0.6020599913279624;
struct FramePatch {
  std::string name;     // the staircase's name ("street")
  int path_frame = -1;  // frame of the scene's camera path; -1: the scene's own camera
  int x_px = 0, y_px = 0;  // the patch's top-left corner in the frame (top row first)
};
struct FramesConfig {
  std::string scene;  // built-in scene name or scene file (penumbra-render --scene); empty: not a frame study
  int width_px = 960, height_px = 540;  // the frame
  double c = 3.47;                      // the rule's constant that k scales (adaptive.c = k c)
  // Renderer settings every frame shares ("section.key": value, penumbra-render's keys), e.g. the
  // filter radius in world units; the map's size, cascades and the adaptive rule are the study's.
  std::vector<std::pair<std::string, std::string>> settings;
  int reference_cascades = 4;        // the reference: this many cascades ...
  int reference_texels = 8188;       // ... of this many texels, the rule off;
  double reference_k = 0;            // or, when > 0, the rule itself at this k (its converged frame)
  double k_min = 0.125, k_max = 8;   // the grid of k: powers of 2^(1 / k_steps_per_octave) in [k_min, k_max]
  int k_steps_per_octave = 4;
  int warmup_frames = 2;             // frames rendered before the one kept (PCSS's rule reads the frame before)
  std::vector<FramePatch> patches;
  bool enabled() const { return !scene.empty(); }
  // The k shown for a requested one: the grid value nearest in log k, within [k_min, k_max].
  double round_k(double k) const;
};

// Plausible display geometry, checked when a config is read: square pixels within 5 %, the eyes at
// least 20 cm from the screen.
inline constexpr double kPixelAspectTolerance = 0.05;
inline constexpr double kMinViewingDistanceMm = 200;

struct Display {
  int width_px = 1920, height_px = 1080;
  double width_mm = 527, height_mm = 296;
  double viewing_distance_mm = 600;
  // The transfer the stimuli are encoded through: an assumed one, or "measured" with
  // `calibration_file` (display.calibration: a display-calibration.json, absolute once loaded by
  // load_config) whose content load_display_calibration puts into transfer.calibration.
  stimuli::Transfer transfer = stimuli::Transfer::srgb;
  std::string calibration_file;
  int monitor = 0;  // participant view's monitor (GLFW index)
  // Visual angle of `px` pixels at the screen centre, in arcminutes.
  double arcmin(double px) const;
  // Pixels per degree of visual angle at the screen centre (one degree around the centre).
  double pixels_per_degree() const;
};

// Practice trials (docs/study.md): `trials` easy trials at `intensity` (log10(a / r)) before the
// first round only (every_round false: configs written before issue 16, whose flat
// practice_trials / practice_intensity fields still load so) or before every round, showing that
// round's pattern and contrast. `feedback` shows "Correct" / "Wrong" for `feedback_ms` after a
// practice answer, never after a test trial. Practice never updates a staircase.
struct Practice {
  int trials = 4;
  double intensity = 0.3;  // an easy trial: r = a / 2
  bool every_round = false;
  bool feedback = false;
  double feedback_ms = 800;
};

// The participant's texts (config "texts"), so a lab can translate them. One table: key, default
// for 2afc, default for yesno (null: as 2afc), what it is. Keys not in the config take the default.
struct TextEntry {
  const char* key;
  const char* default_2afc;
  const char* default_yesno;
  const char* help;
};
const std::vector<TextEntry>& text_table();

// The characters the participant's window can draw: its font (DejaVu Sans) is loaded with these
// ranges, first to last inclusive (Latin with Extended-A/B, Greek, Cyrillic, quotes, dashes, the
// bullet, the ellipsis, the arrows, the minus sign). A text with any other character is refused when
// the config is read, naming the field and the character: the window showed "?" for it.
const std::vector<std::pair<char32_t, char32_t>>& drawable_ranges();
bool drawable(char32_t code_point);
// Why `value` cannot be texts.<key> ("" if it can): a character the window cannot draw (named as
// U+XXXX), a control character other than a newline (C0 and C1), or a placeholder the text does not
// fill (only texts.round fills {round} and {rounds}).
std::string text_problem(const std::string& key, const std::string& value);
inline constexpr std::size_t kMaxTextBytes = 4000;

struct StudyConfig {
  std::string name;
  std::string task = "2afc";                 // 2afc | yesno
  // yesno only: what QUEST is fed. "jagged_only" (default): the jagged trials as detections
  // ("not straight" = seen), guess rate = the false-alarm rate (gamma 0.05, p_threshold 0.658 by
  // default). "balanced": every trial, jagged and straight, scored correct or not, so P(correct)
  // = 0.5 + 0.5 (1 - fa) F: a 2AFC-like guess rate of 0.5 (gamma 0.5, p_threshold 0.82 by
  // default), one reading of the published design (docs/study.md).
  std::string yesno_scoring = "jagged_only";
  std::vector<double> artifact_px = {5, 10, 20};
  std::vector<RoundConfig> rounds;
  quest::QuestParams quest;                  // t_guess, t_guess_sd in intensity units
  double intensity_min = -2.0, intensity_max = 1.0;  // QUEST's suggestion is clamped to these
  // quest.tail_p_threshold: a second QUEST per condition and artifact size aimed at this lower
  // P(correct) (a low detection probability F), interleaved with the first under the same stopping
  // rule, so that the psychometric function's tail is measured rather than extrapolated from the
  // criterion (docs/study-config.md). 0: none, the staircases of configs before issue 48.
  double tail_p_threshold = 0;
  int min_trials = 10, max_trials = 40;
  double sd_below = 0.1;                     // converged when the posterior sd drops below this
  Practice practice;
  int break_every_trials = 40;               // 0: no breaks
  std::uint64_t seed = 1;                    // with the participant id, each session's seed (randomization.h)
  // The order of the rounds per session: "shuffled" (per participant, from the session seed: order
  // effects average out over participants), "fixed" (the config's order for everyone) or
  // "latin-square" (counterbalanced: participant k runs row k of a balanced Latin square).
  std::string round_order = "shuffled";
  stimuli::Kernel kernel = stimuli::Kernel::disk;
  int poisson_taps = 32;
  int stimulus_size_px = 320;
  // stimulus.technique / stimulus.settings: the renderer's technique that draws the stimuli and
  // its settings by penumbra-render's keys ({"pcf.kernel": "grid"}); empty: the renderer's PCF
  // with `kernel` (stimuli::as_renderer_pcf). The log's kernel column: pcf.kernel for pcf, else grid (RPCF's box and
  // the box blur of the filtered-moments techniques).
  std::string technique;
  std::vector<std::pair<std::string, std::string>> technique_settings;
  Display display;
  FramesConfig frames;  // frames.enabled(): a frame study (stimulus.size_px is the patch's side)
  std::vector<std::pair<std::string, std::string>> texts;  // as given (text_table keys); the rest default
  // "readings": the choices a design's source does not state, as declared by the config
  // ({"kernel": "disk: the thesis does not name it", ...}); documentation carried into
  // session.json, never used to run.
  std::vector<std::pair<std::string, std::string>> readings;
  // The text for `key` (a text_table key): the config's, else the task's default. "round" has
  // {round} and {rounds} replaced when `round` > 0.
  std::string text(const std::string& key, int round = 0, int round_count = 0) const;
};

// Throws std::runtime_error "<file>: <field>: <what>". parse_config reads display.calibration as
// a path and loads nothing; load_config resolves it against the config file's folder and loads it.
StudyConfig parse_config(const nlohmann::json& j, const std::string& file);
StudyConfig load_config(const std::filesystem::path& path);
// Makes `calibration_file` (resolved against the working directory) the config's display
// transfer, loaded: display.calibration of a config, or `run --display-calibration FILE`.
// Throws std::runtime_error "<calibration file>: <field>: <what>".
void load_display_calibration(StudyConfig& c, const std::filesystem::path& calibration_file);
// Makes `kernel` the PCF kernel the stimuli are drawn with (`run --kernel`): stimulus.kernel, or
// pcf.kernel among the settings of a config drawn by the renderer's PCF, so that session.json's
// config, the log's kernel column and the fitted entry all name it. Throws std::invalid_argument
// ("the stimuli are drawn by vsm, ...") for a technique without kernels: its c is one entry.
void set_stimulus_kernel(StudyConfig& c, stimuli::Kernel kernel);
nlohmann::json to_json(const StudyConfig& c);

}  // namespace penumbra::procedure
