// penumbra-view: the renderer in a window. Orbit with the left mouse button, zoom with the wheel;
// the panel edits the technique's parameters (from the same tables as the CLI) and shows the
// fitted light frame, per-pass times and the shadow map, and (the sun) the virtual shadow map's
// debug views: the level each pixel samples by the rule and by the footprint, and its page pool.
#include <epoxy/gl.h>
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <CLI/CLI.hpp>
#include <imgui.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>

#include <glm/gtc/constants.hpp>

#include "apps/cli_options.h"
#include "apps/virtual_debug.h"
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

// The panel's view of the sun's virtual shadow map: refreshed every few frames (marking reads the
// surface back; the pool image reads the pool), kept across frames so that the pool shows which
// pages the camera's move drew (green) and which it kept (blue).
struct VirtualPanel {
  std::unique_ptr<apps::VirtualDebug> debug;
  gl::Texture rule_tex, footprint_tex, pool_tex;
  apps::VirtualDebug::View last;
  std::string problem;

  static void upload(gl::Texture& t, const io::Image8& img) {
    if (t.id() == 0 || t.desc().width != img.width || t.desc().height != img.height)
      t = gl::Texture({GL_RGB8, img.width, img.height, 1}, "virtual debug view");
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glTextureSubImage2D(t.id(), 0, 0, 0, img.width, img.height, GL_RGB, GL_UNSIGNED_BYTE, img.pixels.data());
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
  }
  void refresh(const scene::Scene& scene, const shadows::ShadowSettings& s, int width, int height) {
    const apps::VirtualMarking marking = apps::virtual_marking(s, scene.light);
    problem = scene.light.type != scene::Light::Type::directional ? "the virtual map is the sun's; this scene has a spot light"
                                                                    : marking.problem;
    if (!problem.empty()) return;
    if (!debug) debug = std::make_unique<apps::VirtualDebug>(scene);
    last = debug->view(scene, scene.camera, width, height, marking);
    upload(rule_tex, last.rule_levels);
    upload(footprint_tex, last.footprint_levels);
    upload(pool_tex, apps::pool_image(debug->map(), 256));
  }
  void draw() const {
    if (!problem.empty()) {
      ImGui::TextWrapped("virtual map: %s", problem.c_str());
      return;
    }
    if (!debug) return;
    ImGui::Text("pages: %zu by the rule, %zu by the footprint", last.rule.pages.size(), last.footprint.pages.size());
    ImGui::Text("pool: %d drawn, %d kept, %d missing, %d resident", last.stats.drawn, last.stats.cached, last.stats.missing,
                last.stats.resident);
    const auto id = [](const gl::Texture& t) { return reinterpret_cast<ImTextureID>(static_cast<std::intptr_t>(t.id())); };
    const float w = 200, h = w * static_cast<float>(rule_tex.desc().height) / static_cast<float>(std::max(rule_tex.desc().width, 1));
    ImGui::Image(id(rule_tex), {w, h});
    ImGui::SameLine();
    ImGui::Image(id(footprint_tex), {w, h});
    ImGui::Text("level per pixel: rule | footprint");
    ImGui::Image(id(pool_tex), {200, 200});
    ImGui::Text("pool: green drawn, blue kept, dark red free");
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
  bool virtual_debug = false;
  app.add_flag("--virtual-debug", virtual_debug, "open with the virtual shadow map's debug views shown (the panel's checkbox)");
  apps::add_calibration_option(app, calibration);
  shadows::ShadowSettings settings;  // the panel's starting values
  apps::add_settings_options(app, settings);
  if (const auto status = cli::parse(app, argc, argv, "penumbra-view")) return *status;
  try {
    apps::apply_calibration(app, calibration, settings);
    std::printf("%s\n", apps::calibration_line(calibration, settings).c_str());
    apps::CalibrationFollower follower;  // the panel's technique switch picks that technique's c
    gui::SettingsUndo undo;  // a panel change the view cannot draw is undone, and said in the panel
    scene::Scene scene = scene::load_scene(scene_arg);
    gl::Glfw glfw;
    gl::Window window({.title = "Penumbra — " + scene.name, .width = width, .height = height, .gl_errors_throw = gl::kDebugBuild});
    shadows::Renderer renderer;
    renderer.set_scene(scene);
    Orbit orbit;
    orbit.from_camera(scene.camera);
    gl::PassTimer timer(!window.info().software);
    bool show_map = true;
    VirtualPanel virtual_panel;
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
      shadows::FrameInfo info;
      undo.render(settings, [&](shadows::ShadowSettings& s) {
        follower.update(calibration, s);
        info = renderer.render(gui::drawable_settings(s, renderer.scene()), std::max(fb_w, 1), std::max(fb_h, 1), &timer);
      });
      renderer.present(0, fb_w, fb_h);

      ImGui::SetNextWindowPos({10, 10}, ImGuiCond_FirstUseEver);
      ImGui::SetNextWindowSize({430, 0}, ImGuiCond_FirstUseEver);
      ImGui::Begin("Penumbra");
      ImGui::PushItemWidth(200);
      ImGui::Text("%s | %s", scene.name.c_str(), window.info().renderer.c_str());
      ImGui::Text("%s", apps::calibration_line(calibration, settings).c_str());
      gui::shadow_settings_panel(settings);
      undo.line();
    gui::virtual_pages_line(settings, renderer.scene(), info);
      gui::light_size_control(renderer.scene().light);
      ImGui::Separator();
      if (!info.virtual_map)  // the pages have their own line above
        ImGui::Text("map %d^2, %s, s_xy %.2f, extent %.2f ws", info.resolution_texels, info.light.fitted ? "fitted" : "unfitted",
                    info.light.s_xy, info.light.extent_ws);
      for (const auto& st : timer.stats())
        ImGui::Text("%-10s %7.2f ms (%s)", st.pass.c_str(), st.median_ms, gl::to_string(st.method));
      ImGui::Checkbox("show shadow map", &show_map);
      if (show_map && renderer.shadow_map_texture())
        ImGui::Image(reinterpret_cast<ImTextureID>(static_cast<std::intptr_t>(renderer.shadow_map_texture())), {200, 200}, {0, 1}, {1, 0});
      ImGui::Checkbox("virtual shadow map (sun)", &virtual_debug);
      ImGui::PopItemWidth();
      ImGui::End();
      if (virtual_debug) {  // its own window, top right
        if (frame % 10 == 0 || !virtual_panel.problem.empty() || virtual_panel.last.rule_levels.pixels.empty())
          virtual_panel.refresh(renderer.scene(), settings, std::max(fb_w / 4, 16), std::max(fb_h / 4, 9));
        ImGui::SetNextWindowPos({static_cast<float>(fb_w) / window.framebuffer_scale() - 440, 10}, ImGuiCond_FirstUseEver);
        ImGui::SetNextWindowSize({430, 0}, ImGuiCond_FirstUseEver);
        ImGui::Begin("Virtual shadow map");
        virtual_panel.draw();
        ImGui::End();
      }
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
