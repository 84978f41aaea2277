#pragma once
// What is drawn: objects (mesh + transform + albedo), one camera, one shadow-casting light.
// Plain data: a sweep or a test may build or edit a Scene directly.
#include <filesystem>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>

#include <penumbra/scene/mesh.h>

namespace penumbra::scene {

struct Camera {
  enum class Projection { perspective, orthographic };
  Projection projection = Projection::perspective;
  glm::vec3 position{0, 6, 12};
  glm::vec3 target{0, 0, 0};
  glm::vec3 up{0, 1, 0};
  float fov_y_deg = 50;        // perspective
  float ortho_height_ws = 10;  // orthographic: world-space height of the view
  float near_ws = 0.1f;
  float far_ws = 100;

  glm::mat4 view() const;
  glm::mat4 projection_matrix(float aspect) const;
};

// A camera path: keys at increasing frame numbers, the first at frame 0. Position and target each
// follow a piecewise cubic Hermite curve through the keys over the frame numbers, with monotone
// tangents per coordinate (Fritsch and Butland, as in PCHIP): the camera passes through every key
// at its frame, moves smoothly, and never overshoots a key (a walk at eye height followed by a
// climb does not dip below the ground before climbing).
struct CameraKey {
  int frame = 0;
  glm::vec3 position{0};
  glm::vec3 target{0};
};

struct CameraPath {
  std::vector<CameraKey> keys;

  bool empty() const { return keys.empty(); }
  int frames() const { return keys.empty() ? 0 : keys.back().frame + 1; }
  // `base` (projection, fov, clip planes) moved to frame `frame` of the path (clamped to it).
  Camera at(const Camera& base, double frame) const;
};

struct Light {
  enum class Type { directional, spot };
  Type type = Type::directional;
  glm::vec3 direction{0, -1, 0};  // the direction light travels, normalized
  glm::vec3 position{0, 10, 0};   // spot only
  float spot_fov_deg = 60;        // spot only: full cone angle
  // Area-light size for soft shadows (PCSS): the light's angular diameter in degrees for a
  // directional light, the emitter's width in world units for a spot light.
  float size = 1;
  // A directional light's angular diameter lies in [0, kMaxAngularDiameterDeg]: the sun's is 0.53°;
  // 90° is a cone of half-angle 45°, whose penumbrae grow as fast as the distance from the caster.
  // The soft-shadow model widens them by tan(size / 2), infinite at 180° and wrapping beyond it (400°
  // rendered as 40°).
  static constexpr float kMaxAngularDiameterDeg = 90;
  glm::vec3 color{1, 1, 1};
  float ambient = 0.2f;  // fraction of light that reaches shadowed surfaces
};

// Two unit vectors across the light's `axis` (perpendicular to it and to each other): the plane
// the references offset an area light's samples in, and the light-space x and y of the sun's
// virtual shadow map.
void light_basis(glm::vec3 axis, glm::vec3& e1, glm::vec3& e2);

struct Object {
  std::string name;
  std::shared_ptr<const MeshData> mesh;
  glm::mat4 model{1};
  glm::vec3 albedo{0.8f, 0.8f, 0.8f};
};

// A key of an object's path: at `frame`, the object moved by `translate` (world units) from its
// placement in the scene.
struct ObjectKey {
  int frame = 0;
  glm::vec3 translate{0};
};

// An object moving along keys (straight between them, held before the first and after the last):
// a caster that moves from frame to frame, which shadow maps redraw whole and the virtual shadow
// map only where it was and is.
struct ObjectPath {
  std::string object;  // the name of exactly one of the scene's objects
  std::vector<ObjectKey> keys;  // frames increasing from 0
  glm::vec3 translate_at(double frame) const;
};

struct Scene {
  std::string name;
  std::vector<Object> objects;
  Camera camera;
  Light light;
  CameraPath camera_path;  // empty unless the scene defines one
  std::vector<ObjectPath> object_paths;  // the objects that move along the camera path's frames

  // World-space bounds of all objects (empty for an empty scene).
  Aabb bounds() const;
};

// Thrown for a bad scene name or file; what() is one line naming the file and field.
class SceneError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The index of the one object of `scene` named `path.object`; throws SceneError when no object,
// or more than one, has that name.
std::size_t path_object(const Scene& scene, const ObjectPath& path);
// Moves each of `base`'s moving objects (object_paths) to its place at `frame` in `posed`, a copy
// of `base` or of some of its objects (a renderer's scene, the scene less some casters) that holds
// each moving object once: its model becomes translate(path.translate_at(frame)) · its model in
// `base`. Other objects are left as they are. Throws SceneError when a moving object is not
// exactly once in either scene.
void pose_objects(const Scene& base, double frame, Scene& posed);
// `base` with its moving objects at their places at `frame`.
Scene posed_at(const Scene& base, double frame);

// Built-in procedural scenes: "demo" (the default: box, sphere, fence, tilted panel on a ground
// plane), "box", "sphere", "fence", "tilted" (grazing receiver for acne/bias), "square" (analytic
// square occluder, light and orthographic camera straight down), "two-planes" (half-plane blocker
// over a receiver under a spot light), "outdoor" and "outdoor-spot" (scene/outdoor.h: a town of
// about a million triangles with a camera path, under the sun or a floodlight), "empty".
std::span<const std::string_view> builtin_scene_names();
Scene make_builtin_scene(std::string_view name);

// Square occluder of side `side_ws` at height `height_ws` over a plane (the analytic test scene).
Scene make_square_scene(float side_ws, float height_ws);
// Half-plane blocker (x < 0) at `blocker_height_ws` over a receiver at y = 0, lit by a spot light
// of width `light_width_ws` at `light_height_ws`, seen by an orthographic camera from above.
Scene make_two_planes_scene(float blocker_height_ws, float light_height_ws, float light_width_ws);

// Loads a JSON scene file (format in docs/scene-format.md); models through Assimp.
Scene load_scene_file(const std::filesystem::path& path);
// Writes `scene` as a scene file at `path` (ending in .json) that load_scene_file reads back:
// camera, light, camera path, and every object as a model, its mesh with the object's transform
// applied, in glTF 2.0 binary `<stem>/<index>-<name>.glb` beside the file (so a user's own glTF
// can take any object's place). The .json is written last. Throws SceneError naming the file.
void write_scene_file(const Scene& scene, const std::filesystem::path& path);
// A built-in name or a path to a scene file.
Scene load_scene(std::string_view name_or_path);

}  // namespace penumbra::scene
