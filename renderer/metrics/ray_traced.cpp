#include "metrics/ray_traced.h"

#if PENUMBRA_HAS_RAY_TRACING
#include <embree3/rtcore.h>
#endif

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <glm/gtc/matrix_inverse.hpp>

#include "metrics/ground_truth.h"
#include "metrics/surface_probe.h"

namespace penumbra::metrics {

#if PENUMBRA_HAS_RAY_TRACING

struct RayTracedScene::Embree {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  // Per geometry (Embree's geomID): the world-space vertex normals and the triangles' indices.
  std::vector<std::vector<glm::vec3>> normals;
  std::vector<const std::vector<std::uint32_t>*> indices;
  std::vector<std::shared_ptr<const scene::MeshData>> meshes;  // keeps `indices` alive
  // Per geometry: the object's name and its mask bit (one bit per distinct name in order of first
  // appearance; names past the 32nd share the last bit).
  std::vector<std::string> names;
  std::vector<unsigned> masks;
  bool ray_masks = false;  // whether the library honours ray.mask (EMBREE_RAY_MASK)
  ~Embree() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }
};

namespace {

std::string device_error(RTCDevice device) {
  switch (rtcGetDeviceError(device)) {
    case RTC_ERROR_NONE: return "no error";
    case RTC_ERROR_INVALID_ARGUMENT: return "invalid argument";
    case RTC_ERROR_INVALID_OPERATION: return "invalid operation";
    case RTC_ERROR_OUT_OF_MEMORY: return "out of memory";
    case RTC_ERROR_UNSUPPORTED_CPU: return "unsupported CPU";
    case RTC_ERROR_CANCELLED: return "cancelled";
    default: return "unknown error";
  }
}

// A uniform in [0, 1) from a pixel, a sample and a stream (a SplitMix64 finalizer over their
// combination): the same on every run and platform.
float hash_uniform(std::uint64_t pixel, std::uint64_t sample, std::uint64_t stream) {
  std::uint64_t z = pixel * 0x9E3779B97F4A7C15ull ^ (sample + 0x632BE59BD9B4E019ull) * 0xBF58476D1CE4E5B9ull ^ stream * 0x94D049BB133111EBull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  z ^= z >> 31;
  return static_cast<float>(static_cast<double>(z >> 11) * 0x1.0p-53);
}

}  // namespace

RayTracedScene::RayTracedScene(const scene::Scene& scene) : embree_(std::make_unique<Embree>()) {
  embree_->device = rtcNewDevice(nullptr);
  if (!embree_->device) throw std::runtime_error("ray tracing: cannot create the Embree device (" + device_error(nullptr) + ")");
  embree_->ray_masks = rtcGetDeviceProperty(embree_->device, RTC_DEVICE_PROPERTY_RAY_MASK_SUPPORTED) != 0;
  embree_->scene = rtcNewScene(embree_->device);
  rtcSetSceneBuildQuality(embree_->scene, RTC_BUILD_QUALITY_HIGH);
  std::vector<std::string> distinct;  // the names seen so far, in order: bit i for the i-th
  for (const scene::Object& o : scene.objects) {
    if (!o.mesh || o.mesh->indices.size() < 3) continue;
    const scene::MeshData& mesh = *o.mesh;
    RTCGeometry g = rtcNewGeometry(embree_->device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* v = static_cast<float*>(
        rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), mesh.vertices.size()));
    for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
      const glm::vec4 p = o.model * glm::vec4(mesh.vertices[i].position, 1.0f);
      v[3 * i] = p.x, v[3 * i + 1] = p.y, v[3 * i + 2] = p.z;
    }
    const std::size_t n = mesh.indices.size() / 3;
    auto* idx = static_cast<unsigned*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), n));
    std::copy(mesh.indices.begin(), mesh.indices.begin() + static_cast<std::ptrdiff_t>(3 * n), idx);
    const auto named = std::find(distinct.begin(), distinct.end(), o.name);
    const std::size_t bit = std::min<std::size_t>(static_cast<std::size_t>(named - distinct.begin()), 31);
    if (named == distinct.end()) distinct.push_back(o.name);
    rtcSetGeometryMask(g, 1u << bit);
    rtcCommitGeometry(g);
    const unsigned id = rtcAttachGeometry(embree_->scene, g);
    if (id >= embree_->normals.size()) {
      embree_->normals.resize(id + 1), embree_->indices.resize(id + 1), embree_->meshes.resize(id + 1);
      embree_->names.resize(id + 1), embree_->masks.resize(id + 1, 0);
    }
    embree_->names[id] = o.name;
    embree_->masks[id] = 1u << bit;
    const glm::mat3 normal_matrix = glm::inverseTranspose(glm::mat3(o.model));
    for (const scene::Vertex& vertex : mesh.vertices) embree_->normals[id].push_back(normal_matrix * vertex.normal);
    embree_->indices[id] = &mesh.indices;
    embree_->meshes[id] = o.mesh;
    rtcReleaseGeometry(g);
    triangles_ += n;
  }
  rtcCommitScene(embree_->scene);
  if (rtcGetDeviceError(embree_->device) != RTC_ERROR_NONE)
    throw std::runtime_error("ray tracing: building the scene failed (" + device_error(embree_->device) + ")");
}

RayTracedScene::~RayTracedScene() = default;

namespace {

// The ray through the centre of pixel (x, y), rows top-down (NDC y = +1 at row 0).
void pixel_ray(const glm::mat4& inverse_view_projection, int x, int y, int width_px, int height_px, glm::vec3& origin,
               glm::vec3& direction) {
  const float nx = (static_cast<float>(x) + 0.5f) / static_cast<float>(width_px) * 2 - 1;
  const float ny = 1 - (static_cast<float>(y) + 0.5f) / static_cast<float>(height_px) * 2;
  const glm::vec4 near = inverse_view_projection * glm::vec4(nx, ny, -1, 1), far = inverse_view_projection * glm::vec4(nx, ny, 1, 1);
  origin = glm::vec3(near) / near.w;
  direction = glm::normalize(glm::vec3(far) / far.w - origin);
}

// A ray from `origin` along `direction`, from `tnear` on, tested against the geometries in `mask`.
RTCRay ray_from(const glm::vec3& origin, const glm::vec3& direction, float tnear = 0, unsigned mask = 0xFFFFFFFFu) {
  RTCRay ray{};
  ray.org_x = origin.x, ray.org_y = origin.y, ray.org_z = origin.z;
  ray.dir_x = direction.x, ray.dir_y = direction.y, ray.dir_z = direction.z;
  ray.tnear = tnear, ray.tfar = std::numeric_limits<float>::infinity();
  ray.mask = mask, ray.flags = 0, ray.time = 0;
  return ray;
}

// The nearest hit of that ray (geomID RTC_INVALID_GEOMETRY_ID: none).
RTCRayHit nearest_hit(RTCScene scene, const glm::vec3& origin, const glm::vec3& direction, float tnear = 0) {
  RTCRayHit hit{};
  hit.ray = ray_from(origin, direction, tnear);
  hit.hit.geomID = RTC_INVALID_GEOMETRY_ID, hit.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  rtcIntersect1(scene, &context, &hit);
  return hit;
}

// Whether anything in `mask` lies on the ray from `start` along `direction`.
bool occluded(RTCScene scene, const glm::vec3& start, const glm::vec3& direction, unsigned mask = 0xFFFFFFFFu) {
  RTCRay ray = ray_from(start, direction, 0, mask);
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  rtcOccluded1(scene, &context, &ray);
  return ray.tfar < 0;  // tfar is set to -inf when occluded
}

// How many of the `count` (1 to 8) rays from `start` along `directions` reach the light, traced as
// one packet of Embree's native width (the rays of one pixel's light samples are coherent: one
// origin, directions within the sun's disk). The same answer per ray as occluded().
int unoccluded8(RTCScene scene, const glm::vec3& start, const glm::vec3* directions, int count) {
  alignas(32) int valid[8];
  alignas(32) RTCRay8 rays{};
  for (int k = 0; k < 8; ++k) {
    const glm::vec3& d = directions[k < count ? k : 0];
    valid[k] = k < count ? -1 : 0;
    rays.org_x[k] = start.x, rays.org_y[k] = start.y, rays.org_z[k] = start.z;
    rays.dir_x[k] = d.x, rays.dir_y[k] = d.y, rays.dir_z[k] = d.z;
    rays.tnear[k] = 0, rays.tfar[k] = std::numeric_limits<float>::infinity();
    rays.mask[k] = 0xFFFFFFFFu, rays.flags[k] = 0, rays.time[k] = 0;
  }
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  rtcOccluded8(valid, scene, &context, &rays);
  int seen = 0;
  for (int k = 0; k < count; ++k) seen += rays.tfar[k] < 0 ? 0 : 1;  // tfar is set to -inf when occluded
  return seen;
}

// Where a shadow ray leaves a surface seen at `position` (geometric normal `normal`, on the side
// the camera sees): 1e-4 of the camera distance off it, at least 1 mm.
glm::vec3 shadow_ray_start(const glm::vec3& position, const glm::vec3& normal, const glm::vec3& camera_position) {
  return position + normal * std::max(1e-3f, 1e-4f * glm::length(position - camera_position));
}

// Runs work() on `threads` threads (0: one per hardware thread), this one included.
template <class F>
void on_threads(int threads, F work) {
  const int n = threads > 0 ? threads : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  std::vector<std::thread> pool;
  for (int t = 1; t < n; ++t) pool.emplace_back(work);
  work();
  for (auto& t : pool) t.join();
}

}  // namespace

bool RayTracedScene::primary(const glm::vec3& origin, const glm::vec3& direction, Hit& out) const {
  const RTCRayHit hit = nearest_hit(embree_->scene, origin, direction);
  if (hit.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
  out.position = origin + hit.ray.tfar * direction;
  out.geometric = glm::normalize(glm::vec3(hit.hit.Ng_x, hit.hit.Ng_y, hit.hit.Ng_z));
  const bool front = glm::dot(out.geometric, direction) < 0;
  if (!front) out.geometric = -out.geometric;  // the side the camera sees
  // The interpolated normal, turned like the shader's (n = -n where the camera sees the back).
  const auto& idx = *embree_->indices[hit.hit.geomID];
  const auto& normals = embree_->normals[hit.hit.geomID];
  const std::size_t t = 3 * static_cast<std::size_t>(hit.hit.primID);
  const glm::vec3 n = (1 - hit.hit.u - hit.hit.v) * normals[idx[t]] + hit.hit.u * normals[idx[t + 1]] + hit.hit.v * normals[idx[t + 2]];
  out.shading = glm::length(n) > 0 ? glm::normalize(n) : out.geometric;
  if (!front) out.shading = -out.shading;
  return true;
}

template <class F>
void RayTracedScene::for_each_seen_pixel(const scene::Camera& camera, int width_px, int height_px, int threads, F seen) const {
  const glm::mat4 inverse = glm::inverse(camera_view_projection(camera, width_px, height_px));
  std::atomic<int> next_row{0};
  on_threads(threads, [&] {
    for (int y = next_row++; y < height_px; y = next_row++)
      for (int x = 0; x < width_px; ++x) {
        glm::vec3 origin, direction;
        pixel_ray(inverse, x, y, width_px, height_px, origin, direction);
        Hit hit;
        if (primary(origin, direction, hit)) seen(static_cast<std::size_t>(y) * static_cast<std::size_t>(width_px) + static_cast<std::size_t>(x), hit);
      }
  });
}

io::Image8 RayTracedScene::facing_light(const scene::Camera& camera, const scene::Light& light, int width_px, int height_px,
                                        int threads) const {
  if (width_px < 1 || height_px < 1) throw std::invalid_argument("ray-traced facing mask: empty image");
  io::Image8 out{width_px, height_px, 1, std::vector<std::uint8_t>(static_cast<std::size_t>(width_px) * height_px, 0)};
  for_each_seen_pixel(camera, width_px, height_px, threads, [&](std::size_t pixel, const Hit& hit) {
    const glm::vec3 to_light = light.type == scene::Light::Type::directional ? -glm::normalize(light.direction)
                                                                              : glm::normalize(light.position - hit.position);
    if (glm::dot(hit.shading, to_light) > 0) out.pixels[pixel] = 255;
  });
  return out;
}

io::ImageF RayTracedScene::area_light_visibility(const scene::Camera& camera, const scene::Light& light, int width_px, int height_px,
                                                 int per_side, int threads) const {
  if (light.type != scene::Light::Type::directional)
    throw std::invalid_argument("ray-traced visibility: only a directional light (a spot light's cone is the shadow map's)");
  if (per_side < 1) throw std::invalid_argument("ray-traced visibility: per_side must be at least 1, got " + std::to_string(per_side));
  if (width_px < 1 || height_px < 1) throw std::invalid_argument("ray-traced visibility: empty image");
  const glm::vec3 camera_position = camera.position;
  // The sun's directions toward the light: -(light_sample's direction), light_sample's basis.
  const float tan_half = std::tan(glm::radians(std::max(light.size, 0.0f)) / 2);
  const glm::vec3 axis = glm::normalize(light.direction);
  glm::vec3 e1, e2;
  scene::light_basis(axis, e1, e2);
  const int samples = per_side * per_side;
  const float cell = 2.0f / static_cast<float>(per_side);

  io::ImageF out{width_px, height_px, 1, std::vector<float>(static_cast<std::size_t>(width_px) * height_px, 1.0f)};
  for_each_seen_pixel(camera, width_px, height_px, threads, [&](std::size_t pixel, const Hit& hit) {
    const glm::vec3 start = shadow_ray_start(hit.position, hit.geometric, camera_position);
    int seen = 0, queued = 0;
    glm::vec3 toward[8];
    for (int j = 0; j < per_side; ++j)
      for (int i = 0; i < per_side; ++i) {
        const std::uint64_t s = static_cast<std::uint64_t>(j * per_side + i);
        const glm::vec2 uv = concentric_disk({-1 + (static_cast<float>(i) + hash_uniform(pixel, s, 0)) * cell,
                                              -1 + (static_cast<float>(j) + hash_uniform(pixel, s, 1)) * cell});
        toward[queued++] = -glm::normalize(axis + tan_half * (uv.x * e1 + uv.y * e2));
        if (queued == 8) seen += unoccluded8(embree_->scene, start, toward, queued), queued = 0;
      }
    if (queued > 0) seen += unoccluded8(embree_->scene, start, toward, queued);
    out.pixels[pixel] = static_cast<float>(seen) / static_cast<float>(samples);
  });
  return out;
}

RayTracedScene::HardVisibility RayTracedScene::hard_visibility_split(const scene::Camera& camera, const scene::Light& light, int width_px,
                                                                    int height_px, const std::vector<std::string>& excluded_names,
                                                                    int threads) const {
  if (light.type != scene::Light::Type::directional)
    throw std::invalid_argument("ray-traced hard shadows: only a directional light (a spot light's cone is the shadow map's)");
  if (width_px < 1 || height_px < 1) throw std::invalid_argument("ray-traced hard shadows: empty image");
  const glm::vec3 camera_position = camera.position;
  const glm::vec3 to_light = -glm::normalize(light.direction);
  // Which geometries are left out, and whether their mask bits are theirs alone.
  const std::size_t geometries = embree_->names.size();
  std::vector<char> excluded(geometries, 0);
  unsigned excluded_bits = 0, kept_bits = 0;
  bool any_excluded = false;
  for (std::size_t g = 0; g < geometries; ++g) {
    if (!embree_->masks[g]) continue;  // no geometry under this id
    excluded[g] = std::find(excluded_names.begin(), excluded_names.end(), embree_->names[g]) != excluded_names.end();
    (excluded[g] ? excluded_bits : kept_bits) |= embree_->masks[g];
    any_excluded = any_excluded || excluded[g];
  }
  const bool by_mask = embree_->ray_masks && (excluded_bits & kept_bits) == 0;

  const std::size_t n = static_cast<std::size_t>(width_px) * static_cast<std::size_t>(height_px);
  HardVisibility out{{width_px, height_px, 1, std::vector<float>(n, 1.0f)}, {width_px, height_px, 1, std::vector<float>(n, 1.0f)}};
  // Without ray masks: the nearest hits in turn, past the left-out geometries' ones.
  auto occluded_by_kept = [&](const glm::vec3& start) {
    float tnear = 0;
    for (;;) {
      const RTCRayHit hit = nearest_hit(embree_->scene, start, to_light, tnear);
      if (hit.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
      if (!excluded[hit.hit.geomID]) return true;
      tnear = std::nextafter(hit.ray.tfar, std::numeric_limits<float>::infinity());
    }
  };
  for_each_seen_pixel(camera, width_px, height_px, threads, [&](std::size_t p, const Hit& hit) {
    const glm::vec3 start = shadow_ray_start(hit.position, hit.geometric, camera_position);
    if (!occluded(embree_->scene, start, to_light)) return;
    out.all.pixels[p] = 0;
    const bool blocked = !any_excluded || (by_mask ? occluded(embree_->scene, start, to_light, ~excluded_bits) : occluded_by_kept(start));
    if (blocked) out.without.pixels[p] = 0;
  });
  return out;
}

#else

// Built without Embree (PENUMBRA_RAY_TRACING=OFF, the gpu-bundle preset): the references fall
// back to the shadow maps' mean (ground_truth.h) and nothing constructs this.
struct RayTracedScene::Embree {};
RayTracedScene::RayTracedScene(const scene::Scene&) {
  throw std::runtime_error("ray tracing: this build has no Embree (configure with PENUMBRA_RAY_TRACING=ON)");
}
RayTracedScene::~RayTracedScene() = default;
io::ImageF RayTracedScene::area_light_visibility(const scene::Camera&, const scene::Light&, int, int, int, int) const { return {}; }
io::Image8 RayTracedScene::facing_light(const scene::Camera&, const scene::Light&, int, int, int) const { return {}; }
RayTracedScene::HardVisibility RayTracedScene::hard_visibility_split(const scene::Camera&, const scene::Light&, int, int,
                                                                    const std::vector<std::string>&, int) const {
  return {};
}
bool RayTracedScene::primary(const glm::vec3&, const glm::vec3&, Hit&) const { return false; }

#endif

}  // namespace penumbra::metrics
