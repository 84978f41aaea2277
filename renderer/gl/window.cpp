#include "gl/window.h"

#include <epoxy/gl.h>
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <vector>

#include <imgui.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>

namespace penumbra::gl {
namespace {
std::string g_glfw_error;
void on_glfw_error(int, const char* message) { g_glfw_error = message; }
}  // namespace

WindowContext::WindowContext(int width, int height, const std::string& title) {
  glfwSetErrorCallback(on_glfw_error);
  if (!glfwInit()) throw std::runtime_error("cannot start GLFW: " + g_glfw_error + " (is DISPLAY set? try xvfb-run)");
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 4);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 5);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
#ifndef NDEBUG
  glfwWindowHint(GLFW_OPENGL_DEBUG_CONTEXT, GLFW_TRUE);
#endif
  window_ = glfwCreateWindow(width, height, title.c_str(), nullptr, nullptr);
  if (!window_) {
    glfwTerminate();
    throw std::runtime_error("cannot open an OpenGL 4.5 core window: " + g_glfw_error);
  }
  glfwMakeContextCurrent(window_);
  glfwSwapInterval(0);
#ifndef NDEBUG
  install_debug_output(true);
#else
  install_debug_output(false);
#endif
  info_ = query_context_info("glfw");
  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGui::GetIO().IniFilename = nullptr;  // no imgui.ini littered into the working directory
  ImGui::StyleColorsDark();
  ImGui_ImplGlfw_InitForOpenGL(window_, true);
  ImGui_ImplOpenGL3_Init("#version 450 core");
}

WindowContext::~WindowContext() {
  ImGui_ImplOpenGL3_Shutdown();
  ImGui_ImplGlfw_Shutdown();
  ImGui::DestroyContext();
  glfwDestroyWindow(window_);
  glfwTerminate();
}

bool WindowContext::should_close() const { return glfwWindowShouldClose(window_) != 0; }

void WindowContext::begin_frame() {
  glfwPollEvents();
  ImGui_ImplOpenGL3_NewFrame();
  ImGui_ImplGlfw_NewFrame();
  ImGui::NewFrame();
}

void WindowContext::render_ui() {
  ImGui::Render();
  int w = 0, h = 0;
  framebuffer_size(w, h);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  glViewport(0, 0, w, h);
  ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
}

void WindowContext::swap() { glfwSwapBuffers(window_); }

void WindowContext::framebuffer_size(int& width, int& height) const { glfwGetFramebufferSize(window_, &width, &height); }

image::Image8 WindowContext::read_back() const {
  int w = 0, h = 0;
  framebuffer_size(w, h);
  return read_back_buffer(w, h);
}

image::Image8 read_back_buffer(int w, int h) {
  image::Image8 shot{w, h, 4, std::vector<std::uint8_t>(static_cast<std::size_t>(w) * h * 4)};
  glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
  glReadBuffer(GL_BACK);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, w, h, GL_RGBA, GL_UNSIGNED_BYTE, shot.pixels.data());
  image::flip_vertical(shot);
  return shot;
}

}  // namespace penumbra::gl
