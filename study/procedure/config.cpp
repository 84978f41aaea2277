#include "procedure/config.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <set>
#include <stdexcept>

#include "json/json_fields.h"
#include "json/json_input.h"
#include "text/printable.h"

namespace penumbra::procedure {

double Display::arcmin(double px) const {
  const double mm = px * width_mm / width_px;
  return 2.0 * std::atan(0.5 * mm / viewing_distance_mm) * 180.0 / M_PI * 60.0;
}

double Display::pixels_per_degree() const {
  const double mm = 2.0 * viewing_distance_mm * std::tan(0.5 * M_PI / 180.0);
  return mm * width_px / width_mm;
}

// U+2190 / U+2192: the arrow keys.
#define PENUMBRA_LEFT "\xe2\x86\x90"
#define PENUMBRA_RIGHT "\xe2\x86\x92"

const std::vector<TextEntry>& text_table() {
  static const std::vector<TextEntry> table = {
      {"welcome_title", "Shadow edges", nullptr, "title of the first screen"},
      {"welcome_back_title", "Welcome back", nullptr, "its title when a session is resumed"},
      {"welcome", "Thank you for taking part.", nullptr, "first screen, above the task"},
      {"task",
       "You will see two shadow edges: one jagged (stair-stepped), one straight.\n"
       "Which side shows the jagged edge? " PENUMBRA_LEFT " or F: left, " PENUMBRA_RIGHT " or J: right.\n"
       "If you are unsure, guess.",
       "You will see one shadow edge: straight or jagged (stair-stepped).\n"
       "Is it straight? " PENUMBRA_LEFT " or F: yes, " PENUMBRA_RIGHT " or J: no, it is jagged.\n"
       "If you are unsure, guess.",
       "how to answer: first screen and every round's screen"},
      {"question", "Which side shows the jagged (stair-stepped) edge?", "Is this edge straight?", "above the stimuli in every trial"},
      {"answer_first", "Left   " PENUMBRA_LEFT " or F", "Yes   " PENUMBRA_LEFT " or F", "first answer button (" PENUMBRA_LEFT " or F)"},
      {"answer_second", "Right   " PENUMBRA_RIGHT " or J", "No   " PENUMBRA_RIGHT " or J", "second answer button (" PENUMBRA_RIGHT " or J)"},
      {"example_jagged", "Jagged (stair-stepped)", nullptr, "label under the jagged example"},
      {"example_straight", "Straight", nullptr, "label under the straight example"},
      {"round", "Round {round} of {rounds}", nullptr, "round line of the instruction screens and the progress line"},
      {"round_body", "New shadow edges. The task stays the same.", nullptr, "screen between rounds, above the task"},
      {"practice_note", "The first few trials are practice.", nullptr, "added when practice trials come next"},
      {"practice_feedback_note", "The first few trials are practice; you will see if you were right.", nullptr,
       "instead, when practice has feedback"},
      {"practice", "Practice", nullptr, "progress line during practice"},
      {"practice_feedback_correct", "Correct", nullptr, "feedback after a right practice answer"},
      {"practice_feedback_wrong", "Wrong", nullptr, "feedback after a wrong practice answer"},
      {"start", "Start   (Space)", nullptr, "button of the first screen"},
      {"continue", "Continue   (Space)", nullptr, "button of the round and break screens"},
      {"break_title", "Break", nullptr, "title of the break screen"},
      {"break", "Rest your eyes for a moment.\nContinue when you are ready.", nullptr, "break screen"},
      {"pause_title", "Please wait", nullptr, "title while the experimenter pauses"},
      {"pause", "The experimenter has paused the session.", nullptr, "text while the experimenter pauses"},
      {"end_title", "Thank you!", nullptr, "title of the end screen"},
      {"end", "The session is complete.\nPlease tell the experimenter.", nullptr, "end screen"},
      {"consent", "", nullptr, "consent text shown before the session is created (empty: no consent screen)"},
      {"consent_title", "Consent", nullptr, "title of the consent screen"},
      {"consent_agree", "I agree   (Enter)", nullptr, "agree button (Enter)"},
      {"consent_decline", "I do not agree   (Esc)", nullptr, "decline button (Escape): the app exits, nothing written"},
  };
  return table;
}

#undef PENUMBRA_LEFT
#undef PENUMBRA_RIGHT

const std::vector<std::pair<char32_t, char32_t>>& drawable_ranges() {
  static const std::vector<std::pair<char32_t, char32_t>> ranges = {
      {0x0020, 0x007E}, {0x00A0, 0x024F}, {0x0370, 0x03FF}, {0x0400, 0x04FF}, {0x2013, 0x2014}, {0x2018, 0x201E},
      {0x2022, 0x2022}, {0x2026, 0x2026}, {0x2190, 0x2193}, {0x2212, 0x2212}};
  return ranges;
}

bool drawable(char32_t cp) {
  for (const auto& [first, last] : drawable_ranges())
    if (cp >= first && cp <= last) return true;
  return false;
}

std::string text_problem(const std::string& key, const std::string& value) {
  if (!text::valid_utf8(value)) return "not valid UTF-8 (save the file as UTF-8)";
  for (std::size_t i = 0; i < value.size();) {
    const auto lead = static_cast<unsigned char>(value[i]);
    const int n = lead < 0x80 ? 1 : lead < 0xE0 ? 2 : lead < 0xF0 ? 3 : 4;
    char32_t cp = n == 1 ? lead : lead & (0xFF >> (n + 1));
    for (int k = 1; k < n; ++k) cp = (cp << 6) | (static_cast<unsigned char>(value[i + static_cast<std::size_t>(k)]) & 0x3F);
    if (cp != '\n' && !drawable(cp)) {
      char code[16];
      std::snprintf(code, sizeof code, "U+%04X", static_cast<unsigned>(cp));
      if (cp < 0x20 || (cp >= 0x7F && cp < 0xA0)) return std::string("a control character (") + code + "); only a newline (\\n) is allowed";
      return std::string("character ") + code + " '" + value.substr(i, static_cast<std::size_t>(n)) +
             "' cannot be drawn by the participant's window (its font covers Latin, Greek and Cyrillic); translate or remove it";
    }
    i += static_cast<std::size_t>(n);
  }
  for (std::size_t open = value.find('{'); open != std::string::npos; open = value.find('{', open + 1)) {
    const std::size_t close = value.find('}', open);
    if (close == std::string::npos) break;
    const std::string name = value.substr(open, close - open + 1);
    const bool filled = key == "round" && (name == "{round}" || name == "{rounds}");
    if (!filled && name.size() > 2 && name.find_first_not_of("abcdefghijklmnopqrstuvwxyz_", 1) == name.size() - 1)
      return "placeholder " + name + " is not filled in" + (key == "round" ? " (texts.round fills {round} and {rounds})" : " this text (only texts.round fills {round} and {rounds})");
  }
  return "";
}

std::string StudyConfig::text(const std::string& key, int round, int round_count) const {
  std::string out;
  const auto given = std::find_if(texts.begin(), texts.end(), [&](const auto& kv) { return kv.first == key; });
  if (given != texts.end()) {
    out = given->second;
  } else {
    const auto& table = text_table();
    const auto entry = std::find_if(table.begin(), table.end(), [&](const TextEntry& e) { return key == e.key; });
    if (entry == table.end()) throw std::logic_error("StudyConfig::text: no text '" + key + "'");
    out = task == "yesno" && entry->default_yesno ? entry->default_yesno : entry->default_2afc;
  }
  if (round > 0)
    for (const auto& [placeholder, value] : {std::pair<std::string, int>{"{round}", round}, {"{rounds}", round_count}})
      for (std::size_t at; (at = out.find(placeholder)) != std::string::npos;) out.replace(at, placeholder.size(), std::to_string(value));
  return out;
}

namespace {

// The config's fields are stated where they are read; json_input::Reader checks each and words its
// errors. `path` is the object's field path with a trailing '.' ("quest."), or "" at the top level.
class Reader {
 public:
  explicit Reader(std::string file) : r_(std::move(file)) {}
  [[noreturn]] void fail(const std::string& field, const std::string& what) const { r_.fail(field, what); }
  const nlohmann::json* find(const nlohmann::json& obj, const std::string& key) const {
    auto it = obj.find(key);
    return it == obj.end() ? nullptr : &*it;
  }
  double number(const nlohmann::json& obj, const std::string& path, const std::string& key, double fallback,
                double lo, double hi) const {
    const auto* v = r_.get(obj, at(path), {.name = key, .type = json_input::Type::number, .min = lo, .max = hi});
    return v ? v->get<double>() : fallback;
  }
  long integer(const nlohmann::json& obj, const std::string& path, const std::string& key, long fallback, long lo,
               long hi) const {
    const auto* v = r_.get(obj, at(path),
                           {.name = key, .type = json_input::Type::integer, .min = static_cast<double>(lo), .max = static_cast<double>(hi)});
    return v ? v->get<long>() : fallback;
  }
  bool boolean(const nlohmann::json& obj, const std::string& path, const std::string& key, bool fallback) const {
    const auto* v = r_.get(obj, at(path), {.name = key, .type = json_input::Type::boolean});
    return v ? v->get<bool>() : fallback;
  }
  std::string text(const nlohmann::json& obj, const std::string& path, const std::string& key,
                   const std::string& fallback) const {
    const auto* v = r_.get(obj, at(path), {.name = key, .type = json_input::Type::string});
    return v ? v->get<std::string>() : fallback;
  }
  // A string of `choices`, named `key` in the error.
  std::string choice(const nlohmann::json& obj, const std::string& path, const std::string& key, const std::string& fallback,
                     std::vector<std::string> choices) const {
    const auto* v = r_.get(obj, at(path), {.name = key, .type = json_input::Type::string, .choices = std::move(choices), .noun = key});
    return v ? v->get<std::string>() : fallback;
  }
  const nlohmann::json* get(const nlohmann::json& obj, const std::string& path, const json_input::Field& f) const {
    return r_.get(obj, at(path), f);
  }
  void only(const nlohmann::json& obj, const std::string& path, std::initializer_list<const char*> keys) const {
    json_input::ObjectSpec spec;
    for (const char* k : keys) spec.fields.push_back({.name = k});
    r_.object(obj, at(path), spec);
  }
  template <class F>
  auto parse_enum(const std::string& field, const std::string& value, F parse) const {
    try {
      return parse(value);
    } catch (const std::invalid_argument& e) {
      fail(field, e.what());
    }
  }
  static std::string fmt(double d) {
    char b[32];
    std::snprintf(b, sizeof b, "%g", d);
    return b;
  }

 private:
  static std::string at(const std::string& path) { return path.empty() ? path : path.substr(0, path.size() - 1); }
  json_input::Reader r_;
};

// "section.key": value pairs (penumbra-render's keys) as text, in the file's order.
std::vector<std::pair<std::string, std::string>> settings_of(const Reader& r, const nlohmann::json& settings, const std::string& path) {
  if (!settings.is_object()) r.fail(path, "expected an object of \"section.key\": value");
  std::vector<std::pair<std::string, std::string>> out;
  for (auto it = settings.begin(); it != settings.end(); ++it) {
    const std::string field = path + "." + text::printable(it.key());
    if (it.key().empty() || it.key().size() > 64) r.fail(field, "expected a setting's name (e.g. pcf.kernel)");
    std::string value;
    if (it->is_string()) value = it->get<std::string>();
    else if (it->is_boolean()) value = it->get<bool>() ? "true" : "false";
    else if (it->is_number()) value = it->dump();
    else r.fail(field, "expected a string, a number or true/false");
    if (value.size() > 64) r.fail(field, "value longer than 64 characters");
    out.emplace_back(it.key(), value);
  }
  return out;
}

// The settings a frame study sets itself for every frame (the rule, its constant, the maps).
bool study_owned_setting(const std::string& key) {
  return key.rfind("adaptive.enabled", 0) == 0 || key == "adaptive.c" || key == "adaptive.visibility" || key == "map.cascades" ||
         key == "map.resolution_texels" || key == "map.virtual_pages";
}

void parse_frames(const Reader& r, const nlohmann::json& f, FramesConfig& out) {
  r.only(f, "frames.", {"scene", "width_px", "height_px", "c", "settings", "reference", "k_grid", "warmup_frames", "patches"});
  const auto* scene = r.get(f, "frames.", {.name = "scene", .type = json_input::Type::string, .required = true,
                                           .why = "the scene whose frames are shown (outdoor, demo, or a scene file)"});
  out.scene = scene->get<std::string>();
  if (out.scene.empty() || out.scene.size() > 4096) r.fail("frames.scene", "expected a built-in scene name or a scene file");
  out.width_px = static_cast<int>(r.integer(f, "frames.", "width_px", 960, 16, 8192));
  out.height_px = static_cast<int>(r.integer(f, "frames.", "height_px", 540, 16, 8192));
  out.c = r.number(f, "frames.", "c", 3.47, 0.1, 100);
  if (const auto* settings = r.find(f, "settings")) {
    out.settings = settings_of(r, *settings, "frames.settings");
    for (const auto& [key, value] : out.settings)
      if (study_owned_setting(key))
        r.fail("frames.settings." + text::printable(key), "set by the study (the rule with adaptive.c = k c, the reference's maps)");
  }
  if (const auto* ref = r.find(f, "reference")) {
    r.only(*ref, "frames.reference.", {"cascades", "resolution_texels", "k"});
    if (r.find(*ref, "k")) {
      for (const char* maps : {"cascades", "resolution_texels"})
        if (r.find(*ref, maps))
          r.fail(std::string("frames.reference.") + maps, "not with frames.reference.k (the reference is the rule at that k, or maps)");
      out.reference_k = r.number(*ref, "frames.reference.", "k", 8, 0.01, 1000);
    }
    out.reference_cascades = static_cast<int>(r.integer(*ref, "frames.reference.", "cascades", 4, 1, 4));
    out.reference_texels = static_cast<int>(r.integer(*ref, "frames.reference.", "resolution_texels", 8188, 64, 16384));
  }
  if (const auto* grid = r.find(f, "k_grid")) {
    r.only(*grid, "frames.k_grid.", {"min", "max", "steps_per_octave"});
    out.k_min = r.number(*grid, "frames.k_grid.", "min", 0.125, 0.01, 100);
    out.k_max = r.number(*grid, "frames.k_grid.", "max", 8, 0.01, 100);
    if (!(out.k_max > out.k_min)) r.fail("frames.k_grid.max", "expected above frames.k_grid.min");
    out.k_steps_per_octave = static_cast<int>(r.integer(*grid, "frames.k_grid.", "steps_per_octave", 4, 1, 64));
  }
  out.warmup_frames = static_cast<int>(r.integer(f, "frames.", "warmup_frames", 2, 0, 100));
  const auto* patches = r.get(f, "frames.", {.name = "patches", .type = json_input::Type::array, .required = true,
                                             .why = "the patches shown: [{\"name\", \"path_frame\", \"x_px\", \"y_px\"}]", .min_items = 1});
  for (std::size_t i = 0; i < patches->size(); ++i) {
    const std::string p = "frames.patches[" + std::to_string(i) + "].";
    const nlohmann::json& e = (*patches)[i];
    r.only(e, p, {"name", "path_frame", "x_px", "y_px"});
    FramePatch patch;
    patch.name = r.text(e, p, "name", "");
    if (patch.name.empty() || patch.name.size() > 64 ||
        patch.name.find_first_of(",\"\n\r ") != std::string::npos || !text::valid_utf8(patch.name))
      r.fail(p + "name", "expected a short name without spaces, commas or quotes (the staircase's name in the log)");
    for (const FramePatch& other : out.patches)
      if (other.name == patch.name) r.fail(p + "name", "'" + patch.name + "' names another patch already");
    patch.path_frame = static_cast<int>(r.integer(e, p, "path_frame", -1, -1, 10'000'000));
    patch.x_px = static_cast<int>(r.integer(e, p, "x_px", 0, 0, 8192));
    patch.y_px = static_cast<int>(r.integer(e, p, "y_px", 0, 0, 8192));
    out.patches.push_back(patch);
  }
}

}  // namespace

double FramesConfig::round_k(double k) const {
  const double step = 1.0 / k_steps_per_octave;  // in octaves
  const double lo = std::ceil(std::log2(k_min) / step - 1e-9), hi = std::floor(std::log2(k_max) / step + 1e-9);
  const double i = std::clamp(std::round(std::log2(k) / step), lo, hi);
  return std::exp2(i * step);
}

StudyConfig parse_config(const nlohmann::json& j, const std::string& file) {
  const Reader r(file);
  r.only(j, "", {"name", "task", "artifact_px", "rounds", "quest", "intensity_bounds", "stopping", "practice_trials",
                 "practice_intensity", "practice", "texts", "break_every_trials", "seed", "round_order", "stimulus", "display", "description",
                 "yesno_scoring", "readings", "frames"});
  StudyConfig c;
  const nlohmann::json* frames = r.find(j, "frames");
  c.name = r.text(j, "", "name", "study");
  c.task = r.choice(j, "", "task", "2afc", {"2afc", "yesno"});
  if (r.find(j, "yesno_scoring")) {
    if (c.task != "yesno") r.fail("yesno_scoring", "only for task yesno (a 2afc trial is scored one way)");
    c.yesno_scoring = r.choice(j, "", "yesno_scoring", "jagged_only", {"jagged_only", "balanced"});
  }
  if (const auto* readings = r.find(j, "readings")) {
    if (!readings->is_object()) r.fail("readings", "expected an object of \"choice\": \"what was chosen and why\"");
    for (auto it = readings->begin(); it != readings->end(); ++it) {
      const std::string field = "readings." + text::printable(it.key());
      if (!it->is_string() || it->get<std::string>().empty()) r.fail(field, "expected a non-empty string");
      if (!text::valid_utf8(it->get<std::string>())) r.fail(field, "not valid UTF-8 (save the file as UTF-8)");
      c.readings.emplace_back(it.key(), it->get<std::string>());
    }
  }

  if (frames) {
    if (c.task != "2afc") r.fail("task", "a frame study is 2afc (which of the two is the reference?)");
    parse_frames(r, *frames, c.frames);
    for (const char* edge_only : {"artifact_px", "intensity_bounds"})
      if (r.find(j, edge_only))
        r.fail(edge_only, "not with frames (a frame study's staircases are its patches, its intensities log10(1 / k) within frames.k_grid)");
    c.artifact_px.clear();
    c.intensity_min = -std::log10(c.frames.k_max);
    c.intensity_max = -std::log10(c.frames.k_min);
  }
  if (const auto* a = r.find(j, "artifact_px")) {
    if (!a->is_array() || a->empty()) r.fail("artifact_px", "expected a non-empty array of sizes in px");
    c.artifact_px.clear();
    std::set<double> seen;
    for (std::size_t i = 0; i < a->size(); ++i) {
      const auto& v = (*a)[i];
      const std::string f = "artifact_px[" + std::to_string(i) + "]";
      if (!v.is_number() || !(v.get<double>() >= 1 && v.get<double>() <= 200)) r.fail(f, "expected a size in [1, 200] px");
      if (!seen.insert(v.get<double>()).second) r.fail(f, "duplicate artifact size");
      c.artifact_px.push_back(v.get<double>());
    }
  }
  const auto* rounds = r.get(j, "", {.name = "rounds", .type = json_input::Type::array, .required = true,
                                     .why = "a study needs its rounds: [{\"pattern\", \"contrast\"}]", .min_items = 1});
  for (std::size_t i = 0; i < rounds->size(); ++i) {
    const std::string p = "rounds[" + std::to_string(i) + "].";
    RoundConfig rc;
    if (frames) {
      r.only((*rounds)[i], p, {"technique"});
      rc.technique = r.text((*rounds)[i], p, "technique", "");
      if (rc.technique.empty() || rc.technique.size() > 32)
        r.fail(p + "technique", "expected the technique whose frames the round shows (penumbra-render --technique: pcf, pcss, ...)");
      for (std::size_t k = 0; k < i; ++k)
        if (c.rounds[k].technique == rc.technique) r.fail(p + "technique", "'" + text::printable(rc.technique) + "' has a round already");
      c.rounds.push_back(rc);
      continue;
    }
    r.only((*rounds)[i], p, {"pattern", "contrast"});
    rc.pattern = r.parse_enum(p + "pattern", r.text((*rounds)[i], p, "pattern", "stair"), stimuli::parse_pattern);
    rc.contrast = r.number((*rounds)[i], p, "contrast", 1.0, 0.01, 1.0);
    c.rounds.push_back(rc);
  }
  // yesno feeds QUEST the jagged trials only (hit = "not straight"): its guess rate is the
  // false-alarm rate, and p_threshold puts the threshold at the same point of the underlying
  // detection function F as 2afc's .82 does (F = 0.6465 with delta .01; docs/study.md). Scored
  // balanced, every trial counts and the guess rate is 2afc's.
  const bool yesno = c.task == "yesno" && c.yesno_scoring == "jagged_only";
  const double default_gamma = yesno ? 0.05 : 0.5, default_p = yesno ? 0.658 : 0.82;
  if (const auto* q = r.find(j, "quest")) {
    r.only(*q, "quest.", {"t_guess", "t_guess_sd", "p_threshold", "beta", "delta", "gamma", "grain", "range", "tail_p_threshold"});
    c.quest.t_guess = r.number(*q, "quest.", "t_guess", frames ? 0.0 : -0.5, -5, 5);
    c.quest.t_guess_sd = r.number(*q, "quest.", "t_guess_sd", 1.0, 0.01, 100);
    c.quest.p_threshold = r.number(*q, "quest.", "p_threshold", default_p, 0.01, 0.999);
    c.quest.beta = r.number(*q, "quest.", "beta", 3.5, 0.1, 100);
    c.quest.delta = r.number(*q, "quest.", "delta", 0.01, 0, 0.5);
    c.quest.gamma = r.number(*q, "quest.", "gamma", default_gamma, 0, 0.99);
    if (c.quest.p_threshold <= c.quest.gamma) r.fail("quest.p_threshold", "expected above quest.gamma");
    c.quest.grain = r.number(*q, "quest.", "grain", 0.01, 1e-4, 1);
    if (r.find(*q, "range")) c.quest.range = r.number(*q, "quest.", "range", 5, 0.1, 100);
    if (r.find(*q, "tail_p_threshold")) {
      if (frames) r.fail("quest.tail_p_threshold", "not with frames (a tail target is for the edge study's staircases)");
      c.tail_p_threshold = r.number(*q, "quest.", "tail_p_threshold", 0, 0.01, 0.999);
      // Between the guess rate (a target there is no detection at all) and the criterion (the
      // first staircase's; above it is no tail).
      if (!(c.tail_p_threshold > c.quest.gamma && c.tail_p_threshold < c.quest.p_threshold))
        r.fail("quest.tail_p_threshold", "expected between quest.gamma (" + Reader::fmt(c.quest.gamma) + ") and quest.p_threshold (" +
                                             Reader::fmt(c.quest.p_threshold) + "), both excluded, got " + Reader::fmt(c.tail_p_threshold));
    }
  } else {
    c.quest.t_guess = frames ? 0.0 : -0.5;  // frames: k = 1, the rule as it is
    c.quest.t_guess_sd = 1.0;
    c.quest.gamma = default_gamma;
    c.quest.p_threshold = default_p;
  }
  if (const auto* b = r.find(j, "intensity_bounds")) {
    if (!b->is_array() || b->size() != 2 || !(*b)[0].is_number() || !(*b)[1].is_number() ||
        !((*b)[0].get<double>() < (*b)[1].get<double>()))
      r.fail("intensity_bounds", "expected [min, max] with min < max (log10(a / r))");
    c.intensity_min = (*b)[0].get<double>();
    c.intensity_max = (*b)[1].get<double>();
  }
  if (const auto* s = r.find(j, "stopping")) {
    r.only(*s, "stopping.", {"min_trials", "max_trials", "sd_below"});
    c.min_trials = static_cast<int>(r.integer(*s, "stopping.", "min_trials", 10, 1, 10000));
    c.max_trials = static_cast<int>(r.integer(*s, "stopping.", "max_trials", 40, 1, 10000));
    if (c.max_trials < c.min_trials) r.fail("stopping.max_trials", "expected >= stopping.min_trials");
    c.sd_below = r.number(*s, "stopping.", "sd_below", 0.1, 0, 10);
  }
  if (const auto* p = r.find(j, "practice")) {
    for (const char* flat : {"practice_trials", "practice_intensity"})
      if (r.find(j, flat)) r.fail(flat, "not with practice (practice.trials and practice.intensity say it)");
    r.only(*p, "practice.", {"trials", "intensity", "every_round", "feedback", "feedback_ms"});
    c.practice.trials = static_cast<int>(r.integer(*p, "practice.", "trials", 4, 0, 1000));
    c.practice.intensity = r.number(*p, "practice.", "intensity", frames ? kFramePracticeIntensity : 0.3, -3, 3);
    c.practice.every_round = r.boolean(*p, "practice.", "every_round", true);
    c.practice.feedback = r.boolean(*p, "practice.", "feedback", true);
    c.practice.feedback_ms = r.number(*p, "practice.", "feedback_ms", 800, 0, 10000);
  } else {  // configs and sessions from before the practice block: the first round's practice, no feedback
    c.practice.trials = static_cast<int>(r.integer(j, "", "practice_trials", 4, 0, 1000));
    c.practice.intensity = r.number(j, "", "practice_intensity", frames ? kFramePracticeIntensity : 0.3, -3, 3);
  }
  if (const auto* t = r.find(j, "texts")) {
    if (!t->is_object()) r.fail("texts", "expected an object of \"name\": \"text\"");
    const auto& table = text_table();
    for (auto it = t->begin(); it != t->end(); ++it) {
      const std::string field = "texts." + text::printable(it.key());
      if (std::none_of(table.begin(), table.end(), [&](const TextEntry& e) { return it.key() == e.key; })) {
        std::vector<std::string> known;
        for (const TextEntry& e : table) known.emplace_back(e.key);
        r.fail(field, json_input::Reader::unknown_key(known));
      }
      if (!it->is_string()) r.fail(field, "expected a string, got " + json_input::describe(*it));
      const std::string value = it->get<std::string>();
      if (!text::valid_utf8(value)) r.fail(field, "not valid UTF-8 (save the file as UTF-8)");
      if (value.size() > kMaxTextBytes) r.fail(field, "longer than " + std::to_string(kMaxTextBytes) + " bytes");
      if (const std::string problem = text_problem(it.key(), value); !problem.empty()) r.fail(field, problem);
      if (value.empty() && it.key() != "consent") r.fail(field, "expected a non-empty text");
      c.texts.emplace_back(it.key(), value);
    }
  }
  c.break_every_trials = static_cast<int>(r.integer(j, "", "break_every_trials", 40, 0, 100000));
  c.round_order = r.choice(j, "", "round_order", "shuffled", {"shuffled", "fixed", "latin-square"});
  if (const auto* s = r.find(j, "seed")) {
    if (!s->is_number_unsigned()) r.fail("seed", "expected a non-negative integer, got " + json_input::describe(*s));
    c.seed = s->get<std::uint64_t>();
  }
  if (const auto* s = r.find(j, "stimulus")) {
    if (frames) r.only(*s, "stimulus.", {"size_px"});  // the rounds name the technique, frames.settings its settings
    r.only(*s, "stimulus.", {"size_px", "kernel", "poisson_taps", "technique", "settings"});
    c.stimulus_size_px = static_cast<int>(r.integer(*s, "stimulus.", "size_px", 320, 16, 4096));
    if (r.find(*s, "technique")) {
      // The technique's settings (checked against the renderer's tables by penumbra-study before
      // a session starts) say the kernel and taps; without a technique, the kernel field does.
      for (const char* own : {"kernel", "poisson_taps"})
        if (r.find(*s, own))
          r.fail(std::string("stimulus.") + own, "the kernel without a technique (the renderer's PCF); with stimulus.technique the "
                                                 "technique's settings say it (\"settings\": {\"pcf.kernel\": \"grid\"})");
      c.technique = r.text(*s, "stimulus.", "technique", "");
      if (c.technique.empty() || c.technique.size() > 32) r.fail("stimulus.technique", "expected a technique name (penumbra-render --technique)");
      if (const auto* settings = r.find(*s, "settings")) {
        if (!settings->is_object()) r.fail("stimulus.settings", "expected an object of \"section.key\": value");
        for (auto it = settings->begin(); it != settings->end(); ++it) {
          const std::string field = "stimulus.settings." + text::printable(it.key());
          if (it.key().empty() || it.key().size() > 64) r.fail(field, "expected a setting's name (e.g. pcf.kernel)");
          std::string value;
          if (it->is_string()) value = it->get<std::string>();
          else if (it->is_boolean()) value = it->get<bool>() ? "true" : "false";
          else if (it->is_number()) value = it->dump();
          else r.fail(field, "expected a string, a number or true/false");
          if (value.size() > 64) r.fail(field, "value longer than 64 characters");
          c.technique_settings.emplace_back(it.key(), value);
        }
      }
      if (c.technique == "pcf") {
        const auto kernel = std::find_if(c.technique_settings.begin(), c.technique_settings.end(),
                                         [](const auto& kv) { return kv.first == "pcf.kernel"; });
        if (kernel == c.technique_settings.end())
          r.fail("stimulus.settings", "pcf.kernel is required with technique pcf (disk, grid or poisson: the log's kernel column)");
        c.kernel = r.parse_enum("stimulus.settings.pcf.kernel", kernel->second, stimuli::parse_kernel);
      } else {
        c.kernel = stimuli::Kernel::grid;  // RPCF's box and the moments techniques' box blur
      }
    } else {
      if (r.find(*s, "settings")) r.fail("stimulus.settings", "needs stimulus.technique (the technique the settings are for)");
      c.kernel = r.parse_enum("stimulus.kernel", r.text(*s, "stimulus.", "kernel", "disk"), stimuli::parse_kernel);
      c.poisson_taps = static_cast<int>(r.integer(*s, "stimulus.", "poisson_taps", 32, 1, 64));
    }
  }
  if (const auto* d = r.find(j, "display")) {
    r.only(*d, "display.", {"width_px", "height_px", "width_mm", "height_mm", "viewing_distance_mm", "transfer", "calibration", "monitor"});
    c.display.width_px = static_cast<int>(r.integer(*d, "display.", "width_px", 1920, 1, 100000));
    c.display.height_px = static_cast<int>(r.integer(*d, "display.", "height_px", 1080, 1, 100000));
    c.display.width_mm = r.number(*d, "display.", "width_mm", 527, 1, 100000);
    c.display.height_mm = r.number(*d, "display.", "height_mm", 296, 1, 100000);
    c.display.viewing_distance_mm = r.number(*d, "display.", "viewing_distance_mm", 600, 1, 100000);
    c.display.calibration_file = r.text(*d, "display.", "calibration", "");
    if (r.find(*d, "calibration") && (c.display.calibration_file.empty() || c.display.calibration_file.size() > 4096))
      r.fail("display.calibration", "expected the path of a display-calibration.json (penumbra-study calibrate-display)");
    const std::string transfer = r.text(*d, "display.", "transfer", c.display.calibration_file.empty() ? "srgb" : "measured");
    if (transfer == "measured") {
      if (c.display.calibration_file.empty()) r.fail("display.transfer", "measured needs display.calibration (the measurement's file)");
      c.display.transfer = {stimuli::Transfer::Kind::measured, nullptr};
    } else {
      c.display.transfer = r.parse_enum("display.transfer", transfer, stimuli::parse_transfer);
      if (!c.display.calibration_file.empty())
        r.fail("display.transfer", "'" + transfer + "' with display.calibration: the calibration measures the transfer; leave display.transfer out");
    }
    c.display.monitor = static_cast<int>(r.integer(*d, "display.", "monitor", 0, 0, 16));
  }
  for (double a : c.artifact_px)
    if (2 * a > c.stimulus_size_px) r.fail("artifact_px", "an artifact larger than half the stimulus cannot be shown");
  // Geometry a lab could not have (issue 16): every angle the log records would be wrong.
  const Display& d = c.display;
  const double pixel_aspect = (d.height_mm / d.height_px) / (d.width_mm / d.width_px);
  if (std::abs(pixel_aspect - 1.0) > kPixelAspectTolerance)
    r.fail("display.height_mm", "pixels " + Reader::fmt(pixel_aspect) + " times as tall as wide (" + Reader::fmt(d.width_mm) + " mm / " +
                                    std::to_string(d.width_px) + " px across, " + Reader::fmt(d.height_mm) + " mm / " +
                                    std::to_string(d.height_px) + " px down); expected square pixels within 5 %: check the sizes in mm");
  if (d.viewing_distance_mm < kMinViewingDistanceMm)
    r.fail("display.viewing_distance_mm", "expected at least " + Reader::fmt(kMinViewingDistanceMm) + " mm (the screen centre to the eyes), got " +
                                              Reader::fmt(d.viewing_distance_mm));
  const int across = c.task == "2afc" ? 2 * c.stimulus_size_px : c.stimulus_size_px;  // 2afc: side by side
  if (across > d.width_px || c.stimulus_size_px > d.height_px)
    r.fail("stimulus.size_px", std::to_string(c.stimulus_size_px) + " px" + (c.task == "2afc" ? " twice side by side" : "") +
                                   " does not fit the display's " + std::to_string(d.width_px) + " x " + std::to_string(d.height_px) + " px");
  for (std::size_t i = 0; frames && i < c.frames.patches.size(); ++i) {
    const FramePatch& patch = c.frames.patches[i];
    if (patch.x_px + c.stimulus_size_px > c.frames.width_px || patch.y_px + c.stimulus_size_px > c.frames.height_px)
      r.fail("frames.patches[" + std::to_string(i) + "]", "a patch of stimulus.size_px " + std::to_string(c.stimulus_size_px) + " at (" +
                                                          std::to_string(patch.x_px) + ", " + std::to_string(patch.y_px) +
                                                          ") does not fit the " + std::to_string(c.frames.width_px) + " x " +
                                                          std::to_string(c.frames.height_px) + " frame");
  }
  try {
    quest::Quest probe(c.quest);
  } catch (const std::exception& e) {
    r.fail("quest", e.what());
  }
  return c;
}

StudyConfig load_config(const std::filesystem::path& path) {
  StudyConfig c = parse_config(json_input::read_file(path, {.max_bytes = 1 << 20, .max_depth = 16}), path.string());
  if (!c.display.calibration_file.empty()) {
    const std::filesystem::path named = c.display.calibration_file;
    try {
      load_display_calibration(c, named.is_absolute() ? named : path.parent_path() / named);
    } catch (const std::exception& e) {
      throw std::runtime_error(path.string() + ": display.calibration: " + e.what());
    }
  }
  return c;
}

void load_display_calibration(StudyConfig& c, const std::filesystem::path& calibration_file) {
  const std::filesystem::path file = std::filesystem::absolute(calibration_file).lexically_normal();
  c.display.transfer = stimuli::Transfer::measured(display::load_calibration(file));
  c.display.calibration_file = file.string();
}

void set_stimulus_kernel(StudyConfig& c, stimuli::Kernel kernel) {
  if (!c.technique.empty() && c.technique != "pcf")
    throw std::invalid_argument("the stimuli are drawn by " + text::printable(c.technique) +
                                ", which has no kernel to choose (only pcf has; its entry is one for any kernel)");
  c.kernel = kernel;
  for (auto& [key, value] : c.technique_settings)
    if (key == "pcf.kernel") value = stimuli::to_string(kernel);
}

// Hand-written: the config file's layout (nested sections, enums as names, fields only when set or not default).
nlohmann::json to_json(const StudyConfig& c) {
  nlohmann::json rounds = nlohmann::json::array();
  for (const auto& r : c.rounds)
    rounds.push_back(c.frames.enabled() ? nlohmann::json{{"technique", r.technique}}
                                        : nlohmann::json{{"pattern", stimuli::to_string(r.pattern)}, {"contrast", r.contrast}});
  nlohmann::json quest = {{"t_guess", c.quest.t_guess}, {"t_guess_sd", c.quest.t_guess_sd},
                          {"p_threshold", c.quest.p_threshold}, {"beta", c.quest.beta}, {"delta", c.quest.delta},
                          {"gamma", c.quest.gamma}, {"grain", c.quest.grain}};
  if (c.quest.range) quest["range"] = *c.quest.range;
  if (c.tail_p_threshold > 0) quest["tail_p_threshold"] = c.tail_p_threshold;  // only when set: earlier sessions read back equal
  nlohmann::json stimulus = {{"size_px", c.stimulus_size_px}};
  if (c.technique.empty() && !c.frames.enabled()) {  // a frame study's stimulus block holds its size alone
    stimulus["kernel"] = stimuli::to_string(c.kernel);
    stimulus["poisson_taps"] = c.poisson_taps;
  } else if (!c.technique.empty()) {
    stimulus["technique"] = c.technique;
    stimulus["settings"] = nlohmann::json::object();
    for (const auto& [key, value] : c.technique_settings) stimulus["settings"][key] = value;
  }
  nlohmann::json display = {{"width_px", c.display.width_px}, {"height_px", c.display.height_px},
                             {"width_mm", c.display.width_mm}, {"height_mm", c.display.height_mm},
                             {"viewing_distance_mm", c.display.viewing_distance_mm},
                             {"transfer", stimuli::to_string(c.display.transfer)}, {"monitor", c.display.monitor}};
  if (!c.display.calibration_file.empty()) display["calibration"] = c.display.calibration_file;
  nlohmann::json j = {{"name", c.name},
          {"task", c.task},
          {"artifact_px", c.artifact_px},
          {"rounds", rounds},
          {"quest", quest},
          {"intensity_bounds", {c.intensity_min, c.intensity_max}},
          {"stopping", {{"min_trials", c.min_trials}, {"max_trials", c.max_trials}, {"sd_below", c.sd_below}}},
          {"break_every_trials", c.break_every_trials},
          {"seed", c.seed},
          {"round_order", c.round_order},
          {"stimulus", stimulus},
          {"display", display}};
  const Practice legacy;
  if (!c.practice.every_round && !c.practice.feedback && c.practice.feedback_ms == legacy.feedback_ms) {
    j["practice_trials"] = c.practice.trials;  // as configs before the practice block said it
    j["practice_intensity"] = c.practice.intensity;
  } else {
    j["practice"] = {{"trials", c.practice.trials}, {"intensity", c.practice.intensity}, {"every_round", c.practice.every_round},
                     {"feedback", c.practice.feedback}, {"feedback_ms", c.practice.feedback_ms}};
  }
  if (!c.texts.empty()) {
    j["texts"] = nlohmann::json::object();
    for (const auto& [key, value] : c.texts) j["texts"][key] = value;
  }
  if (c.frames.enabled()) {
    j.erase("artifact_px");
    j.erase("intensity_bounds");
    const FramesConfig& f = c.frames;
    nlohmann::json patches = nlohmann::json::array();
    for (const FramePatch& p : f.patches) patches.push_back({{"name", p.name}, {"path_frame", p.path_frame}, {"x_px", p.x_px}, {"y_px", p.y_px}});
    nlohmann::json settings = nlohmann::json::object();
    for (const auto& [key, value] : f.settings) settings[key] = value;
    j["frames"] = {{"scene", f.scene}, {"width_px", f.width_px}, {"height_px", f.height_px}, {"c", f.c}, {"settings", settings},
                   {"reference", f.reference_k > 0 ? nlohmann::json{{"k", f.reference_k}}
                                                   : nlohmann::json{{"cascades", f.reference_cascades}, {"resolution_texels", f.reference_texels}}},
                   {"k_grid", {{"min", f.k_min}, {"max", f.k_max}, {"steps_per_octave", f.k_steps_per_octave}}},
                   {"warmup_frames", f.warmup_frames}, {"patches", patches}};
  }
  // Only when not the default, so that sessions written before the field existed read back equal.
  if (c.yesno_scoring != "jagged_only") j["yesno_scoring"] = c.yesno_scoring;
  if (!c.readings.empty()) {
    j["readings"] = nlohmann::json::object();
    for (const auto& [key, value] : c.readings) j["readings"][key] = value;
  }
  return j;
}

}  // namespace penumbra::procedure
