#include "apps/demo/path.h"

#include <algorithm>
#include <cmath>

#include <glm/gtc/constants.hpp>

namespace penumbra::demo {

scene::Camera orbit_camera(const scene::Camera& start, int i, int n) {
  scene::Camera c = start;
  const glm::vec3 d = start.position - start.target;
  const float distance = glm::length(d);
  const float pitch = std::asin(std::clamp(d.y / std::max(distance, 1e-6f), -1.0f, 1.0f));
  const float t = n > 1 ? static_cast<float>(i) / static_cast<float>(n - 1) : 0.0f;
  const float yaw = std::atan2(d.x, d.z) + glm::radians(90.0f) * (t - 0.5f);
  const float r = distance * (1.0f - 0.4f * std::sin(glm::pi<float>() * t));
  c.position = c.target + r * glm::vec3(std::cos(pitch) * std::sin(yaw), std::sin(pitch), std::cos(pitch) * std::cos(yaw));
  return c;
}

PathPlan plan_path(const scene::Scene& scene, const std::string& path, int frames) {
  PathPlan p;
  if (scene.camera_path.empty()) {
    p.kind = "orbit";
    p.length = frames;
    for (int i = 0; i < frames; ++i) p.frames.push_back({i, i > 0, i == frames / 2});
    return p;
  }
  p.length = scene.camera_path.frames();
  if (path == "full") {
    p.kind = "full";
    const int every = std::min(30, p.length);
    for (int i = 0; i < p.length; ++i) p.frames.push_back({i, i > 0, i % every == every / 2});
    return p;
  }
  p.kind = "short";
  const int per_station = std::min({3, frames, p.length});
  const int stations = std::max(1, frames / per_station);
  for (int s = 0; s < stations; ++s) {
    const int span = p.length - per_station;
    const int start = stations == 1 ? span / 2 : static_cast<int>(std::lround(static_cast<double>(s) * span / (stations - 1)));
    for (int j = 0; j < per_station; ++j) p.frames.push_back({start + j, j > 0, j == per_station / 2});
  }
  return p;
}

scene::Camera camera_at(const scene::Scene& scene, const PathPlan& plan, int frame) {
  return plan.kind == "orbit" ? orbit_camera(scene.camera, frame, plan.length) : scene.camera_path.at(scene.camera, frame);
}

}  // namespace penumbra::demo
