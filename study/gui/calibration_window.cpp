#include "gui/calibration_window.h"

#include <epoxy/gl.h>
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <imgui.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <memory>
#include <stdexcept>

#include "gl/objects.h"
#include "gl/window.h"
#include "display/typed_readings.h"
#include "gui/study_gui.h"
#include "procedure/config.h"

namespace penumbra::study_gui {

namespace {

void say(const std::string& line) { std::cout << line << std::endl; }

// The window on the monitor measured, and what is known about that monitor.
struct Screen {
  std::unique_ptr<gl::Window> window;
  nlohmann::json monitor;
};

Screen open_screen(const gl::Glfw& glfw, const CalibrationScreen& s, const std::string& title) {
  int win_w = 0, win_h = 0;
  if (!s.windowed.empty()) parse_window_size(s.windowed, win_w, win_h);
  const auto monitors = glfw.monitors();
  if (monitors.empty()) throw std::runtime_error("no monitor connected");
  if (s.monitor >= static_cast<int>(monitors.size()))
    throw std::invalid_argument("--monitor " + std::to_string(s.monitor) + ": only " + std::to_string(monitors.size()) +
                                " monitor(s) connected (0.." + std::to_string(monitors.size() - 1) + ")");
  GLFWmonitor* monitor = monitors[static_cast<std::size_t>(s.monitor)];
  const bool fullscreen = s.windowed.empty();
  gl::WindowSpec spec;
  spec.title = title;
  spec.width = win_w;
  spec.height = win_h;
  spec.fullscreen_on = fullscreen ? monitor : nullptr;
  spec.x = fullscreen ? -1 : 0;
  spec.y = 0;
  spec.vsync = true;
  spec.font_px = 16;
  spec.glyph_ranges = procedure::drawable_ranges();  // what a config's texts may hold
  Screen screen;
  screen.window = std::make_unique<gl::Window>(spec);
  const GLFWvidmode* mode = glfwGetVideoMode(monitor);
  int fb_w = 0, fb_h = 0, mm_w = 0, mm_h = 0;
  screen.window->framebuffer_size(fb_w, fb_h);
  glfwGetMonitorPhysicalSize(monitor, &mm_w, &mm_h);
  const char* name = glfwGetMonitorName(monitor);
  screen.monitor = {{"monitor", s.monitor},
                    {"monitor_name", name ? name : ""},
                    {"fullscreen", fullscreen},
                    {"video_mode", {{"width_px", mode->width}, {"height_px", mode->height}, {"refresh_hz", mode->refreshRate}}},
                    {"monitor_size_mm", {mm_w, mm_h}},
                    {"framebuffer_px", {fb_w, fb_h}}};
  return screen;
}

// A small opaque box of text in a corner of the window, over whatever is drawn.
void begin_corner_box(const char* id, ImVec2 pivot) {
  const ImVec2 size = ImGui::GetIO().DisplaySize;
  ImGui::SetNextWindowPos({pivot.x * size.x + (pivot.x < 0.5f ? 8.0f : -8.0f), size.y - 8.0f}, ImGuiCond_Always, {pivot.x, 1.0f});
  ImGui::SetNextWindowBgAlpha(1.0f);
  ImGui::Begin(id, nullptr,
               ImGuiWindowFlags_NoDecoration | ImGuiWindowFlags_AlwaysAutoResize | ImGuiWindowFlags_NoMove |
                   ImGuiWindowFlags_NoSavedSettings | ImGuiWindowFlags_NoFocusOnAppearing);
}

}  // namespace

MeasuredLevels measure_levels(const std::vector<int>& levels, display::Model model, const std::vector<display::Reading>& kept,
                              const std::string& kept_file, const std::function<void(const std::vector<display::Reading>&)>& keep,
                              const CalibrationScreen& s) {
  gl::Glfw glfw;
  Screen screen = open_screen(glfw, s, "Penumbra display calibration");
  gl::Window& window = *screen.window;
  display::TypedReadings entry(levels, model, kept);
  auto stopped = [&] { return MeasuredLevels{false, entry.readings(), entry.model(), screen.monitor}; };
  if (!kept.empty()) say("going on from " + std::to_string(kept.size()) + " readings kept in " + kept_file);
  std::size_t shown = levels.size() + 1;
  bool review_said = false;
  const ImVec4 red{1.0f, 0.55f, 0.45f, 1.0f}, amber{1.0f, 0.8f, 0.4f, 1.0f};
  const std::string escape_line = "Escape: stop; the readings are kept in " + kept_file + ".";
  for (;;) {
    glfw.wait_events(0.05);
    if (window.should_close()) return stopped();
    bool write = false;
    for (const gl::Press& p : window.take_presses()) {
      if (p.key == GLFW_KEY_ESCAPE) return stopped();
      // Up/Down select a level, on the review and while levels are read (the one-line text box
      // has no use for them). Other keys belong to the text box while levels are read.
      if (p.key == GLFW_KEY_UP || p.key == GLFW_KEY_DOWN) {
        entry.select(p.key == GLFW_KEY_UP ? -1 : 1);
        if (entry.reviewing()) say("selected level " + std::to_string(entry.level()));
        continue;
      }
      if (!entry.reviewing()) continue;
      if (p.key == GLFW_KEY_BACKSPACE) {
        entry.remeasure();
        review_said = false;
        say("measuring level " + std::to_string(entry.level()) + " again");
      } else if (p.key == GLFW_KEY_TAB) {
        entry.set_model(entry.model() == display::Model::gamma ? display::Model::table : display::Model::gamma);
        review_said = false;
        say("model " + display::to_string(entry.model()));
      } else if ((p.key == GLFW_KEY_ENTER || p.key == GLFW_KEY_KP_ENTER) && entry.fitted()) {
        write = true;
      }
    }
    if (write) {
      say("readings accepted");
      return MeasuredLevels{true, entry.readings(), entry.model(), screen.monitor};
    }
    window.begin_frame();
    int w = 0, h = 0;
    window.framebuffer_size(w, h);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glDisable(GL_FRAMEBUFFER_SRGB);
    glDisable(GL_SCISSOR_TEST);
    glViewport(0, 0, w, h);
    bool typing = false, entered = false;
    if (!entry.reviewing()) {
      const int level = entry.level();
      const float v = static_cast<float>(level) / 255.0f;  // stored as exactly the level
      glClearColor(v, v, v, 1);
      glClear(GL_COLOR_BUFFER_BIT);
      begin_corner_box("##reading", {0.0f, 1.0f});
      ImGui::Text("Level %d (%zu of %zu; %zu read): point the photometer at the centre,", level, entry.current() + 1, levels.size(),
                  entry.read_count());
      ImGui::Text("type its reading in cd/m\xc2\xb2 (a decimal point: 8.1) and press Enter.");
      if (const auto& before = entry.reading(entry.current()))
        ImGui::Text("Read before: %g cd/m\xc2\xb2; a new reading replaces it.", *before);
      ImGui::Text("Up/Down: another level (to read it again). %s", escape_line.c_str());
      if (!entry.message().empty()) {  // wrapped: a refusal names the level to read again
        ImGui::PushTextWrapPos(ImGui::GetFontSize() * 36);
        ImGui::TextColored(red, "%s", entry.message().c_str());
        ImGui::PopTextWrapPos();
      }
      if (!ImGui::IsAnyItemActive()) ImGui::SetKeyboardFocusHere();
      ImGui::SetNextItemWidth(160);
      char typed[32] = {};
      entry.field().copy(typed, sizeof typed - 1);
      // One box per level: another level's box starts empty, not with what ImGui held for this one.
      ImGui::PushID(level);
      // No character filter: a typed comma reaches the parser, which says what to type instead.
      entered = ImGui::InputText("cd/m\xc2\xb2", typed, sizeof typed, ImGuiInputTextFlags_EnterReturnsTrue);
      // Enter leaves the box; it takes the keyboard back at once, so the next reading's first
      // characters are not lost.
      if (entered) ImGui::SetKeyboardFocusHere(-1);
      entry.field() = typed;
      typing = ImGui::IsItemActive();
      ImGui::PopID();
      ImGui::End();
    } else {
      // The review: every reading and the fitted model, before anything is written.
      glClearColor(0.5f, 0.5f, 0.5f, 1);
      glClear(GL_COLOR_BUFFER_BIT);
      begin_corner_box("##review", {0.0f, 1.0f});
      ImGui::Text("All %zu levels read. Check them before the calibration is written:", levels.size());
      if (ImGui::BeginTable("readings", 3, ImGuiTableFlags_Borders | ImGuiTableFlags_SizingFixedFit)) {
        ImGui::TableSetupColumn("");
        ImGui::TableSetupColumn("level");
        ImGui::TableSetupColumn("cd/m\xc2\xb2");
        ImGui::TableHeadersRow();
        for (std::size_t i = 0; i < levels.size(); ++i) {
          ImGui::TableNextRow();
          ImGui::TableNextColumn();
          ImGui::TextUnformatted(i == entry.current() ? ">" : "");
          ImGui::TableNextColumn();
          ImGui::Text("%d", levels[i]);
          ImGui::TableNextColumn();
          ImGui::Text("%g", entry.reading(i).value_or(0));
        }
        ImGui::EndTable();
      }
      const char* other = entry.model() == display::Model::gamma ? "table" : "gamma";
      if (const auto& c = entry.fitted()) {
        if (entry.model() == display::Model::gamma)
          ImGui::Text("Model gamma: gamma %.3f, black %.4g cd/m\xc2\xb2, white %.4g cd/m\xc2\xb2, RMS residual %.3g cd/m\xc2\xb2", c->gamma,
                      *c->black_cd_m2, *c->white_cd_m2, *c->residual_rms_cd_m2);
        else
          ImGui::Text("Model table: the readings, interpolated between levels; black %.4g cd/m\xc2\xb2, white %.4g cd/m\xc2\xb2",
                      *c->black_cd_m2, *c->white_cd_m2);
        if (!entry.fit_warning().empty()) ImGui::TextColored(amber, "%s", entry.fit_warning().c_str());
        ImGui::Text("Enter: write the calibration. Tab: the %s model instead.", other);
      } else {
        ImGui::TextColored(red, "No calibration from these readings: %s", entry.fit_problem().c_str());
        ImGui::Text("Tab: the %s model instead.", other);
      }
      ImGui::Text("Up/Down: select a level; Backspace: read it again. %s", escape_line.c_str());
      ImGui::End();
    }
    window.end_frame();
    window.swap();
    // Announced once the level is on screen and the entry box takes keys.
    if (!entry.reviewing() && shown != entry.current() && typing) {
      shown = entry.current();
      say("showing level " + std::to_string(entry.level()) + " (" + std::to_string(entry.current() + 1) + " of " +
          std::to_string(levels.size()) + ")");
    }
    if (entry.reviewing() && !review_said) {
      review_said = true;
      shown = levels.size() + 1;
      say(entry.fitted() ? "review: " + std::to_string(levels.size()) + " readings, model " + display::to_string(entry.model()) +
                               ", Enter writes" + (entry.fit_warning().empty() ? "" : "; note: " + entry.fit_warning())
                         : "review: no calibration from these readings: " + entry.fit_problem());
    }
    if (!entered) continue;
    const std::string typed = entry.field();
    const int level = entry.level();
    switch (entry.enter()) {
      case display::TypedReadings::Outcome::accepted:
        keep(entry.readings());  // on disk before the next level is shown
        say("level " + std::to_string(level) + ": " + typed + " cd/m2");
        break;
      case display::TypedReadings::Outcome::refused: say("level " + std::to_string(level) + ": refused: " + entry.message()); break;
      case display::TypedReadings::Outcome::confirm: say("level " + std::to_string(level) + ": confirm: " + entry.message()); break;
    }
  }
}

std::optional<CheckerboardMatch> match_checkerboard(const CalibrationScreen& s, int start_level) {
  gl::Glfw glfw;
  Screen screen = open_screen(glfw, s, "Penumbra display calibration");
  gl::Window& window = *screen.window;
  int w = 0, h = 0;
  window.framebuffer_size(w, h);
  // The whole frame as one texture copied 1:1 (a blit of equal sizes): left half the checkerboard,
  // right half the grey; rewritten when the grey changes.
  gl::Texture texture({GL_RGBA8, w, h, 1}, "checkerboard match");
  const gl::Framebuffer::Attachment attachment{&texture, GL_COLOR_ATTACHMENT0};
  gl::Framebuffer framebuffer({&attachment, 1}, "checkerboard match");
  struct CurrentOnExit {
    gl::Window& window;
    ~CurrentOnExit() { window.make_current(); }  // GL objects are freed in the context that made them
  } current_on_exit{window};
  std::vector<std::uint8_t> rgba(static_cast<std::size_t>(w) * h * 4);
  int level = std::clamp(start_level, 1, 254), uploaded = -1;
  for (;;) {
    glfw.wait_events(0.05);
    if (window.should_close()) return std::nullopt;
    for (const gl::Press& p : window.take_presses()) {
      if (p.key == GLFW_KEY_ESCAPE) return std::nullopt;
      if (p.key == GLFW_KEY_ENTER || p.key == GLFW_KEY_KP_ENTER) {
        say("matched grey level " + std::to_string(level));
        return CheckerboardMatch{level, screen.monitor};
      }
      if (p.key == GLFW_KEY_UP || p.key == GLFW_KEY_RIGHT) level = std::min(254, level + 1);
      if (p.key == GLFW_KEY_DOWN || p.key == GLFW_KEY_LEFT) level = std::max(1, level - 1);
      if (p.key == GLFW_KEY_PAGE_UP) level = std::min(254, level + 10);
      if (p.key == GLFW_KEY_PAGE_DOWN) level = std::max(1, level - 10);
    }
    window.begin_frame();
    if (level != uploaded) {
      for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
          std::uint8_t* p = &rgba[(static_cast<std::size_t>(y) * w + x) * 4];
          const std::uint8_t v = x < w / 2 ? ((x + y) % 2 ? 255 : 0) : static_cast<std::uint8_t>(level);
          p[0] = p[1] = p[2] = v;
          p[3] = 255;
        }
      glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
      glTextureSubImage2D(texture.id(), 0, 0, 0, w, h, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
    }
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glDisable(GL_FRAMEBUFFER_SRGB);
    glBlitNamedFramebuffer(framebuffer.id(), 0, 0, 0, w, h, 0, 0, w, h, GL_COLOR_BUFFER_BIT, GL_NEAREST);
    begin_corner_box("##match", {0.5f, 1.0f});
    ImGui::Text("Step back until the checkerboard (left) looks uniform. Grey level %d (gamma %.3f).", level,
                std::log(0.5) / std::log(level / 255.0));
    ImGui::Text("Up/Down: change the grey until both halves look equally bright (Page Up/Down: by 10). Enter: accept. Escape: stop.");
    ImGui::End();
    window.end_frame();
    window.swap();
    if (level != uploaded) say("grey level " + std::to_string(level));  // on screen now
    uploaded = level;
  }
}

}  // namespace penumbra::study_gui
