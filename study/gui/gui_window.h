#pragma once
// Windows of the study app: each GLFW window has its own OpenGL context and its own Dear ImGui
// context, so the participant view and the admin view can live on two monitors. GLFW delivers
// every window's input during one glfwPollEvents(); the callbacks here route each event to the
// ImGui context of the window it belongs to (ImGui's GLFW backend alone assumes one window).
#include <string>
#include <vector>

#include "io/image_io.h"

struct GLFWwindow;
struct GLFWmonitor;
struct ImFont;
struct ImGuiContext;

namespace penumbra::study_gui {

// GLFW's lifetime: one per process, outliving every GuiWindow.
class Glfw {
 public:
  Glfw();  // throws "cannot start GLFW: ... (is DISPLAY set? try xvfb-run)"
  ~Glfw();
  Glfw(const Glfw&) = delete;
  Glfw& operator=(const Glfw&) = delete;
  std::vector<GLFWmonitor*> monitors() const;
  // Blocks until an event arrives or `seconds` pass (0: returns at once).
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
  float font_px = 18;       // body text
  float large_font_px = 0;  // a second, larger font (0: none)
  float small_font_px = 0;  // a third, smaller one (0: none)
};

// A key or mouse-button press with the time it was seen (glfwGetTime, in seconds).
struct Press {
  int key = -1;  // GLFW_KEY_*, or -1 for a mouse button
  int mouse_button = -1;
  double time_s = 0;
};

class GuiWindow {
 public:
  explicit GuiWindow(const WindowSpec& spec);  // throws with GLFW's message
  ~GuiWindow();
  GuiWindow(const GuiWindow&) = delete;
  GuiWindow& operator=(const GuiWindow&) = delete;

  GLFWwindow* window() const { return window_; }
  bool close_requested() const;
  // Makes this window's GL and ImGui contexts current (begin_frame does it too).
  void make_current() const;
  // Makes this window's GL and ImGui contexts current and starts an ImGui frame.
  void begin_frame();
  // Renders the ImGui frame over the default framebuffer; the back buffer then holds the whole
  // frame until swap().
  void end_frame();
  void swap();
  // Physical framebuffer pixels (what the stimuli are placed in) and the ImGui coordinate scale.
  void framebuffer_size(int& width, int& height) const;
  float framebuffer_scale() const;
  // The back buffer as RGBA, top row first (between end_frame and swap).
  io::Image8 read_back() const;
  // Presses since the last call, oldest first (GLFW key repeats are not presses).
  std::vector<Press> take_presses();
  ImFont* body_font() const { return body_font_; }
  ImFont* large_font() const { return large_font_; }
  ImFont* small_font() const { return small_font_; }

 private:
  static void on_key(GLFWwindow* w, int key, int scancode, int action, int mods);
  static void on_char(GLFWwindow* w, unsigned int c);
  static void on_mouse_button(GLFWwindow* w, int button, int action, int mods);
  static void on_scroll(GLFWwindow* w, double dx, double dy);
  static void on_cursor_enter(GLFWwindow* w, int entered);
  static void on_focus(GLFWwindow* w, int focused);

  GLFWwindow* window_ = nullptr;
  ImGuiContext* imgui_ = nullptr;
  ImFont* body_font_ = nullptr;
  ImFont* large_font_ = nullptr;
  ImFont* small_font_ = nullptr;
  std::vector<Press> presses_;
};

}  // namespace penumbra::study_gui
