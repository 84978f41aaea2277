#include "apps/virtual_debug.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <iterator>
#include <stdexcept>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "metrics/surface_probe.h"
#include "shadows/frame_plan.h"
#include "shadows/technique.h"

namespace penumbra::apps {

namespace {

glm::vec3 level_colour(float level, int levels) {
  static const glm::vec3 kPalette[] = {{0.12f, 0.47f, 0.71f}, {1.0f, 0.5f, 0.05f},  {0.17f, 0.63f, 0.17f}, {0.84f, 0.15f, 0.16f},
                                       {0.58f, 0.4f, 0.74f},  {0.55f, 0.34f, 0.29f}, {0.89f, 0.47f, 0.76f}, {0.5f, 0.5f, 0.5f},
                                       {0.74f, 0.74f, 0.13f}, {0.09f, 0.75f, 0.81f}, {0.68f, 0.78f, 0.91f}, {1.0f, 0.73f, 0.47f}};
  if (level < 0) return glm::vec3(0);
  if (level >= static_cast<float>(levels)) return glm::vec3(1);
  return kPalette[static_cast<std::size_t>(level) % std::size(kPalette)];
}

void put(io::Image8& img, std::size_t pixel, const glm::vec3& c) {
  for (std::size_t k = 0; k < 3; ++k)
    img.pixels[3 * pixel + k] = static_cast<std::uint8_t>(std::lround(255 * std::clamp(c[static_cast<int>(k)], 0.0f, 1.0f)));
}

}  // namespace

VirtualMarking virtual_marking(const shadows::ShadowSettings& s, const scene::Light& light) {
  // Who marks and how, from the technique's registry entry (as the renderer's pass): the pages a
  // fixed filter of world radius reaches, or PCSS's two rounds.
  VirtualMarking m;
  m.problem = shadows::virtual_marking_unsupported(s);
  const shadows::TechniqueEntry& e = shadows::technique_entry(s.technique);
  if (e.pages == shadows::PageReading::blocker_search) {
    m.pcss = shadows::virtual_pcss(s, light.size);
  } else if (m.problem.empty()) {
    m.radius_ws = e.filter_radius(s).radius;
  }
  m.options = shadows::virtual_mark_options(s);
  m.options.marking = adaptive::Marking::rule;  // the views show the rule beside the footprint themselves
  return m;
}

io::Image8 level_image(const gl::Texture& levels_tex, int levels) {
  const int w = levels_tex.desc().width, h = levels_tex.desc().height;
  std::vector<float> v(static_cast<std::size_t>(w) * h);
  glGetTextureImage(levels_tex.id(), 0, GL_RED, GL_FLOAT, static_cast<GLsizei>(v.size() * sizeof(float)), v.data());
  io::Image8 img{w, h, 3, std::vector<std::uint8_t>(v.size() * 3)};
  for (std::size_t p = 0; p < v.size(); ++p) put(img, p, level_colour(v[p], levels));
  return img;
}

io::Image8 level_key(int levels, int width, int height) {
  io::Image8 img{width, height, 3, std::vector<std::uint8_t>(static_cast<std::size_t>(width) * height * 3)};
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      put(img, static_cast<std::size_t>(y) * width + x, y < height / 2 ? level_colour(static_cast<float>(x * levels / width), levels) : glm::vec3(0.1f));
  return img;
}

io::Image8 pool_image(const shadows::VirtualShadowMap& map, int max_side) {
  const int side = map.pool().desc().width;
  std::vector<float> depth(static_cast<std::size_t>(side) * side);
  glGetTextureImage(map.pool().id(), 0, GL_DEPTH_COMPONENT, GL_FLOAT, static_cast<GLsizei>(depth.size() * sizeof(float)), depth.data());
  const int step = std::max(1, (side + max_side - 1) / std::max(max_side, 1));
  const int out = side / step, page = map.layout().page_texels, per_side = map.pool_pages_per_side();
  const auto states = map.slot_states();
  // Depths stretched over the range the pages hold (the sun's depth range spans the whole town).
  float lo = 1, hi = 0;
  for (float d : depth)
    if (d < 1) lo = std::min(lo, d), hi = std::max(hi, d);
  const float range = hi > lo ? hi - lo : 1.0f;
  io::Image8 img{out, out, 3, std::vector<std::uint8_t>(static_cast<std::size_t>(out) * out * 3)};
  for (int y = 0; y < out; ++y)
    for (int x = 0; x < out; ++x) {
      const int tx = x * step, ty = y * step;  // the pool's texel; its row 0 is the image's bottom
      const int slot = (ty / page) * per_side + tx / page;
      const auto state = states[static_cast<std::size_t>(slot)];
      const float d = depth[static_cast<std::size_t>(ty) * side + tx];
      const float grey = 0.2f + 0.8f * (1.0f - std::clamp((d - lo) / range, 0.0f, 1.0f));  // near the sun: light
      const glm::vec3 tint = state == shadows::VirtualShadowMap::SlotState::drawn    ? glm::vec3(0.55f, 1.0f, 0.55f)
                             : state == shadows::VirtualShadowMap::SlotState::cached ? glm::vec3(0.55f, 0.7f, 1.0f)
                                                                                     : glm::vec3(0.25f, 0.05f, 0.05f);
      const bool border = tx % page < step || ty % page < step;  // slot outlines
      put(img, static_cast<std::size_t>(out - 1 - y) * out + x, border ? glm::vec3(0.05f) : state == shadows::VirtualShadowMap::SlotState::free ? tint : grey * tint);
    }
  return img;
}

struct VirtualDebug::State {
  adaptive::VirtualMapLayout layout;
  scene::GpuMeshes meshes;
  metrics::SurfaceProbe probe;
  shadows::VirtualMapView view;
  shadows::PageMarker marker{layout};
  shadows::VirtualShadowMap map{layout, 32};
  gl::Texture positions, levels;
  bool has_view = false;
  explicit State(const scene::Scene& scene) : meshes(scene.objects), probe(scene) {}
};

VirtualDebug::VirtualDebug(const scene::Scene& scene) {
  if (scene.light.type != scene::Light::Type::directional)
    throw std::runtime_error("virtual shadow map: it is the sun's; scene " + scene.name + " has a spot light");
  state_ = std::make_unique<State>(scene);
}

VirtualDebug::~VirtualDebug() = default;

const shadows::VirtualShadowMap& VirtualDebug::map() const { return state_->map; }
const adaptive::VirtualMapLayout& VirtualDebug::layout() const { return state_->layout; }

VirtualDebug::View VirtualDebug::view(const scene::Scene& scene, const scene::Camera& camera, int width, int height,
                                      const VirtualMarking& marking, bool images) {
  State& st = *state_;
  if (st.positions.id() == 0 || st.positions.desc().width != width || st.positions.desc().height != height) {
    st.positions = gl::Texture({GL_RGBA32F, width, height, 1}, "virtual debug surface");
    st.levels = gl::Texture({GL_R32F, width, height, 1}, "virtual debug levels");
  }
  st.probe.set_models(scene);
  const io::ImageF surface = st.probe.render(camera, width, height);
  glTextureSubImage2D(st.positions.id(), 0, 0, 0, width, height, GL_RGBA, GL_FLOAT, surface.pixels.data());
  // The light view follows the scene's light: a moved sun drops every page (update does). The
  // depth range is the maps' bounded region for this camera (shadows::sun_virtual_view).
  st.map.invalidate_moved_casters(scene);
  scene::Scene seen = scene;
  seen.camera = camera;
  st.view = shadows::sun_virtual_view(seen, static_cast<float>(width) / static_cast<float>(height), st.has_view ? &st.view : nullptr);
  st.has_view = true;
  adaptive::MarkOptions footprint = marking.options;
  footprint.marking = adaptive::Marking::footprint;
  const gl::Texture* levels = images ? &st.levels : nullptr;
  View v;
  if (marking.pcss) {
    // The renderer's two rounds: the searches' pages (one set for both markings: a search's level
    // is set by its radius and the pixel floor), then each marking's penumbra pages.
    const adaptive::MarkResult search = st.marker.mark_pcss_search(st.positions, camera, height, st.view, *marking.pcss, marking.options);
    const shadows::VirtualMapStats first = st.map.update(search.pages, st.view, scene, st.meshes);
    v.footprint = st.marker.mark_pcss_filter(st.positions, camera, height, st.map, *marking.pcss, footprint, levels);
    if (images) v.footprint_levels = level_image(st.levels, st.layout.levels);
    v.rule = st.marker.mark_pcss_filter(st.positions, camera, height, st.map, *marking.pcss, marking.options, levels);
    if (images) v.rule_levels = level_image(st.levels, st.layout.levels);
    v.rule.pages.insert(search.pages.begin(), search.pages.end());
    v.footprint.pages.insert(search.pages.begin(), search.pages.end());
    v.stats = st.map.update(v.rule.pages, st.view, scene, st.meshes);
    v.stats.drawn += first.drawn;  // the searches' pages drawn by the first round are this view's too
    v.stats.cached -= first.drawn;
    v.stats.evicted += first.evicted;
    return v;
  }
  v.footprint = st.marker.mark(st.positions, camera, height, st.view, marking.radius_ws, footprint, levels);
  if (images) v.footprint_levels = level_image(st.levels, st.layout.levels);
  v.rule = st.marker.mark(st.positions, camera, height, st.view, marking.radius_ws, marking.options, levels);
  if (images) v.rule_levels = level_image(st.levels, st.layout.levels);
  v.stats = st.map.update(v.rule.pages, st.view, scene, st.meshes);
  return v;
}

nlohmann::json write_virtual_debug(const scene::Scene& scene, const scene::Camera* previous, const scene::Camera& camera, int width,
                                   int height, const VirtualMarking& marking, const std::filesystem::path& dir) {
  VirtualDebug debug(scene);
  nlohmann::json out;
  if (previous)  // the pages the previous view drew: kept (cached) where this one asks for them too
    out["pages_previous"] = debug.view(scene, *previous, width, height, marking, false).rule.pages.size();
  VirtualDebug::View v = debug.view(scene, camera, width, height, marking);
  const int levels = debug.layout().levels;
  std::vector<io::Image8> images = {std::move(v.rule_levels), std::move(v.footprint_levels), level_key(levels, width, std::max(1, height / 4))};
  io::write_png(dir / "virtual-levels.png",
                io::montage(images,
                            {"rule: " + std::to_string(v.rule.pages.size()) + " pages",
                             "footprint: " + std::to_string(v.footprint.pages.size()) + " pages",
                             "key: levels 0-" + std::to_string(levels - 1) + ", fine to coarse"},
                            2, std::min(width, 640)));
  io::write_png(dir / "virtual-pool.png", pool_image(debug.map(), 1024));
  out["pages_rule"] = v.rule.pages.size();
  out["pages_footprint"] = v.footprint.pages.size();
  out["pages_per_level_rule"] = v.rule.pages_per_level();
  out["drawn"] = v.stats.drawn;
  out["cached"] = v.stats.cached;
  out["missing"] = v.stats.missing;
  out["pool_slots"] = debug.map().pool_slots();
  return out;
}

}  // namespace penumbra::apps
