// penumbra-view: the renderer in a window. Orbit with the left mouse button, zoom with the wheel;
// the panel edits the technique's parameters (from the same tables as the CLI) and shows the
// fitted light frame, per-pass times and the shadow map.
#include <epoxy/gl.h>
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <CLI/CLI.hpp>
#include <imgui.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>

#include <glm/gtc/constants.hpp>

#include "apps/cli_options.h"
#include "cli/main.h"
#include "gl/timer.h"
#include "gl/window.h"
#include "gui/settings_panel.h"
#include "io/image_io.h"
#include "scene/scene.h"
#include "shadows/renderer.h"

using namespace penumbra;

namespace {

// Orbit camera around the scene camera's target.
struct Orbit {
  float yaw = 0, pitch = 0.4f, distance = 10;
  void from_camera(const scene::Camera& c) {
    const glm::vec3 d = c.position - c.target;
    distance = glm::length(d);
    pitch = std::asin(std::clamp(d.y / distance, -1.0f, 1.0f));
    yaw = std::atan2(d.x, d.z);
  }
  void apply(scene::Camera& c) const {
    c.position = c.target + distance * glm::vec3(std::cos(pitch) * std::sin(yaw), std::sin(pitch), std::cos(pitch) * std::cos(yaw));
  }
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Interactive shadow viewer (GLFW + Dear ImGui)."};
  cli::describe_tool(app, "penumbra-view", "renderer.md");
  std::string scene_arg = "demo", screenshot;
  int width = 1280, height = 720, frames = 0;
  apps::CalibrationOption calibration;
  app.add_option("--scene", scene_arg, "built-in scene name or scene file (.json)");
  app.add_option("--width", width, "window width")->check(CLI::Range(64, 8192));
  app.add_option("--height", height, "window height")->check(CLI::Range(64, 8192));
  app.add_option("--screenshot", screenshot, "write the window (with the panel) to this PNG after --frames frames, then exit");
  app.add_option("--frames", frames, "frames to run before --screenshot (0: run until closed)")->check(CLI::Range(0, 1000000));
  apps::add_calibration_option(app, calibration);
  if (const auto status = cli::parse(app, argc, argv, "penumbra-view")) return *status;
  try {
    shadows::ShadowSettings settings;
    apps::apply_calibration(app, calibration, settings);
    std::printf("%s\n", apps::calibration_line(calibration, settings).c_str());
    apps::CalibrationFollower follower;  // the panel's technique switch picks that technique's c
    scene::Scene scene = scene::load_scene(scene_arg);
    gl::Glfw glfw;
    gl::Window window({.title = "Penumbra — " + scene.name, .width = width, .height = height, .gl_errors_throw = gl::kDebugBuild});
    shadows::Renderer renderer;
    renderer.set_scene(scene);
    Orbit orbit;
    orbit.from_camera(scene.camera);
    gl::PassTimer timer(!window.info().software);
    bool show_map = true;
    int frame = 0;
    double last_x = 0, last_y = 0;
    while (!window.should_close()) {
      glfw.wait_events(0);
      window.begin_frame();
      ImGuiIO& io = ImGui::GetIO();
      if (!io.WantCaptureMouse) {
        double x, y;
        glfwGetCursorPos(window.window(), &x, &y);
        if (glfwGetMouseButton(window.window(), GLFW_MOUSE_BUTTON_LEFT) == GLFW_PRESS) {
          orbit.yaw -= static_cast<float>(x - last_x) * 0.005f;
          orbit.pitch = std::clamp(orbit.pitch + static_cast<float>(y - last_y) * 0.005f, 0.05f, 1.5f);
        }
        orbit.distance = std::clamp(orbit.distance * std::pow(0.9f, io.MouseWheel), 0.5f, 200.0f);
        last_x = x, last_y = y;
      }
      orbit.apply(renderer.scene().camera);

      int fb_w = 0, fb_h = 0;
      window.framebuffer_size(fb_w, fb_h);
      if (frame % 30 == 0) timer.clear();
      follower.update(calibration, settings);
      const shadows::FrameInfo info = renderer.render(settings, std::max(fb_w, 1), std::max(fb_h, 1), &timer);
      renderer.present(0, fb_w, fb_h);

      ImGui::SetNextWindowPos({10, 10}, ImGuiCond_FirstUseEver);
      ImGui::SetNextWindowSize({430, 0}, ImGuiCond_FirstUseEver);
      ImGui::Begin("Penumbra");
      ImGui::PushItemWidth(200);
      ImGui::Text("%s | %s", scene.name.c_str(), window.info().renderer.c_str());
      ImGui::Text("%s", apps::calibration_line(calibration, settings).c_str());
      gui::shadow_settings_panel(settings);
      gui::light_size_control(renderer.scene().light);
      ImGui::Separator();
      ImGui::Text("map %d^2, %s, s_xy %.2f, extent %.2f ws", info.resolution_texels, info.light.fitted ? "fitted" : "unfitted",
                  info.light.s_xy, info.light.extent_ws);
      for (const auto& st : timer.stats())
        ImGui::Text("%-10s %7.2f ms (%s)", st.pass.c_str(), st.median_ms, gl::to_string(st.method));
      ImGui::Checkbox("show shadow map", &show_map);
      if (show_map && renderer.shadow_map_texture())
        ImGui::Image(reinterpret_cast<ImTextureID>(static_cast<std::intptr_t>(renderer.shadow_map_texture())), {200, 200}, {0, 1}, {1, 0});
      ImGui::PopItemWidth();
      ImGui::End();
      window.end_frame();
      ++frame;
      if (!screenshot.empty() && frame >= std::max(frames, 2)) {
        io::write_png(screenshot, window.read_back());
        break;
      }
      window.swap();
      if (frames > 0 && screenshot.empty() && frame >= frames) break;
    }
    return 0;
  } catch (const std::exception& e) {
    return cli::fail("penumbra-view", e);
  }
}
