#pragma once
// Windows through GLFW, each with its own OpenGL 4.5 core context and its own Dear ImGui context:
// the renderer apps open one (the renderer draws into its own framebuffers, the window shows
// them), the study app two (the participant view and the admin view, on two monitors). GLFW
// delivers every window's input during one glfwPollEvents(); the callbacks here route each event
// to the ImGui context of the window it belongs to (ImGui's GLFW backend alone assumes one window).
#include <string>
#include <utility>
#include <vector>

#include "gl/context.h"
#include "gl/input_trickle.h"
#include "image/image.h"

struct GLFWwindow;
struct GLFWmonitor;
struct ImFont;
struct ImGuiContext;

namespace penumbra::gl {

#ifdef NDEBUG
inline constexpr bool kDebugBuild = false;
#else
inline constexpr bool kDebugBuild = true;
#endif

// GLFW's lifetime: one per process, outliving every Window.
class Glfw {
 public:
  Glfw();  // throws "cannot start GLFW: ... (is DISPLAY set? try xvfb-run)"
  ~Glfw();
  Glfw(const Glfw&) = delete;
  Glfw& operator=(const Glfw&) = delete;
  std::vector<GLFWmonitor*> monitors() const;
  // Blocks until an event arrives or `seconds` pass (0: polls the pending events and returns).
  void wait_events(double seconds) const;
  double now_s() const;
};

struct WindowSpec {
  std::string title;
  int width = 1280, height = 720;  // windowed size (screen coordinates)
  GLFWmonitor* fullscreen_on = nullptr;  // full screen at the monitor's current video mode
  int x = -1, y = -1;                    // windowed position; -1: where the system puts it
  bool vsync = false;
  bool focused = true;  // take the keyboard focus when opened
  // A GL debug context whose errors throw from check_errors() (the renderer apps' debug builds);
  // otherwise GL errors are printed once each.
  bool gl_errors_throw = false;
  float font_px = 0;        // body text in DejaVu Sans (0: ImGui's built-in font)
  float large_font_px = 0;  // a second, larger font (0: none)
  float small_font_px = 0;  // a third, smaller one (0: none)
  // The characters the fonts hold, as inclusive ranges (empty: ImGui's default, Basic Latin and
  // Latin-1). Code points above U+FFFF are cut to ImGui's 16-bit characters.
  std::vector<std::pair<char32_t, char32_t>> glyph_ranges;
};

// A key or mouse-button press with the time it was seen (glfwGetTime, in seconds).
struct Press {
  int key = -1;  // GLFW_KEY_*, or -1 for a mouse button
  int mouse_button = -1;
  double time_s = 0;
};

class Window {
 public:
  // Needs a Glfw; throws std::runtime_error with GLFW's message if no window can be opened.
  explicit Window(const WindowSpec& spec);
  ~Window();
  Window(const Window&) = delete;
  Window& operator=(const Window&) = delete;

  const ContextInfo& info() const { return info_; }
  GLFWwindow* window() const { return window_; }
  bool should_close() const;
  // Makes this window's GL and ImGui contexts current (begin_frame does it too).
  void make_current() const;
  // Makes this window's GL and ImGui contexts current and starts an ImGui frame. Events are
  // polled by Glfw::wait_events, before.
  void begin_frame();
  // Renders the ImGui frame over the default framebuffer; the back buffer then holds the whole
  // frame (for screenshots) until swap().
  void end_frame();
  void swap();
  // Physical framebuffer pixels (what the stimuli are placed in) and the ImGui coordinate scale.
  void framebuffer_size(int& width, int& height) const;
  float framebuffer_scale() const;
  // The back buffer as RGBA, top row first (between end_frame and swap).
  image::Image8 read_back() const;
  // Presses since the last call, oldest first (GLFW key repeats are not presses).
  std::vector<Press> take_presses();
  ImFont* body_font() const { return body_font_; }  // null with ImGui's built-in font
  ImFont* large_font() const { return large_font_; }
  ImFont* small_font() const { return small_font_; }

 private:
  static void on_key(GLFWwindow* w, int key, int scancode, int action, int mods);
  static void on_char(GLFWwindow* w, unsigned int c);
  static void on_mouse_button(GLFWwindow* w, int button, int action, int mods);
  static void on_scroll(GLFWwindow* w, double dx, double dy);
  static void on_cursor_enter(GLFWwindow* w, int entered);
  static void on_focus(GLFWwindow* w, int focused);
  ImFont* add_font(float px);

  GLFWwindow* window_ = nullptr;
  ContextInfo info_;
  ImGuiContext* imgui_ = nullptr;
  std::vector<unsigned short> glyph_ranges_;  // ImGui's zero-terminated list; lives as long as the fonts
  ImFont* body_font_ = nullptr;
  ImFont* large_font_ = nullptr;
  ImFont* small_font_ = nullptr;
  std::vector<Press> presses_;
  InputTrickle keyboard_;  // keys and text for ImGui, spread over frames so that none is lost
};

}  // namespace penumbra::gl
