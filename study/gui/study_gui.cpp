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
#include "gui/admin_view.h"
#include "gui/gui_window.h"
#include "gui/participant_view.h"
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

namespace {

enum class Screen { welcome, round, blank, trial, feedback, pause, rest, finished };

const char* describe(Screen s) {
  switch (s) {
    case Screen::welcome: return "welcome screen";
    case Screen::round: return "round instructions";
    case Screen::feedback: return "practice feedback";
    case Screen::blank: return "blank (between trials)";
    case Screen::trial: return "trial on screen";
    case Screen::pause: return "paused";
    case Screen::rest: return "break screen";
    case Screen::finished: return "end screen";
  }
  return "";
}

void write_rgb_png(const fs::path& path, const io::Image8& rgba) {
  io::Image8 rgb{rgba.width, rgba.height, 3, std::vector<std::uint8_t>(static_cast<std::size_t>(rgba.width) * rgba.height * 3)};
  for (std::size_t i = 0; i < static_cast<std::size_t>(rgba.width) * rgba.height; ++i)
    for (int c = 0; c < 3; ++c) rgb.pixels[i * 3 + c] = rgba.pixels[i * 4 + c];
  io::write_png(path, rgb);
}

void say(const std::string& line) { std::cout << line << std::endl; }  // operators and the GUI test read this

}  // namespace

void parse_window_size(const std::string& s, int& w, int& h) {
  char x = 0;
  char extra = 0;
  if (std::sscanf(s.c_str(), "%d%c%d%c", &w, &x, &h, &extra) != 3 || x != 'x' || w < 64 || h < 64 || w > 16384 || h > 16384)
    throw std::invalid_argument("--windowed '" + text::printable(s) + "': expected WIDTHxHEIGHT in pixels, e.g. 1280x800");
}

int run_session(const OpenSession& open_session, const GuiOptions& o, const std::optional<Intake>& intake) {
  // Everything that can refuse comes before the session is opened, so a refusal leaves no
  // new session directory behind.
  int win_w = 0, win_h = 0;
  if (!o.windowed.empty()) parse_window_size(o.windowed, win_w, win_h);
  Glfw glfw;
  const auto monitors = glfw.monitors();
  if (monitors.empty()) throw std::runtime_error("no monitor connected");
  const int n_monitors = static_cast<int>(monitors.size());
  auto check_monitor = [&](int m, const std::string& what) {
    if (m >= n_monitors)
      throw std::invalid_argument(what + " " + std::to_string(m) + ": only " + std::to_string(n_monitors) +
                                  " monitor(s) connected (0.." + std::to_string(n_monitors - 1) + ")");
  };
  if (o.monitor >= 0) check_monitor(o.monitor, "--monitor");
  const bool fullscreen = o.windowed.empty();
  if (fullscreen && !o.admin_panel && n_monitors < 2)
    throw std::invalid_argument("one monitor only: the admin window would cover or sit under the participant's screen; "
                                "use --admin-panel (F12 toggles it) or --windowed WxH");

  // The config's monitor and stimuli against the screen, before the session is created or resumed
  // (a stimulus too large was refused only once the participant had pressed Space).
  auto check_config = [&](const procedure::StudyConfig& c) {
    const int m = o.monitor >= 0 ? o.monitor : c.display.monitor;
    check_monitor(m, "display.monitor");
    int w = win_w, h = win_h;
    if (fullscreen) {
      const GLFWvidmode* mode = glfwGetVideoMode(monitors[static_cast<std::size_t>(m)]);
      w = mode->width;
      h = mode->height;
    }
    (void)stimulus_layout(w, h, c.stimulus_size_px, c.task == "2afc" ? 2 : 1);  // throws naming the sizes
  };
  std::optional<procedure::Session> opened;
  if (intake) check_config(intake->config);  // the session is created once the participant id is typed
  else opened.emplace(open_session(check_config, ""));
  const procedure::StudyConfig config = intake ? intake->config : opened->config();
  const bool two = config.task == "2afc";
  const int monitor = o.monitor >= 0 ? o.monitor : config.display.monitor;
  if (fullscreen) {
    const GLFWvidmode* mode = glfwGetVideoMode(monitors[static_cast<std::size_t>(monitor)]);
    if (mode->width != config.display.width_px || mode->height != config.display.height_px)
      std::cerr << "penumbra-study: warning: monitor " << monitor << " runs at " << mode->width << "x" << mode->height
                << " px but the config's display is " << config.display.width_px << "x" << config.display.height_px
                << " px; arcmin values in the log follow the config\n";
  }

  WindowSpec ps;
  ps.title = "Penumbra study";
  ps.width = win_w;
  ps.height = win_h;
  ps.fullscreen_on = fullscreen ? monitors[static_cast<std::size_t>(monitor)] : nullptr;
  ps.x = fullscreen ? -1 : 0;
  ps.y = 0;
  ps.vsync = true;
  ps.font_px = 22;
  ps.large_font_px = 30;
  ps.small_font_px = o.admin_panel ? 16 : 0;
  std::unique_ptr<GuiWindow> admin;  // destroyed last: the objects below need the participant's context
  GuiWindow participant(ps);
  participant.make_current();
  // Stimulus onsets count from here on the steady clock: this run of the session (a resumed one
  // starts again at 0).
  const double clock_start_s = glfw.now_s();
  double refresh_hz = 0;
  ParticipantView view(config.task);   // styles the participant's ImGui context
  stimuli::StimulusRenderer renderer;  // lives in the participant window's GL context
  struct CurrentOnExit {
    GuiWindow& window;
    ~CurrentOnExit() { window.make_current(); }  // GL objects are freed in the context that made them
  } current_on_exit{participant};
  // --screenshot-at: participant.png of that screen (between end_frame and swap), then the app stops.
  auto screenshot_of = [&](const char* name) {
    if (o.screenshot_dir.empty() || o.screenshot_at != name) return false;
    fs::create_directories(o.screenshot_dir);
    write_rgb_png(o.screenshot_dir / "participant.png", participant.read_back());
    say("wrote " + (o.screenshot_dir / "participant.png").string() + " (" + name + ")");
    return true;
  };

  if (intake) {
    // The experimenter types the participant id; nothing exists on disk until it is accepted and
    // the participant has agreed to the consent text (when the config has one).
    const std::string consent = config.text("consent");
    std::string id, problem;
    bool consenting = false, accepted = false;
    for (int frame = 0; !accepted; ++frame) {
      // Said once the field has the keyboard (ImGui focuses it in the frame after it asks).
      if (frame == 2) say("intake screen: waiting for the participant id");
      const double frame_start = glfw.now_s();
      bool agree = false, quit = participant.close_requested();
      for (const Press& p : participant.take_presses()) {
        if (p.key == GLFW_KEY_ESCAPE) quit = true;
        else if (consenting && (p.key == GLFW_KEY_ENTER || p.key == GLFW_KEY_KP_ENTER)) agree = true;
      }
      participant.begin_frame();
      const bool on_consent = consenting;
      if (consenting) {
        const ConsentChoice choice = view.draw_consent(participant, config.text("consent_title"), consent,
                                                       config.text("consent_agree"), config.text("consent_decline"));
        agree |= choice == ConsentChoice::agree;
        quit |= choice == ConsentChoice::decline;
      } else if (view.draw_intake(participant, id, config.name, problem)) {
        problem = intake->problem(id);
        if (!problem.empty()) {
          say("intake: refused: " + problem);
        } else if (consent.empty()) {
          accepted = true;
        } else {
          consenting = true;
          say("consent screen: waiting for agree (Enter) or decline (Escape)");
        }
      }
      participant.end_frame();
      const bool shot = screenshot_of(on_consent ? "consent" : "intake");
      participant.swap();
      if (shot) return 0;
      if (quit && !accepted) {
        say(on_consent ? "consent declined: nothing written" : "intake cancelled: nothing written");
        return 0;
      }
      if (agree) {
        say("consent given");
        accepted = true;
      }
      glfw.wait_events(std::max(0.0, frame_start + 1.0 / 60 - glfw.now_s()));
    }
    say("participant '" + text::printable(id) + "' accepted");
    opened.emplace(open_session(check_config, id));
  }
  procedure::Session& session = *opened;
  {
    // What the participant really sees, beside the config's assumptions (display-check).
    GLFWmonitor* shown_on = fullscreen ? monitors[static_cast<std::size_t>(monitor)] : glfwGetPrimaryMonitor();
    const GLFWvidmode* mode = glfwGetVideoMode(shown_on);
    int fb_w = 0, fb_h = 0, mm_w = 0, mm_h = 0;
    participant.framebuffer_size(fb_w, fb_h);
    glfwGetMonitorPhysicalSize(shown_on, &mm_w, &mm_h);
    const char* renderer_name = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
    // Dropped frames are judged against the video mode's refresh rate, or --refresh-hz where the
    // mode reports none (GLFW gives 0).
    refresh_hz = mode->refreshRate > 0 ? mode->refreshRate : o.refresh_hz;
    const char* refresh_from = mode->refreshRate > 0 ? "video mode" : o.refresh_hz > 0 ? "--refresh-hz" : "unknown";
    if (mode->refreshRate > 0 && o.refresh_hz > 0 && o.refresh_hz != mode->refreshRate)
      std::cerr << "penumbra-study: warning: --refresh-hz " << o.refresh_hz << " ignored: the video mode reports "
                << mode->refreshRate << " Hz\n";
    const nlohmann::json presentation = {
        {"fullscreen", fullscreen},
        {"monitor", fullscreen ? monitor : -1},
        {"monitor_name", glfwGetMonitorName(shown_on) ? glfwGetMonitorName(shown_on) : ""},
        {"video_mode", {{"width_px", mode->width}, {"height_px", mode->height}, {"refresh_hz", mode->refreshRate}}},
        {"monitor_size_mm", {mm_w, mm_h}},
        {"framebuffer_px", {fb_w, fb_h}},
        {"matches_config", mode->width == config.display.width_px && mode->height == config.display.height_px},
        {"gl_renderer", renderer_name ? renderer_name : ""},
        {"admin", o.admin_panel ? "panel (F12)" : "window"},
        {"frame_timing",
         {{"refresh_hz", refresh_hz > 0 ? nlohmann::json(refresh_hz) : nlohmann::json()},
          {"from", refresh_from},
          {"dropped_over_ms", refresh_hz > 0 ? nlohmann::json(trial_log::kDroppedFramePeriods * 1000.0 / refresh_hz) : nlohmann::json()}}}};
    session.record_presentation(presentation);
    say("presentation: " + presentation.dump());
  }

  if (!o.admin_panel) {
    WindowSpec as;
    as.title = "Penumbra study - admin";
    as.width = 1120;
    as.height = 780;
    if (fullscreen) {
      GLFWmonitor* other = nullptr;
      for (std::size_t i = 0; i < monitors.size(); ++i)
        if (static_cast<int>(i) != monitor) {
          other = monitors[i];
          break;
        }
      int x = 0, y = 0, w = 0, h = 0;
      glfwGetMonitorWorkarea(other, &x, &y, &w, &h);
      as.x = x + 20;
      as.y = y + 40;
      as.width = std::min(as.width, w - 40);
      as.height = std::min(as.height, h - 80);
    } else {
      as.x = win_w + 10;
      as.y = 0;
    }
    as.font_px = 16;
    as.focused = false;  // the keyboard belongs to the participant
    admin = std::make_unique<GuiWindow>(as);
    glfwFocusWindow(participant.window());
  }
  bool panel_visible = !o.screenshot_dir.empty();
  // The admin panel over the participant's view hides the stimuli (except for --screenshot, which
  // captures the two together on purpose).
  auto panel_covers = [&] { return o.admin_panel && panel_visible && o.screenshot_dir.empty(); };

  Screen screen = Screen::welcome;
  std::optional<procedure::TrialPlan> plan;
  double blank_until = 0, onset_s = -1, last_mouse_s = 0, admin_drawn_s = -1, feedback_until = 0;
  int break_done_at = session.trials_done();  // a resumed session starts with the welcome screen instead
  bool paused = false, stop = false, screenshot_due = false;
  AdminStatus status;
  status.dropped_frame_ms = refresh_hz > 0 ? trial_log::kDroppedFramePeriods * 1000.0 / refresh_hz : 0;
  // The intervals of the frames that showed the current stimulus, each from the swap before it.
  std::vector<double> stimulus_frames_ms;
  const bool resumed = session.trials_done() > 0;
  const int n_rounds = static_cast<int>(session.rounds().size());
  TrialText trial_text{config.text("question"), config.text("answer_first"), config.text("answer_second"), "", false};

  auto round_line = [&](int round) { return config.text("round", session.round_position(round) + 1, n_rounds); };
  auto progress = [&] {
    const int round = session.current_round();
    if (plan && plan->practice) return config.text("practice");
    if (round >= n_rounds) return std::string();
    return round_line(round);
  };
  // The instruction screens: the task in the config's words, the practice to come, and examples of
  // the round's pattern and contrast with the config's largest artifact and no filter to speak of
  // (the smallest radius shown, 1 px): a plainly jagged edge beside the straight one.
  int introduced_round = -1, examples_round = -1;
  auto show_examples = [&](int round) {
    if (round == examples_round) return;
    participant.make_current();
    const double artifact_px = *std::max_element(config.artifact_px.begin(), config.artifact_px.end());
    const stimuli::StimulusPair pair = renderer.render(session.stimulus(round, artifact_px, 1.0, 1));
    view.set_examples(pair.artifact, pair.line);
    examples_round = round;
  };
  // The first screen names the round below the examples; a round's own screen has it as the title.
  auto instructions = [&](const std::string& title, const std::string& intro, bool practice_next, bool round_below) {
    Instructions in;
    in.title = title;
    in.body = intro + "\n\n" + config.text("task");
    if (practice_next) in.body += "\n\n" + config.text(config.practice.feedback ? "practice_feedback_note" : "practice_note");
    in.jagged_label = config.text("example_jagged");
    in.straight_label = config.text("example_straight");
    in.examples = examples_round >= 0;
    in.round_line = round_below && examples_round >= 0 ? round_line(examples_round) : "";
    in.button = paused ? "" : config.text(screen == Screen::welcome ? "start" : "continue");
    return in;
  };
  if (const auto upcoming = session.next()) {  // the first screen introduces the first round to come
    introduced_round = upcoming->round;
    show_examples(upcoming->round);
  }
  const bool practice_first = session.next() && session.next()->practice;

  // The next trial's stimuli, after a blank interval.
  auto present = [&] {
    participant.make_current();  // the renderer's GL context (advance may run in the admin's frame)
    const stimuli::StimulusPair pair = renderer.render(plan->stimulus);
    if (two) {
      const bool left_jagged = plan->target == "left";
      view.set_stimuli({left_jagged ? &pair.artifact : &pair.line, left_jagged ? &pair.line : &pair.artifact});
    } else {
      view.set_stimuli({plan->target == "jagged" ? &pair.artifact : &pair.line});
    }
    screen = Screen::blank;
    blank_until = glfw.now_s() + o.iti_ms / 1000.0;
  };
  // Chooses what comes next: the end, a new round's instructions, a break, or the next trial.
  auto advance = [&] {
    plan = session.next();
    if (!plan) {
      screen = Screen::finished;
      say("session complete: " + std::to_string(session.trials_done()) + " trials in " + session.dir().string());
      return;
    }
    if (plan->round != introduced_round) {
      introduced_round = plan->round;
      break_done_at = session.trials_done();  // the round's screen is a rest as well
      show_examples(plan->round);
      screen = Screen::round;
      say("round screen: " + round_line(plan->round) + " (" + session.condition(plan->round) + (plan->practice ? ", practice first" : "") +
          "), waiting for Space");
      return;
    }
    if (session.break_due() && break_done_at != session.trials_done()) {
      screen = Screen::rest;
      say("break after " + std::to_string(session.trials_done()) + " trials");
      return;
    }
    present();
  };
  auto answer = [&](Answer a, double when_s) {
    const std::string response = response_for(a, config.task);
    const double rt_ms = std::max(0.0, (when_s - onset_s) * 1000.0);
    const trial_log::FrameTiming timing = trial_log::frame_timing(onset_s - clock_start_s, stimulus_frames_ms, refresh_hz);
    const trial_log::TrialRow row = session.record(*plan, response, rt_ms, timing);
    char buf[200];
    std::snprintf(buf, sizeof buf, "trial %d: %s (%s), %.0f ms", row.trial, response.c_str(),
                  row.correct ? "correct" : "wrong", rt_ms);
    status.last_answer = buf;
    say(buf);
    std::snprintf(buf, sizeof buf, "trial %d: %d frames, mean %.1f ms, max %.1f ms", row.trial, timing.frames,
                  timing.frame_ms_mean, timing.frame_ms_max);
    status.last_timing = buf;
    ++status.timed_trials;
    if (timing.dropped_frames.value_or(0) > 0) {
      ++status.trials_with_drops;
      status.dropped_frames += *timing.dropped_frames;
      std::snprintf(buf, sizeof buf, "warning: trial %d: %d dropped frame(s) while the stimulus was up (max %.1f ms, over %.1f ms)",
                    row.trial, *timing.dropped_frames, timing.frame_ms_max, status.dropped_frame_ms);
      say(buf);
    }
    if (plan->practice && config.practice.feedback) {  // practice only: test trials never say
      trial_text.feedback = config.text(row.correct ? "practice_feedback_correct" : "practice_feedback_wrong");
      trial_text.feedback_correct = row.correct == 1;
      screen = Screen::feedback;
      feedback_until = glfw.now_s() + config.practice.feedback_ms / 1000.0;
      say("trial " + std::to_string(row.trial) + " feedback: " + (row.correct ? "correct" : "wrong"));
      return;
    }
    advance();
  };
  auto start = [&] {
    if (screen == Screen::welcome) {
      advance();
    } else if (screen == Screen::rest) {
      break_done_at = session.trials_done();
      advance();
    } else if (screen == Screen::round) {
      present();
    }
  };
  auto apply_admin = [&](const AdminActions& a) {
    if (a.toggle_pause && screen != Screen::finished) {
      paused = !paused;
      say(paused ? "paused by the experimenter" : "resumed by the experimenter");
      if (paused && (screen == Screen::blank || screen == Screen::trial)) screen = Screen::pause;
      if (!paused && screen == Screen::pause && !panel_covers()) advance();  // the withdrawn trial comes again (same plan)
    }
    if (a.end_round) {
      say("round " + std::to_string(session.round_position(session.current_round()) + 1) + " (" +
          session.condition(session.current_round()) + ") ended by the experimenter");
      session.end_round();
      if (screen == Screen::blank || screen == Screen::trial || screen == Screen::round) advance();
    }
    if (a.quit) stop = true;
  };

  if (!o.screenshot_dir.empty() && o.screenshot_at == "trial") advance();  // straight to the first trial
  else say("welcome screen: waiting for Space");
  double last_swap_s = glfw.now_s();

  while (!stop) {
    const double frame_start = glfw.now_s();
    if (participant.close_requested() || (admin && admin->close_requested())) break;
    // One keyboard: keys typed while the admin window has the focus (after a click there) count
    // as the participant's; the admin window itself takes only mouse input.
    std::vector<Press> presses = participant.take_presses();
    if (admin)
      for (const Press& p : admin->take_presses())
        if (p.key >= 0) presses.push_back(p);
    std::sort(presses.begin(), presses.end(), [](const Press& a, const Press& b) { return a.time_s < b.time_s; });
    for (const Press& p : presses) {
      if (p.mouse_button >= 0) {
        last_mouse_s = p.time_s;
        continue;
      }
      if (p.key == GLFW_KEY_ESCAPE) stop = true;
      else if (p.key == GLFW_KEY_F12 && o.admin_panel) {
        // The panel covers the stimuli: a trial on screen is withdrawn while it is open (no answer
        // is taken, its reaction time does not run) and comes again, the same plan, once it closes.
        panel_visible = !panel_visible;
        if (panel_covers() && (screen == Screen::blank || screen == Screen::trial)) {
          screen = Screen::pause;
          say("trial " + std::to_string(plan->trial) + " withdrawn: the admin panel is open");
        } else if (!panel_visible && !paused && screen == Screen::pause) {
          advance();
        }
      }
      else if (p.key == GLFW_KEY_SPACE && !paused) start();
      else if (screen == Screen::trial && onset_s >= 0 && p.time_s >= onset_s && answer_for_key(p.key) != Answer::none)
        answer(answer_for_key(p.key), p.time_s);
    }
    if (stop) break;
    if (screen == Screen::feedback && glfw.now_s() >= feedback_until) {
      trial_text.feedback.clear();
      if (paused || panel_covers()) screen = Screen::pause;  // the next trial waits
      else advance();
    }
    if (screen == Screen::blank && glfw.now_s() >= blank_until) {
      // Never under the admin panel: started from the welcome or break screen while it is open,
      // the trial waits until it closes.
      screen = panel_covers() ? Screen::pause : Screen::trial;
      onset_s = -1;
    }

    // Participant frame.
    participant.begin_frame();
    const Screen drawn = screen;
    switch (screen) {
      case Screen::welcome:
        if (view.draw_instructions(participant,
                                   instructions(config.text(resumed ? "welcome_back_title" : "welcome_title"), config.text("welcome"),
                                                practice_first, true),
                                   ""))
          start();
        break;
      case Screen::round:
        if (view.draw_instructions(participant, instructions(round_line(plan->round), config.text("round_body"), plan->practice, false), ""))
          start();
        break;
      case Screen::rest:
        if (view.draw_message(participant, config.text("break_title"), config.text("break"), paused ? "" : config.text("continue"),
                              progress()))
          start();
        break;
      case Screen::pause:
        view.draw_message(participant, config.text("pause_title"), config.text("pause"), "", progress());
        break;
      case Screen::finished:
        view.draw_message(participant, config.text("end_title"), config.text("end"), "", "");
        break;
      case Screen::blank:
        view.draw_blank(participant, progress());
        break;
      case Screen::feedback:
        view.draw_trial(participant, trial_text, progress());
        break;
      case Screen::trial: {
        const Answer clicked = view.draw_trial(participant, trial_text, progress());
        if (clicked != Answer::none && onset_s >= 0) answer(clicked, std::max(last_mouse_s, onset_s));
        break;
      }
    }
    status.screen = describe(screen);
    status.paused = paused;
    if (o.admin_panel && panel_visible) {
      ImGui::PushFont(participant.small_font());
      ImGui::PushStyleVar(ImGuiStyleVar_FramePadding, {8, 4});
      ImGui::SetNextWindowPos({12, 12}, ImGuiCond_FirstUseEver);
      ImGui::SetNextWindowSize({900, 620}, ImGuiCond_FirstUseEver);
      ImGui::SetNextWindowBgAlpha(0.96f);
      ImGui::Begin("Admin (F12 hides)");
      const AdminActions actions = draw_admin(session, status);
      ImGui::End();
      ImGui::PopStyleVar();
      ImGui::PopFont();
      apply_admin(actions);
    }
    participant.end_frame();
    if (screenshot_of(drawn == Screen::welcome ? "welcome" : drawn == Screen::round ? "round" : drawn == Screen::feedback ? "feedback" : "")) {
      participant.swap();
      break;
    }
    const bool first_trial_frame = drawn == Screen::trial && screen == Screen::trial && onset_s < 0;
    if ((first_trial_frame || drawn == Screen::finished) && !o.screenshot_dir.empty() && o.screenshot_at == "trial") {
      fs::create_directories(o.screenshot_dir);
      write_rgb_png(o.screenshot_dir / "participant.png", participant.read_back());
      screenshot_due = true;
    }
    participant.swap();
    glFinish();  // the swap has been executed: the frame is on its way to the screen
    const double swap_s = glfw.now_s();
    if (first_trial_frame) {
      onset_s = swap_s;
      stimulus_frames_ms.clear();
    }
    if (drawn == Screen::trial && screen == Screen::trial && onset_s >= 0)
      stimulus_frames_ms.push_back((swap_s - last_swap_s) * 1000.0);
    last_swap_s = swap_s;
    if (first_trial_frame) {
      participant.take_presses();  // anything pressed before the onset is not an answer
      char buf[160];
      std::snprintf(buf, sizeof buf, "trial %d on screen (round %d, %s, r %.2f px, %s)", plan->trial, plan->round + 1,
                    plan->staircase_name.c_str(), plan->stimulus.filter_radius_px, plan->practice ? "practice" : "QUEST");
      say(buf);
    }

    // Admin window, at most ten times a second (it must not steal the participant's frames).
    if (admin && (screenshot_due || frame_start - admin_drawn_s >= 0.1)) {
      admin_drawn_s = frame_start;
      admin->begin_frame();
      glClearColor(0.09f, 0.10f, 0.11f, 1);
      glClear(GL_COLOR_BUFFER_BIT);
      ImGui::SetNextWindowPos({0, 0});
      ImGui::SetNextWindowSize(ImGui::GetIO().DisplaySize);
      ImGui::Begin("##admin", nullptr, ImGuiWindowFlags_NoDecoration | ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoSavedSettings);
      const AdminActions actions = draw_admin(session, status);
      ImGui::End();
      admin->end_frame();
      if (screenshot_due) write_rgb_png(o.screenshot_dir / "admin.png", admin->read_back());
      admin->swap();
      apply_admin(actions);
    }
    if (screenshot_due) {
      say("wrote " + (o.screenshot_dir / "participant.png").string() + (admin ? " and admin.png" : ""));
      break;
    }
    // Where the swap does not wait for the display (no vsync, e.g. Xvfb), do not spin: wait for
    // input up to ~120 frames a second. Input times come from the callbacks, so RTs do not suffer.
    glfw.wait_events(std::max(0.0, frame_start + 1.0 / 120 - glfw.now_s()));
  }
  if (screen != Screen::finished)
    say("stopped after " + std::to_string(session.trials_done()) + " trials; continue with: penumbra-study run --resume " +
        session.dir().string());
  return 0;
}

}  // namespace penumbra::study_gui
