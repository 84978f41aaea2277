#include "scene/scene.h"

#include <array>
#include <cmath>

#include <glm/gtc/matrix_transform.hpp>

#include "scene/outdoor.h"

namespace penumbra::scene {

glm::mat4 Camera::view() const {
  glm::vec3 fwd = target - position;
  glm::vec3 up_ws = up;
  if (glm::length(glm::cross(fwd, up_ws)) < 1e-6f * glm::length(fwd)) up_ws = {0, 0, -1};  // looking along up
  return glm::lookAt(position, target, up_ws);
}

glm::mat4 Camera::projection_matrix(float aspect) const {
  if (projection == Projection::orthographic) {
    const float h = ortho_height_ws / 2, w = h * aspect;
    return glm::ortho(-w, w, -h, h, near_ws, far_ws);
  }
  return glm::perspective(glm::radians(fov_y_deg), aspect, near_ws, far_ws);
}

Camera CameraPath::at(const Camera& base, double frame) const {
  Camera c = base;
  if (keys.empty()) return c;
  if (keys.size() == 1 || frame <= keys.front().frame) {
    c.position = keys.front().position, c.target = keys.front().target;
    return c;
  }
  if (frame >= keys.back().frame) {
    c.position = keys.back().position, c.target = keys.back().target;
    return c;
  }
  std::size_t k = 0;
  while (k + 2 < keys.size() && frame >= keys[k + 1].frame) ++k;
  const auto time = [&](std::size_t i) { return static_cast<double>(keys[i].frame); };
  // Monotone tangents (Fritsch and Butland): per coordinate, zero where the secants on either
  // side of a key differ in sign, else their weighted harmonic mean; the secant at the ends.
  const auto tangent = [&](std::size_t i, auto member) {
    const auto secant = [&](std::size_t a) { return glm::dvec3(keys[a + 1].*member - keys[a].*member) / (time(a + 1) - time(a)); };
    if (i == 0) return secant(0);
    if (i + 1 == keys.size()) return secant(i - 1);
    const glm::dvec3 before = secant(i - 1), after = secant(i);
    const double h0 = time(i) - time(i - 1), h1 = time(i + 1) - time(i);
    const double w0 = 2 * h1 + h0, w1 = h1 + 2 * h0;
    glm::dvec3 m(0);
    for (int axis = 0; axis < 3; ++axis)
      if (before[axis] * after[axis] > 0) m[axis] = (w0 + w1) / (w0 / before[axis] + w1 / after[axis]);
    return m;
  };
  const double span = time(k + 1) - time(k);
  const double t = (frame - time(k)) / span;
  const double h00 = (1 + 2 * t) * (1 - t) * (1 - t), h10 = t * (1 - t) * (1 - t), h01 = t * t * (3 - 2 * t), h11 = t * t * (t - 1);
  const auto hermite = [&](auto member) {
    return glm::vec3(h00 * glm::dvec3(keys[k].*member) + h10 * span * tangent(k, member) + h01 * glm::dvec3(keys[k + 1].*member) +
                     h11 * span * tangent(k + 1, member));
  };
  c.position = hermite(&CameraKey::position);
  c.target = hermite(&CameraKey::target);
  return c;
}

void light_basis(glm::vec3 axis, glm::vec3& e1, glm::vec3& e2) {
  axis = glm::normalize(axis);
  const glm::vec3 helper = std::abs(axis.y) < 0.9f ? glm::vec3(0, 1, 0) : glm::vec3(1, 0, 0);
  e1 = glm::normalize(glm::cross(helper, axis));
  e2 = glm::cross(axis, e1);
}

glm::vec3 ObjectPath::translate_at(double frame) const {
  if (keys.empty()) return glm::vec3(0);
  if (frame <= keys.front().frame) return keys.front().translate;
  if (frame >= keys.back().frame) return keys.back().translate;
  std::size_t k = 0;
  while (frame >= keys[k + 1].frame) ++k;
  const double t = (frame - keys[k].frame) / static_cast<double>(keys[k + 1].frame - keys[k].frame);
  return glm::vec3(glm::mix(glm::dvec3(keys[k].translate), glm::dvec3(keys[k + 1].translate), t));
}

std::size_t path_object(const Scene& scene, const ObjectPath& path) {
  std::size_t found = scene.objects.size(), count = 0;
  for (std::size_t i = 0; i < scene.objects.size(); ++i)
    if (scene.objects[i].name == path.object) found = i, ++count;
  if (count != 1)
    throw SceneError("scene " + scene.name + ": object path '" + path.object + "' names " +
                     (count == 0 ? std::string("no object") : std::to_string(count) + " objects") + ", not exactly one");
  return found;
}

void pose_objects(const Scene& base, double frame, Scene& posed) {
  for (const ObjectPath& path : base.object_paths) {
    const glm::mat4 model = glm::translate(glm::mat4(1), path.translate_at(frame)) * base.objects[path_object(base, path)].model;
    posed.objects[path_object(posed, path)].model = model;
  }
}

Scene posed_at(const Scene& base, double frame) {
  Scene posed = base;
  pose_objects(base, frame, posed);
  return posed;
}

Aabb Scene::bounds() const {
  Aabb b;
  for (const auto& o : objects) b.extend(o.mesh->bounds().transformed(o.model));
  return b;
}

namespace {

std::shared_ptr<const MeshData> share(MeshData m) { return std::make_shared<const MeshData>(std::move(m)); }

glm::mat4 translate(glm::vec3 t) { return glm::translate(glm::mat4(1), t); }

Object ground(float size) { return {"ground", share(make_plane(size, size)), glm::mat4(1), {0.85f, 0.85f, 0.85f}}; }

Scene base(std::string name) {
  Scene s;
  s.name = std::move(name);
  s.camera.position = {1, 5.5f, 11.5f};
  s.camera.target = {0, 0.8f, 0};
  s.camera.fov_y_deg = 45;
  s.light.type = Light::Type::directional;
  s.light.direction = glm::normalize(glm::vec3(-0.5f, -1.0f, -0.55f));
  s.light.size = 3.0f;
  return s;
}

Object box_object(glm::vec3 at) { return {"box", share(make_box({2, 2, 2})), translate(at), {0.75f, 0.35f, 0.3f}}; }
Object sphere_object(glm::vec3 at) { return {"sphere", share(make_sphere(1.2f)), translate(at), {0.3f, 0.5f, 0.8f}}; }
Object fence_object(glm::vec3 at) {
  return {"fence", share(make_lattice(5, 3, 17, 9, 0.06f)), translate(at), {0.6f, 0.6f, 0.4f}};
}
Object tilted_object(glm::vec3 at, float tilt_deg) {
  const glm::mat4 m = glm::rotate(translate(at), glm::radians(tilt_deg), glm::vec3(1, 0, 0));
  return {"tilted", share(make_plane(5, 5)), m, {0.8f, 0.8f, 0.8f}};
}

constexpr std::array<std::string_view, 10> kNames = {"demo",       "box",     "sphere",       "fence", "tilted", "square",
                                                     "two-planes", "outdoor", "outdoor-spot", "empty"};

}  // namespace

std::span<const std::string_view> builtin_scene_names() { return kNames; }

Scene make_square_scene(float side_ws, float height_ws) {
  Scene s;
  s.name = "square";
  s.objects.push_back(ground(10));
  s.objects.push_back({"square", share(make_box({side_ws, 0.02f, side_ws})), translate({0, height_ws, 0}), {0.5f, 0.5f, 0.5f}});
  s.light.type = Light::Type::directional;
  s.light.direction = {0, -1, 0};
  s.light.size = 1.0f;
  s.camera.projection = Camera::Projection::orthographic;
  s.camera.position = {0, 20, 0};
  s.camera.target = {0, 0, 0};
  s.camera.up = {0, 0, -1};
  s.camera.ortho_height_ws = 10;
  s.camera.near_ws = 1;
  s.camera.far_ws = 40;
  return s;
}

Scene make_two_planes_scene(float blocker_height_ws, float light_height_ws, float light_width_ws) {
  Scene s;
  s.name = "two-planes";
  s.objects.push_back(ground(12));
  // Blocker covers x in [-6, 0]; its edge x = 0 runs along z.
  s.objects.push_back({"blocker", share(make_box({6, 0.01f, 12})), translate({-3, blocker_height_ws, 0}), {0.5f, 0.5f, 0.5f}});
  s.light.type = Light::Type::spot;
  s.light.position = {0, light_height_ws, 0};
  s.light.direction = {0, -1, 0};
  s.light.spot_fov_deg = 90;
  s.light.size = light_width_ws;
  s.camera.projection = Camera::Projection::orthographic;
  s.camera.position = {0, light_height_ws + 5, 0};
  s.camera.target = {0, 0, 0};
  s.camera.up = {0, 0, -1};
  s.camera.ortho_height_ws = 8;
  s.camera.near_ws = 0.5f;
  s.camera.far_ws = light_height_ws + 10;
  return s;
}

Scene make_builtin_scene(std::string_view name) {
  if (name == "demo") {
    Scene s = base("demo");
    s.objects.push_back(ground(30));
    s.objects.push_back(box_object({-4.5f, 1, 1}));
    s.objects.push_back(sphere_object({-0.5f, 1.8f, 2.5f}));
    s.objects.push_back(fence_object({3.5f, 1.6f, 0}));
    s.objects.push_back(tilted_object({-1, 1.5f, -4}, 60));
    return s;
  }
  if (name == "box") {
    Scene s = base("box");
    s.objects.push_back(ground(20));
    s.objects.push_back(box_object({0, 1, 0}));
    return s;
  }
  if (name == "sphere") {
    Scene s = base("sphere");
    s.objects.push_back(ground(20));
    s.objects.push_back(sphere_object({0, 1.5f, 0}));
    return s;
  }
  if (name == "fence") {
    Scene s = base("fence");
    s.objects.push_back(ground(20));
    s.objects.push_back(fence_object({0, 1.6f, 0}));
    return s;
  }
  if (name == "tilted") {
    Scene s = base("tilted");
    s.light.direction = {0, -1, 0};
    s.objects.push_back(tilted_object({0, 2.5f, 0}, 80));  // receiver at 80° from the light, facing the camera
    s.objects.push_back({"caster", share(make_box({1, 0.2f, 1})), translate({0, 6, 0}), {0.7f, 0.3f, 0.3f}});
    s.camera.position = {6, 6, 8};
    s.camera.target = {0, 2.5f, 0};
    return s;
  }
  if (name == "square") return make_square_scene(2, 1);
  if (name == "two-planes") return make_two_planes_scene(3, 10, 1);
  if (name == "outdoor") return make_outdoor_scene({});
  if (name == "outdoor-spot") {
    OutdoorOptions o;
    o.light = OutdoorLight::floodlight;
    return make_outdoor_scene(o);
  }
  if (name == "empty") return base("empty");
  std::string names;
  for (auto n : kNames) names += (names.empty() ? "" : ", ") + std::string(n);
  throw SceneError("unknown built-in scene '" + std::string(name) + "' (known: " + names + ")");
}

Scene load_scene(std::string_view name_or_path) {
  for (auto n : kNames)
    if (n == name_or_path) return make_builtin_scene(n);
  const std::filesystem::path path(name_or_path);
  if (path.extension() != ".json") {
    try {
      return make_builtin_scene(name_or_path);
    } catch (const SceneError& e) {
      throw SceneError(std::string(e.what()) + "; a scene file must end in .json");
    }
  }
  return load_scene_file(path);
}

}  // namespace penumbra::scene
