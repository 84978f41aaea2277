#pragma once
// A windowed OpenGL 4.5 core context through GLFW, with Dear ImGui set up on it. The renderer
// code is the same as headless: it draws into its own framebuffers, and the window shows them.
#include <string>

#include "gl/context.h"
#include "image/image.h"

struct GLFWwindow;

namespace penumbra::gl {

// The current context's default framebuffer's back buffer (width × height) as RGBA, top row
// first: between drawing the UI and swapping, the frame as shown.
image::Image8 read_back_buffer(int width, int height);

class WindowContext {
 public:
  // Throws std::runtime_error with GLFW's message if no window can be opened (e.g. no display).
  WindowContext(int width, int height, const std::string& title);
  ~WindowContext();
  WindowContext(const WindowContext&) = delete;
  WindowContext& operator=(const WindowContext&) = delete;

  const ContextInfo& info() const { return info_; }
  GLFWwindow* window() const { return window_; }
  bool should_close() const;
  // Polls events and starts an ImGui frame.
  void begin_frame();
  // Renders ImGui on top of the default framebuffer; `swap` then shows the frame. Between the two
  // the back buffer holds the complete frame (for screenshots).
  void render_ui();
  void swap();
  void framebuffer_size(int& width, int& height) const;
  // The back buffer as RGBA, top row first: between render_ui and swap, the frame with its panel.
  image::Image8 read_back() const;

 private:
  GLFWwindow* window_ = nullptr;
  ContextInfo info_;
};

}  // namespace penumbra::gl
