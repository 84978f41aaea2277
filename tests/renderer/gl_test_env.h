#pragma once
// One headless OpenGL context per test binary, plus helpers shared by the GL tests.
#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <memory>
#include <vector>

#include <glm/glm.hpp>

#include "gl/context.h"
#include "io/image_io.h"
#include "scene/scene.h"
#include "shadows/renderer.h"
#include "shadows/settings.h"

namespace penumbra::test {

class GlEnvironment : public ::testing::Environment {
 public:
  void SetUp() override { context_ = std::make_unique<gl::HeadlessContext>(); }
  void TearDown() override { context_.reset(); }
  static const gl::ContextInfo& info() { return context_->info(); }

 private:
  static inline std::unique_ptr<gl::HeadlessContext> context_;
};

// Every pixel finite and inside [lo, hi].
inline ::testing::AssertionResult all_finite_in(const io::ImageF& img, float lo, float hi) {
  for (std::size_t i = 0; i < img.pixels.size(); ++i) {
    const float v = img.pixels[i];
    if (!std::isfinite(v) || v < lo || v > hi)
      return ::testing::AssertionFailure() << "pixel " << i << " = " << v << " outside [" << lo << ", " << hi << "]";
  }
  return ::testing::AssertionSuccess();
}

// Top-down orthographic camera over world x in [centre.x ± half] (image x = world x, image row =
// world z) for an image of aspect width / height, seeing only y < max_y: the receiver, not the
// occluders above it.
inline void look_down(scene::Scene& s, glm::vec2 centre, float half, float max_y = 0.5f, float aspect = 1.0f) {
  s.camera.projection = scene::Camera::Projection::orthographic;
  s.camera.position = {centre.x, 20, centre.y};
  s.camera.target = {centre.x, 0, centre.y};
  s.camera.up = {0, 0, -1};
  s.camera.ortho_height_ws = 2 * half / aspect;
  s.camera.near_ws = 20 - max_y;
  s.camera.far_ws = 40;
}

// World x (or z) of pixel column (or row) i in an n-pixel top-down view of width 2·half.
inline float pixel_to_world(int i, int n, float centre, float half) {
  return centre - half + (static_cast<float>(i) + 0.5f) * 2 * half / static_cast<float>(n);
}

// Default settings with a technique, a resolution and fitting on or off.
inline shadows::ShadowSettings settings(shadows::Technique t, int resolution, bool fit) {
  shadows::ShadowSettings s;
  s.technique = t;
  s.map.resolution_texels = resolution;
  s.map.fit = fit;
  return s;
}

// The light visibility of one n x n frame of `s` with settings `st`, from a fresh renderer.
inline io::ImageF render_visibility(const scene::Scene& s, const shadows::ShadowSettings& st, int n) {
  shadows::Renderer r;
  r.set_scene(s);
  r.render(st, n, n);
  return r.read_visibility();
}

// Column means of rows [y0, y1) of a one-channel image.
inline std::vector<double> column_means(const io::ImageF& img, int y0, int y1) {
  std::vector<double> m(static_cast<std::size_t>(img.width), 0.0);
  for (int y = y0; y < y1; ++y)
    for (int x = 0; x < img.width; ++x) m[static_cast<std::size_t>(x)] += img.at(x, y);
  for (auto& v : m) v /= (y1 - y0);
  return m;
}

// Position where an increasing profile first crosses `level` (linear interpolation between pixel
// centres), for profile pixel i at x0 + (i + 0.5) * ws_per_px; NaN when it never does.
inline double crossing(const std::vector<double>& p, double level, double x0, double ws_per_px) {
  for (std::size_t i = 1; i < p.size(); ++i)
    if (p[i - 1] < level && p[i] >= level)
      return x0 + ws_per_px * (static_cast<double>(i - 1) + 0.5 + (level - p[i - 1]) / (p[i] - p[i - 1]));
  return NAN;
}

}  // namespace penumbra::test
