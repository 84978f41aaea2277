#include "gui/study_gui.h"

#include <epoxy/gl.h>
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <CLI/CLI.hpp>
#include <imgui.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <iostream>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

#include "cli/checks.h"
#include "io/safe_path.h"
#include "gui/admin_view.h"
#include "gl/window.h"
#include "gui/participant_view.h"
#include "procedure/config.h"
#include "stimuli/frame_patch.h"
#include "stimuli/stimulus.h"
#include "text/printable.h"

namespace penumbra::study_gui {

namespace fs = std::filesystem;

void add_options(CLI::App& run, GuiOptions& o) {
  run.add_option("--monitor", o.monitor, "participant monitor (GLFW index; default: the config's display.monitor)")
      ->check(CLI::Range(0, 16));
  run.add_option("--windowed", o.windowed, "participant view in a WxH window instead of full screen (testing)");
  run.add_flag("--admin-panel", o.admin_panel, "single monitor: the admin view is a panel in the participant window, F12 shows/hides it");
  run.add_option("--iti-ms", o.iti_ms, "blank screen between trials (ms)")->capture_default_str()->check(cli::finite_range(0.0, 10000.0));
  run.add_option("--screenshot", o.screenshot_dir,
                 "write participant.png and admin.png into DIR at the first stimulus (a finished session: the end screen), then stop");
  run.add_option("--refresh-hz", o.refresh_hz,
                 "refresh rate of a participant display whose video mode reports none (Xvfb, some virtual displays): "
                 "dropped frames are judged against it")
      ->check(cli::finite_range(1.0, 1000.0));
  run.add_option("--screenshot-at", o.screenshot_at,
                 "with --screenshot: capture this screen instead (participant.png only): intake, consent, welcome, round, "
                 "feedback, trial")
      ->capture_default_str()
      ->check(CLI::IsMember({"trial", "intake", "consent", "welcome", "round", "feedback"}));
}

void parse_window_size(const std::string& s, int& w, int& h) {
  char x = 0;
  char extra = 0;
  if (std::sscanf(s.c_str(), "%d%c%d%c", &w, &x, &h, &extra) != 3 || x != 'x' || w < 64 || h < 64 || w > 16384 || h > 16384)
    throw std::invalid_argument("--windowed '" + text::printable(s) + "': expected WIDTHxHEIGHT in pixels, e.g. 1280x800");
}

nlohmann::json presentation_options(const GuiOptions& o) {
  return {{"monitor", o.monitor},
          {"windowed", o.windowed},
          {"admin_panel", o.admin_panel},
          {"refresh_hz", o.refresh_hz},
          {"iti_ms", o.iti_ms}};
}

void reuse_presentation_options(GuiOptions& o, const nlohmann::json& recorded, const std::function<bool(const std::string&)>& given,
                                const std::string& file) {
  if (recorded.is_null()) return;
  const std::string where = file + ": presentation_options";
  if (!recorded.is_object()) throw std::runtime_error(where + ": expected an object");
  auto number = [&](const char* key, double lo, double hi) {
    const nlohmann::json& v = recorded.at(key);
    if (!v.is_number() || !(v.get<double>() >= lo && v.get<double>() <= hi))
      throw std::runtime_error(where + "." + key + ": expected a number in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
    return v.get<double>();
  };
  for (const auto& [key, value] : recorded.items()) {
    if (key == "monitor") {
      const double m = number("monitor", -1, 16);
      if (m != std::floor(m)) throw std::runtime_error(where + ".monitor: expected a whole number");
      if (!given("--monitor")) o.monitor = static_cast<int>(m);
    } else if (key == "windowed") {
      if (!value.is_string()) throw std::runtime_error(where + ".windowed: expected a string (\"\" or WxH)");
      if (!given("--windowed")) o.windowed = value.get<std::string>();
      if (!o.windowed.empty()) {
        int w = 0, h = 0;
        try {
          parse_window_size(o.windowed, w, h);
        } catch (const std::invalid_argument&) {
          throw std::runtime_error(where + ".windowed: '" + text::printable(o.windowed) + "': expected WIDTHxHEIGHT in pixels");
        }
      }
    } else if (key == "admin_panel") {
      if (!value.is_boolean()) throw std::runtime_error(where + ".admin_panel: expected true or false");
      if (!given("--admin-panel")) o.admin_panel = value.get<bool>();
    } else if (key == "refresh_hz") {
      const double hz = number("refresh_hz", 0, 1000);
      if (!given("--refresh-hz")) o.refresh_hz = hz;
    } else if (key == "iti_ms") {
      const double iti = number("iti_ms", 0, 10000);
      if (!given("--iti-ms")) o.iti_ms = iti;
    } else {
      throw std::runtime_error(where + ": unknown key '" + text::printable(key) + "' (monitor, windowed, admin_panel, refresh_hz, iti_ms)");
    }
  }
}

namespace {

void write_rgb_png(const fs::path& path, const io::Image8& rgba) {
  io::Image8 rgb{rgba.width, rgba.height, 3, std::vector<std::uint8_t>(static_cast<std::size_t>(rgba.width) * rgba.height * 3)};
  for (std::size_t i = 0; i < static_cast<std::size_t>(rgba.width) * rgba.height; ++i)
    for (int c = 0; c < 3; ++c) rgb.pixels[i * 3 + c] = rgba.pixels[i * 4 + c];
  io::write_png(path, rgb);
}

void say(const std::string& line) { std::cout << line << std::endl; }  // operators and the GUI test read this

using procedure::Screen;

// The participant's monitor and the windows' sizes, checked before any session is opened.
struct Screens {
  std::vector<GLFWmonitor*> monitors;
  int win_w = 0, win_h = 0;  // --windowed
  bool fullscreen = true;
  int monitor = 0;  // the participant's (set once the config is known)

  Screens(const gl::Glfw& glfw, const GuiOptions& o) {
    if (!o.windowed.empty()) parse_window_size(o.windowed, win_w, win_h);
    monitors = glfw.monitors();
    if (monitors.empty()) throw std::runtime_error("no monitor connected");
    if (o.monitor >= 0) check_monitor(o.monitor, "--monitor");
    fullscreen = o.windowed.empty();
    if (fullscreen && !o.admin_panel && monitors.size() < 2)
      throw std::invalid_argument("one monitor only: the admin window would cover or sit under the participant's screen; "
                                  "use --admin-panel (F12 toggles it) or --windowed WxH");
  }
  void check_monitor(int m, const std::string& what) const {
    const int n = static_cast<int>(monitors.size());
    if (m >= n)
      throw std::invalid_argument(what + " " + std::to_string(m) + ": only " + std::to_string(n) + " monitor(s) connected (0.." +
                                  std::to_string(n - 1) + ")");
  }
  // The config's monitor and stimuli against the screen (a stimulus too large was refused only
  // once the participant had pressed Space).
  void check_config(const procedure::StudyConfig& c, const GuiOptions& o) {
    monitor = o.monitor >= 0 ? o.monitor : c.display.monitor;
    check_monitor(monitor, "display.monitor");
    int w = win_w, h = win_h;
    if (fullscreen) {
      const GLFWvidmode* mode = glfwGetVideoMode(monitors[static_cast<std::size_t>(monitor)]);
      w = mode->width;
      h = mode->height;
    }
    (void)stimulus_layout(w, h, c.stimulus_size_px, c.task == "2afc" ? 2 : 1, c.frames.enabled());  // throws naming the sizes
  }
  GLFWmonitor* participant_monitor() const { return fullscreen ? monitors[static_cast<std::size_t>(monitor)] : glfwGetPrimaryMonitor(); }
};

// A --screenshot-at screen the session would never reach, refused with one line.
void check_screenshot_reachable(const GuiOptions& o, const procedure::StudyConfig& config, bool intake, const procedure::Session* resumed) {
  if (o.screenshot_dir.empty()) return;
  io::check_output(o.screenshot_dir, io::OutputKind::directory, "participant.png");  // every output's rule
  for (Screen s : {Screen::intake, Screen::consent, Screen::welcome, Screen::round, Screen::feedback})
    if (o.screenshot_at == procedure::name_of(s))
      if (const std::string why = procedure::unreachable(s, config, intake, resumed); !why.empty())
        throw std::invalid_argument("--screenshot-at " + o.screenshot_at + ": " + why);
}

// The display as the participant really sees it, beside the config's assumptions: session.json's
// "presentation" (display-check says what the config assumes). Warns where they differ, since the
// log's visual angles follow the config.
nlohmann::json presentation_record(const Screens& screens, const gl::Window& participant, const procedure::StudyConfig& config,
                                   const GuiOptions& o, double refresh_hz) {
  GLFWmonitor* shown_on = screens.participant_monitor();
  const GLFWvidmode* mode = glfwGetVideoMode(shown_on);
  int fb_w = 0, fb_h = 0, mm_w = 0, mm_h = 0;
  participant.framebuffer_size(fb_w, fb_h);
  glfwGetMonitorPhysicalSize(shown_on, &mm_w, &mm_h);
  const procedure::Display& d = config.display;
  const bool px_match = mode->width == d.width_px && mode->height == d.height_px;
  // EDID sizes are whole millimetres, and some monitors round to the centimetre.
  auto close = [](double reported, double configured) { return std::abs(reported - configured) <= std::max(5.0, 0.02 * configured); };
  const bool mm_known = mm_w > 0 && mm_h > 0;
  const bool mm_match = mm_known && close(mm_w, d.width_mm) && close(mm_h, d.height_mm);
  if (screens.fullscreen) {
    const std::string where = "penumbra-study: warning: monitor " + std::to_string(screens.monitor);
    if (!px_match)
      std::cerr << where << " runs at " << mode->width << "x" << mode->height << " px but the config's display is " << d.width_px
                << "x" << d.height_px << " px; visual angles in the log follow the config\n";
    if (mm_known && !mm_match)
      std::cerr << where << " reports " << mm_w << "x" << mm_h << " mm but the config's display is " << d.width_mm << "x"
                << d.height_mm << " mm; visual angles in the log follow the config (measure the screen and correct display.width_mm/height_mm)\n";
  }
  nlohmann::json mismatch = nlohmann::json::array();
  if (!px_match) mismatch.push_back("size_px");
  if (!mm_known) mismatch.push_back("size_mm unknown");
  else if (!mm_match) mismatch.push_back("size_mm");
  const char* renderer_name = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  const char* refresh_from = mode->refreshRate > 0 ? "video mode" : o.refresh_hz > 0 ? "--refresh-hz" : "unknown";
  return {{"fullscreen", screens.fullscreen},
          {"monitor", screens.fullscreen ? screens.monitor : -1},
          {"monitor_name", glfwGetMonitorName(shown_on) ? glfwGetMonitorName(shown_on) : ""},
          {"video_mode", {{"width_px", mode->width}, {"height_px", mode->height}, {"refresh_hz", mode->refreshRate}}},
          {"monitor_size_mm", {mm_w, mm_h}},
          {"framebuffer_px", {fb_w, fb_h}},
          {"matches_config", mismatch.empty()},
          {"differs_from_config", mismatch},
          {"gl_renderer", renderer_name ? renderer_name : ""},
          {"admin", o.admin_panel ? "panel (F12)" : "window"},
          {"frame_timing",
           {{"refresh_hz", refresh_hz > 0 ? nlohmann::json(refresh_hz) : nlohmann::json()},
            {"from", refresh_from},
            {"dropped_over_ms", refresh_hz > 0 ? nlohmann::json(trial_log::kDroppedFramePeriods * 1000.0 / refresh_hz) : nlohmann::json()}}}};
}

std::unique_ptr<gl::Window> open_admin_window(const Screens& screens, const gl::Window& participant) {
  gl::WindowSpec as;
  as.title = "Penumbra study - admin";
  as.width = 1120;
  as.height = 780;
  if (screens.fullscreen) {
    GLFWmonitor* other = nullptr;
    for (std::size_t i = 0; i < screens.monitors.size(); ++i)
      if (static_cast<int>(i) != screens.monitor) {
        other = screens.monitors[i];
        break;
      }
    int x = 0, y = 0, w = 0, h = 0;
    glfwGetMonitorWorkarea(other, &x, &y, &w, &h);
    as.x = x + 20;
    as.y = y + 40;
    as.width = std::min(as.width, w - 40);
    as.height = std::min(as.height, h - 80);
  } else {
    as.x = screens.win_w + 10;
    as.y = 0;
  }
  as.font_px = 16;
  as.glyph_ranges = procedure::drawable_ranges();  // what a config's texts may hold
  as.focused = false;  // the keyboard belongs to the participant
  auto admin = std::make_unique<gl::Window>(as);
  glfwFocusWindow(participant.window());
  return admin;
}

Instructions instructions_of(const procedure::ScreenText& t) {
  Instructions in;
  in.title = t.title;
  in.body = t.body;
  in.jagged_label = t.jagged_label;
  in.straight_label = t.straight_label;
  in.round_line = t.round_line;
  in.button = t.button;
  in.examples = t.examples;
  return in;
}

// Draws the flow's screen into the participant window and passes on what the participant clicked.
void draw_screen(procedure::SessionFlow& flow, ParticipantView& view, gl::Window& window, std::string& typed_id, double last_mouse_s) {
  const procedure::ScreenText t = flow.text();
  switch (flow.screen()) {
    case Screen::intake:
      if (view.draw_intake(window, typed_id, t.title, t.body)) flow.submit_id(typed_id);
      break;
    case Screen::consent: {
      const ConsentChoice choice = view.draw_consent(window, t.title, t.body, t.first, t.second);
      if (choice == ConsentChoice::agree) flow.agree();
      if (choice == ConsentChoice::decline) flow.escape();
      break;
    }
    case Screen::welcome:
    case Screen::round:
      if (view.draw_instructions(window, instructions_of(t), t.progress)) flow.space();
      break;
    case Screen::rest:
    case Screen::pause:
    case Screen::finished:
      if (view.draw_message(window, t.title, t.body, t.button, t.progress)) flow.space();
      break;
    case Screen::blank:
    case Screen::closed:
      view.draw_blank(window, t.progress);
      break;
    case Screen::trial:
    case Screen::feedback: {
      const TrialText text{t.question, t.first, t.second, t.feedback, t.feedback_correct};
      const Answer clicked = view.draw_trial(window, text, t.progress);
      if (clicked != Answer::none && flow.answerable()) flow.answer(clicked, std::max(last_mouse_s, flow.onset_s()));
      break;
    }
  }
}

void apply_admin(procedure::SessionFlow& flow, const AdminActions& a) {
  if (a.toggle_pause) flow.toggle_pause();
  if (a.end_round) flow.end_round();
  if (a.quit) flow.quit();
}

}  // namespace

int run_session(const SessionStart& start, const GuiOptions& o) {
  // Everything that can refuse comes before a session is created or resumed, so a refusal leaves
  // no new session directory behind and an old one as it was.
  gl::Glfw glfw;
  Screens screens(glfw, o);
  std::optional<procedure::Session> resumed;
  if (start.resume) {
    resumed.emplace(start.resume([&](const procedure::Session& s) {
      screens.check_config(s.config(), o);
      check_screenshot_reachable(o, s.config(), false, &s);
      procedure::check_consent_record(s.session_json(), s.config(), (s.dir() / "session.json").string());
    }));
  } else {
    screens.check_config(start.config, o);
    check_screenshot_reachable(o, start.config, start.intake, nullptr);
  }
  const procedure::StudyConfig config = resumed ? resumed->config() : start.config;

  gl::WindowSpec ps;
  ps.title = "Penumbra study";
  ps.width = screens.win_w;
  ps.height = screens.win_h;
  ps.fullscreen_on = screens.fullscreen ? screens.monitors[static_cast<std::size_t>(screens.monitor)] : nullptr;
  ps.x = screens.fullscreen ? -1 : 0;
  ps.y = 0;
  ps.vsync = true;
  ps.font_px = 22;
  ps.large_font_px = 30;
  ps.small_font_px = o.admin_panel ? 16 : 0;
  ps.glyph_ranges = procedure::drawable_ranges();  // what a config's texts may hold
  std::unique_ptr<gl::Window> admin;  // destroyed last: the objects below need the participant's context
  gl::Window participant(ps);
  participant.make_current();
  // Stimulus onsets count from here on the steady clock: this run of the session (a resumed one
  // starts again at 0).
  const double clock_start_s = glfw.now_s();
  // Dropped frames are judged against the video mode's refresh rate, or --refresh-hz where the
  // mode reports none (GLFW gives 0).
  const GLFWvidmode* mode = glfwGetVideoMode(screens.participant_monitor());
  const double refresh_hz = mode->refreshRate > 0 ? mode->refreshRate : o.refresh_hz;
  if (mode->refreshRate > 0 && o.refresh_hz > 0 && o.refresh_hz != mode->refreshRate)
    std::cerr << "penumbra-study: warning: --refresh-hz " << o.refresh_hz << " ignored: the video mode reports " << mode->refreshRate
              << " Hz\n";
  const nlohmann::json presentation = presentation_record(screens, participant, config, o, refresh_hz);
  ParticipantView view(config.task);   // styles the participant's ImGui context
  stimuli::StimulusRenderer renderer;  // lives in the participant window's GL context
  stimuli::FrameCache frames(start.frame_cache, false);  // a frame study's patches: prepared, read from disk
  struct CurrentOnExit {
    gl::Window& window;
    ~CurrentOnExit() { window.make_current(); }  // GL objects are freed in the context that made them
  } current_on_exit{participant};

  procedure::FlowSetup setup;
  setup.config = config;
  setup.intake = start.intake;
  setup.participant = start.participant;
  setup.id_problem = start.id_problem;
  setup.iti_ms = o.iti_ms;
  setup.refresh_hz = refresh_hz;
  setup.admin_panel = o.admin_panel;
  auto announce = [&](procedure::Session& session) {
    session.record_presentation(presentation);
    say("presentation: " + presentation.dump());
  };
  setup.open = [&](const std::string& participant_id, const nlohmann::json& consent) {
    procedure::Session session = start.create(participant_id, consent);
    announce(session);
    return session;
  };
  procedure::FlowHooks hooks;
  hooks.say = say;
  hooks.present = [&](const procedure::TrialPlan& plan) {
    participant.make_current();  // the renderer's GL context (the flow may move on in the admin's frame)
    if (config.frames.enabled()) {  // the reference above; below, the reference on the target's side
      const stimuli::PatchPair pair = stimuli::patch_pair(frames, config, plan);
      const bool left_reference = plan.target == "left";
      view.set_stimuli({left_reference ? &pair.reference : &pair.test, left_reference ? &pair.test : &pair.reference}, &pair.reference);
      return;
    }
    const stimuli::StimulusPair pair = renderer.render(plan.stimulus);
    if (config.task == "2afc") {
      const bool left_jagged = plan.target == "left";
      view.set_stimuli({left_jagged ? &pair.artifact : &pair.line, left_jagged ? &pair.line : &pair.artifact});
    } else {
      view.set_stimuli({plan.target == "jagged" ? &pair.artifact : &pair.line});
    }
  };
  hooks.examples = [&](const stimuli::StimulusSpec& example) {
    participant.make_current();
    const stimuli::StimulusPair pair = renderer.render(example);
    view.set_examples(pair.artifact, pair.line);
  };
  std::optional<procedure::SessionFlow> flow_storage;
  if (resumed) {
    announce(*resumed);
    flow_storage.emplace(std::move(*resumed), setup, hooks, clock_start_s);
  } else {
    flow_storage.emplace(setup, hooks, clock_start_s);  // creates the session after intake and consent
  }
  procedure::SessionFlow& flow = *flow_storage;

  if (!o.admin_panel) admin = open_admin_window(screens, participant);
  const bool shoot = !o.screenshot_dir.empty();
  const bool shoot_trial = shoot && o.screenshot_at == "trial";
  std::string typed_id;
  double last_mouse_s = 0, admin_drawn_s = -1;
  bool admin_shot_due = false;

  while (!flow.done()) {
    const double frame_start = glfw.now_s();
    if (participant.should_close() || (admin && admin->should_close())) {
      flow.escape();
      break;
    }
    if (shoot_trial && flow.screen() == Screen::welcome) flow.space();  // straight to the first trial
    // One keyboard: keys typed while the admin window has the focus (after a click there) count
    // as the participant's; the admin window itself takes only mouse input.
    std::vector<gl::Press> presses = participant.take_presses();
    if (admin)
      for (const gl::Press& p : admin->take_presses())
        if (p.key >= 0) presses.push_back(p);
    std::sort(presses.begin(), presses.end(), [](const gl::Press& a, const gl::Press& b) { return a.time_s < b.time_s; });
    flow.tick(frame_start);
    for (const gl::Press& p : presses) {
      if (p.mouse_button >= 0) last_mouse_s = p.time_s;
      else if (p.key == GLFW_KEY_ESCAPE) flow.escape();
      else if (p.key == GLFW_KEY_F12) flow.toggle_panel();
      else if (p.key == GLFW_KEY_ENTER || p.key == GLFW_KEY_KP_ENTER) {
        if (flow.screen() == Screen::consent) flow.agree();
      } else if (p.key == GLFW_KEY_SPACE) flow.space();
      else if (answer_for_key(p.key) != Answer::none) flow.answer(answer_for_key(p.key), p.time_s);
      if (flow.done()) break;
    }
    if (flow.done()) break;
    flow.tick(glfw.now_s());

    // Participant frame. The admin panel is never in the participant's screenshot: it is hidden in a
    // live run unless the experimenter opens it.
    participant.begin_frame();
    const Screen drawn = flow.screen();
    draw_screen(flow, view, participant, typed_id, last_mouse_s);
    const bool panel = o.admin_panel && flow.has_session() && (flow.panel_visible() || admin_shot_due);
    if (panel) {
      ImGui::PushFont(participant.small_font());
      ImGui::PushStyleVar(ImGuiStyleVar_FramePadding, {8, 4});
      ImGui::SetNextWindowPos({12, 12}, ImGuiCond_FirstUseEver);
      ImGui::SetNextWindowSize({900, 620}, ImGuiCond_FirstUseEver);
      ImGui::SetNextWindowBgAlpha(0.96f);
      ImGui::Begin("Admin (F12 hides)");
      const AdminActions actions = draw_admin(flow.session(), flow.status());
      ImGui::End();
      ImGui::PopStyleVar();
      ImGui::PopFont();
      apply_admin(flow, actions);
    }
    participant.end_frame();
    if (admin_shot_due) {  // --admin-panel: admin.png is the panel over the participant's screen
      write_rgb_png(o.screenshot_dir / "admin.png", participant.read_back());
      say("wrote " + (o.screenshot_dir / "participant.png").string() + " and admin.png");
      break;
    }
    bool shot_done = false, admin_shot_now = false;
    if (shoot && !shoot_trial && o.screenshot_at == procedure::name_of(drawn)) {
      fs::create_directory(o.screenshot_dir);
      write_rgb_png(o.screenshot_dir / "participant.png", participant.read_back());
      say("wrote " + (o.screenshot_dir / "participant.png").string() + " (" + o.screenshot_at + ")");
      shot_done = true;
    }
    const bool first_trial_frame = drawn == Screen::trial && flow.screen() == Screen::trial && !flow.answerable();
    if (shoot_trial && (first_trial_frame || drawn == Screen::finished)) {
      fs::create_directory(o.screenshot_dir);
      write_rgb_png(o.screenshot_dir / "participant.png", participant.read_back());
      if (o.admin_panel) admin_shot_due = true;
      else admin_shot_now = true;
    }
    participant.swap();
    if (shot_done) break;
    glFinish();  // the swap has been executed: the frame is on its way to the screen
    const double swap_s = glfw.now_s();
    flow.swapped(drawn, swap_s);
    if (first_trial_frame && flow.answerable()) participant.take_presses();  // anything pressed before the onset is not an answer

    // Admin window, at most ten times a second (it must not steal the participant's frames).
    if (admin && (admin_shot_now || frame_start - admin_drawn_s >= 0.1)) {
      admin_drawn_s = frame_start;
      admin->begin_frame();
      glClearColor(0.09f, 0.10f, 0.11f, 1);
      glClear(GL_COLOR_BUFFER_BIT);
      ImGui::SetNextWindowPos({0, 0});
      ImGui::SetNextWindowSize(ImGui::GetIO().DisplaySize);
      ImGui::Begin("##admin", nullptr, ImGuiWindowFlags_NoDecoration | ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoSavedSettings);
      AdminActions actions;
      if (flow.has_session()) actions = draw_admin(flow.session(), flow.status());
      else ImGui::Text("No session yet. The participant sees: %s", flow.status().screen.c_str());  // intake, consent
      ImGui::End();
      admin->end_frame();
      if (admin_shot_now) write_rgb_png(o.screenshot_dir / "admin.png", admin->read_back());
      admin->swap();
      apply_admin(flow, actions);
    }
    if (admin_shot_now) {
      say("wrote " + (o.screenshot_dir / "participant.png").string() + " and admin.png");
      break;
    }
    if (shoot_trial && !admin_shot_due && !admin && (first_trial_frame || drawn == Screen::finished)) {
      say("wrote " + (o.screenshot_dir / "participant.png").string());
      break;
    }
    // Where the swap does not wait for the display (no vsync, e.g. Xvfb), do not spin: wait for
    // input up to ~120 frames a second. Input times come from the callbacks, so RTs do not suffer.
    glfw.wait_events(std::max(0.0, frame_start + 1.0 / 120 - glfw.now_s()));
  }
  return 0;
}

}  // namespace penumbra::study_gui
