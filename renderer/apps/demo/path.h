#pragma once
// The frames penumbra-demo visits. A scene with a camera path (the outdoor town) is walked along
// it: `short` visits stations of three consecutive frames spread evenly over the whole path (the
// street, the site, the climb, the overview), `full` every frame; a scene without one is orbited
// (orbit_camera) over --frames frames. Flicker is measured only between consecutive frames; the
// error against the reference at each station's middle frame (every 30th frame of a full path,
// the orbit's middle frame).
#include <string>
#include <vector>

#include "scene/scene.h"

namespace penumbra::demo {

struct PathFrame {
  int frame = 0;           // frame of the scene's camera path, or of the orbit
  bool continues = false;  // the frame visited before it is frame - 1
  bool reference = false;  // measured against the reference here
};

struct PathPlan {
  std::string kind;  // "orbit", "short" or "full"
  int length = 0;    // frames of the whole path
  std::vector<PathFrame> frames;
};

// `path`: "short" or "full" (scenes with a camera path); `frames`: of the short path or the orbit.
PathPlan plan_path(const scene::Scene& scene, const std::string& path, int frames);

// The orbit of a scene without a camera path: a quarter orbit around the scene camera's target
// while zooming in to 60 % of the distance and back, at the scene camera's elevation.
scene::Camera orbit_camera(const scene::Camera& start, int i, int n);

// The camera at `frame` of the plan's path.
scene::Camera camera_at(const scene::Scene& scene, const PathPlan& plan, int frame);

}  // namespace penumbra::demo
