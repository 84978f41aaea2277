#include "metrics/ground_truth.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <numbers>
#include <stdexcept>

#include <epoxy/gl.h>

#include "sampling/random.h"
#if PENUMBRA_HAS_RAY_TRACING
#include "metrics/ray_traced.h"
#endif

namespace penumbra::metrics {
namespace {

int max_texture_size() {
  GLint size = 0;
  glGetIntegerv(GL_MAX_TEXTURE_SIZE, &size);
  return size;
}

// Renders `settings`, halving a map the device cannot allocate (down to 1024², then giving up).
// `note` gains a sentence for each step down.
shadows::FrameInfo render_with_fallback(shadows::Renderer& renderer, shadows::ShadowSettings& settings, int width_px,
                                        int height_px, std::string& note) {
  const int device_max = max_texture_size();
  if (settings.map.resolution_texels > device_max) {
    note += std::to_string(settings.map.resolution_texels) + "² exceeds GL_MAX_TEXTURE_SIZE " + std::to_string(device_max) +
            "; reference at " + std::to_string(device_max) + "². ";
    settings.map.resolution_texels = device_max;
  }
  for (;;) {
    try {
      return renderer.render(settings, width_px, height_px);
    } catch (const std::runtime_error& e) {
      const int res = settings.map.resolution_texels;
      if (std::string(e.what()).find("memory") == std::string::npos || res <= 1024) throw;
      note += std::to_string(res) + "² did not fit in device memory; reference at " + std::to_string(res / 2) + "². ";
      settings.map.resolution_texels = res / 2;
    }
  }
}

// "4096² maps" or "4 cascades of 4096²" (the renderer splits a directional light's view when asked).
std::string maps_of(const shadows::ShadowMapParams& map, int resolution_texels) {
  const std::string res = std::to_string(resolution_texels) + "²";
  return map.cascades > 1 ? std::to_string(map.cascades) + " cascades of " + res : res + " maps";
}

}  // namespace

std::string_view to_string(ReferenceKind k) { return k == ReferenceKind::area_light ? "area_light" : "same_filter"; }

ReferenceKind reference_kind(std::string_view technique_name) {
  return shadows::technique_entry(shadows::technique_from_string(technique_name)).reference;
}

glm::vec2 concentric_disk(glm::vec2 p) {
  if (p.x == 0 && p.y == 0) return {0, 0};
  constexpr float quarter_pi = std::numbers::pi_v<float> / 4;
  float r, phi;
  if (std::abs(p.x) > std::abs(p.y)) {
    r = p.x;
    phi = quarter_pi * (p.y / p.x);
  } else {
    r = p.y;
    phi = 2 * quarter_pi - quarter_pi * (p.x / p.y);
  }
  return {r * std::cos(phi), r * std::sin(phi)};
}

std::vector<glm::vec2> stratified_disk(int per_side) {
  if (per_side < 1) throw std::invalid_argument("stratified_disk: per_side must be at least 1, got " + std::to_string(per_side));
  sampling::Random random(0x5eed1e55u);
  auto unit = [&] { return static_cast<float>(random.uniform()); };  // [0, 1] once rounded to float
  std::vector<glm::vec2> points;
  points.reserve(static_cast<std::size_t>(per_side) * static_cast<std::size_t>(per_side));
  const float cell = 2.0f / static_cast<float>(per_side);
  for (int j = 0; j < per_side; ++j) {
    for (int i = 0; i < per_side; ++i) {
      const float x = -1 + (static_cast<float>(i) + unit()) * cell;
      const float y = -1 + (static_cast<float>(j) + unit()) * cell;
      points.push_back(concentric_disk({x, y}));
    }
  }
  return points;
}

scene::Light light_sample(const scene::Light& light, glm::vec2 uv) {
  scene::Light out = light;
  glm::vec3 e1, e2;
  scene::light_basis(light.direction, e1, e2);
  const glm::vec3 offset = uv.x * e1 + uv.y * e2;
  if (light.type == scene::Light::Type::directional) {
    const float tan_half = std::tan(glm::radians(std::max(light.size, 0.0f)) / 2);
    out.direction = glm::normalize(glm::normalize(light.direction) + tan_half * offset);
  } else {
    out.position = light.position + 0.5f * std::max(light.size, 0.0f) * offset;
  }
  out.size = 0;
  return out;
}

io::ImageF area_light_visibility(shadows::Renderer& renderer, int width_px, int height_px, int per_side,
                                 int resolution_texels, const shadows::ShadowMapParams& map) {
  const scene::Light original = renderer.scene().light;
  shadows::ShadowSettings hard;
  hard.technique = shadows::Technique::hard;
  hard.map = map;
  hard.map.resolution_texels = resolution_texels;
  hard.map.fit = true;
  std::vector<double> sum(static_cast<std::size_t>(width_px) * static_cast<std::size_t>(height_px), 0.0);
  const std::vector<glm::vec2> samples = stratified_disk(per_side);
  std::string ignored;
  try {
    for (const glm::vec2 uv : samples) {
      renderer.scene().light = light_sample(original, uv);
      render_with_fallback(renderer, hard, width_px, height_px, ignored);
      const io::ImageF v = renderer.read_visibility();
      for (std::size_t i = 0; i < sum.size(); ++i) sum[i] += v.pixels[i];
    }
  } catch (...) {
    renderer.scene().light = original;
    throw;
  }
  renderer.scene().light = original;
  io::ImageF out{width_px, height_px, 1, std::vector<float>(sum.size())};
  for (std::size_t i = 0; i < sum.size(); ++i) out.pixels[i] = static_cast<float>(sum[i] / static_cast<double>(samples.size()));
  return out;
}

Reference make_reference(shadows::Renderer& renderer, const shadows::ShadowSettings& settings, int width_px, int height_px,
                         const ReferenceOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  Reference ref;
  ref.kind = reference_kind(shadows::to_string(settings.technique));
  if (ref.kind == ReferenceKind::area_light) {
    if (options.area_samples < 1) throw std::invalid_argument("reference: area_samples must be at least 1");
    const int per_side = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(options.area_samples)) - 1e-9));
    ref.samples = per_side * per_side;
    const scene::Light& light = renderer.scene().light;
    char size[32];
    std::snprintf(size, sizeof size, "%g", static_cast<double>(light.size));
    const std::string emitter = light.type == scene::Light::Type::directional ? "sun disk of " + std::string(size) + " deg"
                                                                              : "spot emitter of width " + std::string(size);
#if PENUMBRA_HAS_RAY_TRACING
    if (options.ray_traced && light.type == scene::Light::Type::directional) {
      std::unique_ptr<RayTracedScene> built;
      if (!options.traced) built = std::make_unique<RayTracedScene>(renderer.scene());
      const RayTracedScene& traced = options.traced ? *options.traced : *built;
      ref.visibility = traced.area_light_visibility(renderer.scene().camera, light, width_px, height_px, per_side);
      ref.resolution_texels = 0;
      ref.ray_traced = true;
      ref.description = "ray-traced: " + std::to_string(ref.samples) + " shadow rays per pixel, stratified and jittered per pixel over the " +
                        emitter + " (Embree, no shadow map)";
      ref.render_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      return ref;
    }
#endif
    ref.resolution_texels = std::min(options.area_resolution_texels, max_texture_size());
    if (ref.resolution_texels < options.area_resolution_texels)
      ref.note = std::to_string(options.area_resolution_texels) + "² exceeds GL_MAX_TEXTURE_SIZE; maps at " +
                 std::to_string(ref.resolution_texels) + "². ";
    ref.visibility = area_light_visibility(renderer, width_px, height_px, per_side, ref.resolution_texels, settings.map);
    ref.description = "mean of " + std::to_string(ref.samples) + " hard shadows, point lights stratified over the " + emitter +
                      ", fitted " + maps_of(settings.map, ref.resolution_texels);
  } else {
    shadows::ShadowSettings s = settings;
    s.map.resolution_texels = options.filter_resolution_texels;
    render_with_fallback(renderer, s, width_px, height_px, ref.note);
    ref.resolution_texels = s.map.resolution_texels;
    ref.visibility = renderer.read_visibility();
    ref.description = shadows::describe(s) + " at " + maps_of(s.map, ref.resolution_texels);
  }
  if (!ref.note.empty() && ref.note.back() == ' ') ref.note.pop_back();
  ref.render_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return ref;
}

}  // namespace penumbra::metrics
