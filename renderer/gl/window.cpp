#include "gl/window.h"

#include <epoxy/gl.h>
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <type_traits>
#include <utility>

#include <imgui.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>

namespace penumbra::gl {

namespace {

std::string g_glfw_error;
void on_glfw_error(int, const char* message) { g_glfw_error = message; }

const char* kFont = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";  // fonts-dejavu-core

static_assert(std::is_same_v<ImWchar, unsigned short>, "Window::glyph_ranges_ holds ImGui's 16-bit characters");

}  // namespace

Glfw::Glfw() {
  glfwSetErrorCallback(on_glfw_error);
  if (!glfwInit()) throw std::runtime_error("cannot start GLFW: " + g_glfw_error + " (is DISPLAY set? try xvfb-run)");
}

Glfw::~Glfw() { glfwTerminate(); }

std::vector<GLFWmonitor*> Glfw::monitors() const {
  int n = 0;
  GLFWmonitor** m = glfwGetMonitors(&n);
  return std::vector<GLFWmonitor*>(m, m + n);
}

void Glfw::wait_events(double seconds) const {
  if (seconds > 0) glfwWaitEventsTimeout(seconds);
  else glfwPollEvents();
}

double Glfw::now_s() const { return glfwGetTime(); }

Window::Window(const WindowSpec& spec) {
  glfwDefaultWindowHints();
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 4);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 5);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  if (spec.gl_errors_throw) glfwWindowHint(GLFW_OPENGL_DEBUG_CONTEXT, GLFW_TRUE);
  // Stimuli are placed in framebuffer pixels: no scaling of the window by the desktop's DPI.
  glfwWindowHint(GLFW_SCALE_TO_MONITOR, GLFW_FALSE);
  glfwWindowHint(GLFW_SRGB_CAPABLE, GLFW_FALSE);
  glfwWindowHint(GLFW_SAMPLES, 0);
  glfwWindowHint(GLFW_FOCUSED, spec.focused ? GLFW_TRUE : GLFW_FALSE);
  glfwWindowHint(GLFW_FOCUS_ON_SHOW, spec.focused ? GLFW_TRUE : GLFW_FALSE);
  int width = spec.width, height = spec.height;
  if (spec.fullscreen_on) {
    const GLFWvidmode* mode = glfwGetVideoMode(spec.fullscreen_on);
    width = mode->width;
    height = mode->height;
    glfwWindowHint(GLFW_REFRESH_RATE, mode->refreshRate);
    glfwWindowHint(GLFW_AUTO_ICONIFY, GLFW_FALSE);  // stays up when the admin clicks the other monitor
  } else if (spec.x >= 0) {
    glfwWindowHint(GLFW_VISIBLE, GLFW_FALSE);
  }
  window_ = glfwCreateWindow(width, height, spec.title.c_str(), spec.fullscreen_on, nullptr);
  if (!window_) throw std::runtime_error("cannot open an OpenGL 4.5 core window '" + spec.title + "': " + g_glfw_error);
  if (!spec.fullscreen_on && spec.x >= 0) {
    glfwSetWindowPos(window_, spec.x, spec.y);
    glfwShowWindow(window_);
  }
  glfwSetWindowUserPointer(window_, this);
  glfwMakeContextCurrent(window_);
  glfwSwapInterval(spec.vsync ? 1 : 0);
  install_debug_output(spec.gl_errors_throw);
  info_ = query_context_info("glfw");

  IMGUI_CHECKVERSION();
  imgui_ = ImGui::CreateContext();
  ImGui::SetCurrentContext(imgui_);
  ImGui::GetIO().IniFilename = nullptr;  // no imgui.ini littered into the working directory
  if (!spec.glyph_ranges.empty()) {
    for (const auto& [first, last] : spec.glyph_ranges) {
      glyph_ranges_.push_back(static_cast<ImWchar>(first));
      glyph_ranges_.push_back(static_cast<ImWchar>(last));
    }
    glyph_ranges_.push_back(0);
  }
  if (spec.font_px > 0) body_font_ = add_font(spec.font_px);
  if (spec.large_font_px > 0) large_font_ = add_font(spec.large_font_px);
  if (spec.small_font_px > 0) small_font_ = add_font(spec.small_font_px);
  // Our callbacks first; ImGui's are called from them with the right context current.
  glfwSetKeyCallback(window_, on_key);
  glfwSetCharCallback(window_, on_char);
  glfwSetMouseButtonCallback(window_, on_mouse_button);
  glfwSetScrollCallback(window_, on_scroll);
  glfwSetCursorEnterCallback(window_, on_cursor_enter);
  glfwSetWindowFocusCallback(window_, on_focus);
  ImGui_ImplGlfw_InitForOpenGL(window_, false);
  ImGui_ImplOpenGL3_Init("#version 450 core");
}

Window::~Window() {
  make_current();
  ImGui_ImplOpenGL3_Shutdown();
  ImGui_ImplGlfw_Shutdown();
  ImGui::DestroyContext(imgui_);
  glfwDestroyWindow(window_);
}

ImFont* Window::add_font(float px) {
  ImGuiIO& io = ImGui::GetIO();
  if (std::filesystem::exists(kFont))
    return io.Fonts->AddFontFromFileTTF(kFont, px, nullptr, glyph_ranges_.empty() ? nullptr : glyph_ranges_.data());
  ImFontConfig config;  // ImGui's built-in bitmap font, scaled: readable, if plain
  config.SizePixels = px;
  return io.Fonts->AddFontDefault(&config);
}

void Window::make_current() const {
  glfwMakeContextCurrent(window_);
  ImGui::SetCurrentContext(imgui_);
}

namespace {
// The ImGui context of the window an event belongs to, current for the event's duration.
class EventContext {
 public:
  explicit EventContext(ImGuiContext* ctx) : previous_(ImGui::GetCurrentContext()) { ImGui::SetCurrentContext(ctx); }
  ~EventContext() { ImGui::SetCurrentContext(previous_); }

 private:
  ImGuiContext* previous_;
};
Window& self(GLFWwindow* w) { return *static_cast<Window*>(glfwGetWindowUserPointer(w)); }
}  // namespace

void Window::on_key(GLFWwindow* w, int key, int /*scancode*/, int action, int /*mods*/) {
  Window& s = self(w);
  if (action == GLFW_PRESS) s.presses_.push_back({key, -1, glfwGetTime()});
  if (action != GLFW_REPEAT) s.keyboard_.key(key, action == GLFW_PRESS);  // ImGui makes its own repeats
}

void Window::on_char(GLFWwindow* w, unsigned int ch) { self(w).keyboard_.character(ch); }

void Window::on_mouse_button(GLFWwindow* w, int button, int action, int mods) {
  Window& s = self(w);
  if (action == GLFW_PRESS) s.presses_.push_back({-1, button, glfwGetTime()});
  EventContext c(s.imgui_);
  ImGui_ImplGlfw_MouseButtonCallback(w, button, action, mods);
}

void Window::on_scroll(GLFWwindow* w, double dx, double dy) {
  EventContext c(self(w).imgui_);
  ImGui_ImplGlfw_ScrollCallback(w, dx, dy);
}

void Window::on_cursor_enter(GLFWwindow* w, int entered) {
  EventContext c(self(w).imgui_);
  ImGui_ImplGlfw_CursorEnterCallback(w, entered);
}

void Window::on_focus(GLFWwindow* w, int focused) {
  EventContext c(self(w).imgui_);
  ImGui_ImplGlfw_WindowFocusCallback(w, focused);
}

bool Window::should_close() const { return glfwWindowShouldClose(window_) != 0; }

void Window::begin_frame() {
  make_current();
  for (const InputTrickle::Event& e : keyboard_.frame_starting()) {
    if (e.is_char) ImGui_ImplGlfw_CharCallback(window_, e.ch);
    else ImGui_ImplGlfw_KeyCallback(window_, e.key, 0, e.pressed ? GLFW_PRESS : GLFW_RELEASE, 0);
  }
  ImGui_ImplOpenGL3_NewFrame();
  ImGui_ImplGlfw_NewFrame();
  ImGui::NewFrame();
}

void Window::end_frame() {
  ImGui::Render();
  int w = 0, h = 0;
  framebuffer_size(w, h);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  glViewport(0, 0, w, h);
  ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
}

void Window::swap() { glfwSwapBuffers(window_); }

void Window::framebuffer_size(int& width, int& height) const { glfwGetFramebufferSize(window_, &width, &height); }

float Window::framebuffer_scale() const {
  int fw = 0, fh = 0, ww = 0, wh = 0;
  glfwGetFramebufferSize(window_, &fw, &fh);
  glfwGetWindowSize(window_, &ww, &wh);
  return ww > 0 ? static_cast<float>(fw) / static_cast<float>(ww) : 1.0f;
}

image::Image8 Window::read_back() const {
  int w = 0, h = 0;
  framebuffer_size(w, h);
  image::Image8 shot{w, h, 4, std::vector<std::uint8_t>(static_cast<std::size_t>(w) * h * 4)};
  glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
  glReadBuffer(GL_BACK);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, w, h, GL_RGBA, GL_UNSIGNED_BYTE, shot.pixels.data());
  image::flip_vertical(shot);
  return shot;
}

std::vector<Press> Window::take_presses() { return std::exchange(presses_, {}); }

}  // namespace penumbra::gl
