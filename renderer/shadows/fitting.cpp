#include "shadows/fitting.h"

#include <algorithm>
#include <cmath>

#include <glm/gtc/matrix_transform.hpp>

#include "adaptive/cascades.h"

namespace penumbra::shadows {

Polyhedron box_polyhedron(const scene::Aabb& b) {
  if (b.empty()) return {};
  auto c = [&](int i) { return glm::dvec3(b.corner(i)); };
  // Faces as corner indices (bit 0: x, bit 1: y, bit 2: z).
  const int faces[6][4] = {{0, 2, 6, 4}, {1, 5, 7, 3}, {0, 4, 5, 1}, {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 6, 7, 5}};
  Polyhedron p;
  for (const auto& f : faces) p.push_back({c(f[0]), c(f[1]), c(f[2]), c(f[3])});
  return p;
}

Polyhedron clip(const Polyhedron& poly, const glm::dvec4& plane) {
  const glm::dvec3 n(plane);
  const double len = glm::length(n);
  if (len == 0) return poly;
  auto dist = [&](const glm::dvec3& p) { return (glm::dot(n, p) + plane.w) / len; };
  constexpr double eps = 1e-12;
  Polyhedron out;
  std::vector<glm::dvec3> cut;
  for (const auto& face : poly) {
    Polygon kept;
    for (std::size_t i = 0; i < face.size(); ++i) {
      const glm::dvec3& a = face[i];
      const glm::dvec3& b = face[(i + 1) % face.size()];
      const double da = dist(a), db = dist(b);
      if (da >= -eps) kept.push_back(a);
      if ((da >= -eps) != (db >= -eps)) {
        const glm::dvec3 x = a + (b - a) * (da / (da - db));
        kept.push_back(x);
        cut.push_back(x);
      }
      if (std::abs(da) <= eps) cut.push_back(a);
    }
    if (kept.size() >= 3) out.push_back(std::move(kept));
  }
  if (cut.size() >= 3) {
    glm::dvec3 centre(0);
    for (const auto& p : cut) centre += p;
    centre /= static_cast<double>(cut.size());
    const glm::dvec3 nn = n / len;
    glm::dvec3 u = glm::cross(nn, std::abs(nn.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0));
    u = glm::normalize(u);
    const glm::dvec3 v = glm::cross(nn, u);
    std::sort(cut.begin(), cut.end(), [&](const glm::dvec3& a, const glm::dvec3& b) {
      return std::atan2(glm::dot(a - centre, v), glm::dot(a - centre, u)) <
             std::atan2(glm::dot(b - centre, v), glm::dot(b - centre, u));
    });
    Polygon cap;
    for (const auto& p : cut)
      if (cap.empty() || glm::length(p - cap.back()) > 1e-9) cap.push_back(p);
    if (cap.size() >= 3) out.push_back(std::move(cap));
  }
  return out;
}

std::array<glm::dvec4, 6> frustum_planes(const glm::dmat4& m) {
  const glm::dvec4 r0(m[0][0], m[1][0], m[2][0], m[3][0]);
  const glm::dvec4 r1(m[0][1], m[1][1], m[2][1], m[3][1]);
  const glm::dvec4 r2(m[0][2], m[1][2], m[2][2], m[3][2]);
  const glm::dvec4 r3(m[0][3], m[1][3], m[2][3], m[3][3]);
  return {r3 + r0, r3 - r0, r3 + r1, r3 - r1, r3 + r2, r3 - r2};
}

std::vector<glm::dvec3> vertices(const Polyhedron& poly) {
  std::vector<glm::dvec3> out;
  for (const auto& f : poly)
    for (const auto& p : f)
      if (std::none_of(out.begin(), out.end(), [&](const glm::dvec3& q) { return glm::length(p - q) < 1e-9; }))
        out.push_back(p);
  return out;
}

float LightFrame::texel_ws(float depth_ws, int resolution) const {
  const float res = static_cast<float>(std::max(resolution, 1));
  if (!perspective) return extent_ws / res;
  return 2.0f * depth_ws * std::tan(glm::radians(fov_deg) / 2) / (s_xy * res);
}

namespace {

glm::mat4 light_view(const scene::Light& light, const glm::vec3& centre, float distance) {
  const glm::vec3 dir = glm::normalize(light.direction);
  const glm::vec3 up = std::abs(dir.y) < 0.99f ? glm::vec3(0, 1, 0) : glm::vec3(0, 0, -1);
  if (light.type == scene::Light::Type::spot) return glm::lookAt(light.position, light.position + dir, up);
  return glm::lookAt(centre - dir * distance, centre, up);
}

// The camera frustum as clipping planes (world space).
std::array<glm::dvec4, 6> camera_planes(const scene::Camera& camera, float aspect) {
  return frustum_planes(glm::dmat4(camera.projection_matrix(aspect) * camera.view()));
}

// Projection of the spot light's cone onto its unfitted frustum for the scene's depth range.
glm::mat4 spot_projection(const scene::Light& light, float near_ws, float far_ws) {
  return glm::perspective(glm::radians(light.spot_fov_deg), 1.0f, near_ws, far_ws);
}

// Grows a centred square [c - h, c + h] by `pad_texels` of the final map and `pad` absolute.
double padded_half(double half, int resolution, float pad_texels, double pad) {
  const double res = std::max(resolution, 1);
  const double texels = std::clamp(static_cast<double>(pad_texels), 0.0, res / 4);
  return (half + pad) * res / (res - 2 * texels);
}

}  // namespace

std::vector<glm::dvec3> potential_receivers(const scene::Scene& scene, float camera_aspect) {
  Polyhedron psr = box_polyhedron(scene.bounds());
  for (const auto& plane : camera_planes(scene.camera, camera_aspect)) psr = clip(psr, plane);
  if (scene.light.type == scene::Light::Type::spot && !psr.empty()) {
    const scene::Aabb b = scene.bounds();
    const glm::mat4 view = light_view(scene.light, {}, 0);
    float far_ws = 0;
    for (int i = 0; i < 8; ++i) far_ws = std::max(far_ws, -(view * glm::vec4(b.corner(i), 1)).z);
    const glm::mat4 proj = spot_projection(scene.light, std::max(far_ws * 1e-4f, 1e-3f), std::max(far_ws, 1e-2f));
    for (const auto& plane : frustum_planes(glm::dmat4(proj * view))) psr = clip(psr, plane);
  }
  return vertices(psr);
}

LightFrame compute_light_frame(const scene::Scene& scene, const FitRequest& request) {
  LightFrame f;
  const scene::Light& light = scene.light;
  scene::Aabb bounds = scene.bounds();
  if (bounds.empty()) {  // nothing to shadow: a unit box keeps every matrix finite
    bounds.extend(glm::vec3(-0.5f));
    bounds.extend(glm::vec3(0.5f));
  }
  const glm::vec3 centre = (bounds.lo + bounds.hi) * 0.5f;
  const float radius = std::max(glm::length(bounds.hi - bounds.lo) * 0.5f, 1e-3f);
  f.view = light_view(light, centre, 2 * radius);
  f.perspective = light.type == scene::Light::Type::spot;

  // Light-view depth range of the scene (all casters and receivers lie in S).
  float zmin = std::numeric_limits<float>::max(), zmax = std::numeric_limits<float>::lowest();
  for (int i = 0; i < 8; ++i) {
    const float z = -(f.view * glm::vec4(bounds.corner(i), 1)).z;
    zmin = std::min(zmin, z);
    zmax = std::max(zmax, z);
  }
  // A margin keeps surfaces lying exactly on the near or far plane off the depth range's ends,
  // where quantization would make a receiver shadow itself.
  const float margin = 0.01f * std::max(zmax - zmin, 1e-3f);
  zmin -= margin;
  zmax += margin;
  const std::vector<glm::dvec3> psr = potential_receivers(scene, request.camera_aspect);
  f.receivers_visible = !psr.empty();
  const bool fit = request.fit && f.receivers_visible;
  f.fitted = fit;

  if (!f.perspective) {
    double lo_x = 1e300, hi_x = -1e300, lo_y = 1e300, hi_y = -1e300, far_z = zmax;
    auto extend = [&](const glm::dvec3& p) {
      const glm::dvec4 q = glm::dmat4(f.view) * glm::dvec4(p, 1);
      lo_x = std::min(lo_x, q.x), hi_x = std::max(hi_x, q.x);
      lo_y = std::min(lo_y, q.y), hi_y = std::max(hi_y, q.y);
    };
    for (int i = 0; i < 8; ++i) extend(glm::dvec3(bounds.corner(i)));
    const double unfitted_side = std::max(hi_x - lo_x, hi_y - lo_y);
    if (fit) {
      lo_x = lo_y = 1e300, hi_x = hi_y = -1e300, far_z = -1e300;
      for (const auto& p : psr) {
        extend(p);
        far_z = std::max(far_z, -(glm::dmat4(f.view) * glm::dvec4(p, 1)).z);
      }
    }
    const double cx = (lo_x + hi_x) / 2, cy = (lo_y + hi_y) / 2;
    // Only a fitted frustum is padded: the unfitted one already spans every caster and receiver.
    const double tight_half = std::max({hi_x - lo_x, hi_y - lo_y, 1e-6}) / 2;
    const double half = fit ? padded_half(tight_half, request.resolution_texels, request.pad_texels, request.pad_ws) : tight_half;
    f.near_ws = zmin;
    f.far_ws = static_cast<float>(std::max(fit ? far_z + margin : far_z, static_cast<double>(zmin) + 1e-4));
    f.projection = glm::ortho(static_cast<float>(cx - half), static_cast<float>(cx + half),
                              static_cast<float>(cy - half), static_cast<float>(cy + half), f.near_ws, f.far_ws);
    f.extent_ws = static_cast<float>(2 * half);
    f.s_xy = fit ? static_cast<float>(unfitted_side / (2 * half)) : 1.0f;
    return f;
  }

  // Spot light: perspective projection, then a crop (fitting) matrix in clip space.
  f.fov_deg = light.spot_fov_deg;
  f.far_ws = std::max(zmax, 1e-2f);
  f.near_ws = std::clamp(zmin, f.far_ws * 1e-4f, f.far_ws * 0.999f);
  const glm::mat4 proj = spot_projection(light, f.near_ws, f.far_ws);
  const float tan_half = std::tan(glm::radians(f.fov_deg) / 2);
  f.extent_ws = 2 * f.near_ws * tan_half;
  f.projection = proj;
  f.s_xy = 1;
  if (fit) {
    double lo_x = 1e300, hi_x = -1e300, lo_y = 1e300, hi_y = -1e300;
    const glm::dmat4 vp(proj * f.view);
    for (const auto& p : psr) {
      const glm::dvec4 c = vp * glm::dvec4(p, 1);
      if (c.w <= 0) continue;
      lo_x = std::min(lo_x, c.x / c.w), hi_x = std::max(hi_x, c.x / c.w);
      lo_y = std::min(lo_y, c.y / c.w), hi_y = std::max(hi_y, c.y / c.w);
    }
    if (lo_x <= hi_x) {
      lo_x = std::max(lo_x, -1.0), hi_x = std::min(hi_x, 1.0), lo_y = std::max(lo_y, -1.0), hi_y = std::min(hi_y, 1.0);
      const double cx = (lo_x + hi_x) / 2, cy = (lo_y + hi_y) / 2;
      // pad_ws is taken at the near plane, where it spans the most clip-space units.
      const double pad_ndc = request.pad_ws / (f.near_ws * tan_half);
      double half = padded_half(std::max({hi_x - lo_x, hi_y - lo_y, 1e-6}) / 2, request.resolution_texels,
                                request.pad_texels, std::min(pad_ndc, 0.5));
      half = std::min(half, 1.0);
      glm::mat4 crop(1);
      crop[0][0] = static_cast<float>(1 / half);
      crop[1][1] = static_cast<float>(1 / half);
      crop[3][0] = static_cast<float>(-cx / half);
      crop[3][1] = static_cast<float>(-cy / half);
      f.projection = crop * proj;
      f.s_xy = static_cast<float>(1 / half);
    }
  }
  return f;
}

std::array<float, 2> receiver_depth_range(const scene::Scene& scene, float camera_aspect) {
  const scene::Camera& cam = scene.camera;
  const std::vector<glm::dvec3> psr = potential_receivers(scene, camera_aspect);
  if (psr.empty()) return {cam.near_ws, cam.far_ws};
  const glm::dmat4 view(cam.view());
  double lo = 1e300, hi = -1e300;
  for (const auto& p : psr) {
    const double z = -(view * glm::dvec4(p, 1)).z;
    lo = std::min(lo, z), hi = std::max(hi, z);
  }
  const float near_ws = std::clamp(static_cast<float>(lo), cam.near_ws, cam.far_ws);
  const float far_ws = std::clamp(static_cast<float>(hi), near_ws, cam.far_ws);
  return {near_ws, far_ws};
}

namespace {

// The eight world-space corners of the camera frustum between view depths z0 and z1.
std::array<glm::dvec3, 8> slice_corners(const scene::Camera& cam, float aspect, double z0, double z1) {
  const glm::dmat4 to_world = glm::inverse(glm::dmat4(cam.view()));
  std::array<glm::dvec3, 8> c{};
  const double tan_half = std::tan(glm::radians(static_cast<double>(cam.fov_y_deg)) / 2);
  for (int i = 0; i < 8; ++i) {
    const double z = (i & 4) ? z1 : z0;
    const double half_h = cam.projection == scene::Camera::Projection::perspective ? z * tan_half : cam.ortho_height_ws / 2.0;
    const double half_w = half_h * aspect;
    const glm::dvec4 p(((i & 1) ? half_w : -half_w), ((i & 2) ? half_h : -half_h), -z, 1);
    c[static_cast<std::size_t>(i)] = glm::dvec3(to_world * p);
  }
  return c;
}

}  // namespace

Cascades compute_cascades(const scene::Scene& scene, const CascadeRequest& request) {
  Cascades out;
  const auto res_of = [&](int i) {
    if (request.resolution_texels.empty()) return 2048;
    const std::size_t k = std::min(static_cast<std::size_t>(i), request.resolution_texels.size() - 1);
    return std::max(request.resolution_texels[k], 1);
  };
  FitRequest single{request.fit, request.camera_aspect, res_of(0), request.pad_texels, request.pad_ws};
  const std::array<float, 2> range = receiver_depth_range(scene, request.camera_aspect);
  if (scene.light.type == scene::Light::Type::spot || request.count <= 1 ||
      potential_receivers(scene, request.camera_aspect).empty()) {
    out.frames.push_back(compute_light_frame(scene, single));
    out.splits_ws = {range[0], range[1]};
    return out;
  }
  // The shared light view and depth range: those of the unfitted map (all casters).
  FitRequest unfitted = single;
  unfitted.fit = false;
  const LightFrame base = compute_light_frame(scene, unfitted);
  const double unfitted_side = base.extent_ws;
  const glm::dmat4 light_view(base.view);

  const std::vector<double> splits = adaptive::cascade_splits(range[0], range[1], request.count, request.lambda);
  for (double z : splits) out.splits_ws.push_back(static_cast<float>(z));
  const scene::Camera& cam = scene.camera;
  for (int i = 0; i < request.count; ++i) {
    const double z0 = splits[static_cast<std::size_t>(i)], z1 = splits[static_cast<std::size_t>(i) + 1];
    const int res = res_of(i);
    double cx = 0, cy = 0, half = 0;
    // The slice's receivers, clipped like the single fitted map.
    scene::Camera slice_camera = cam;
    slice_camera.near_ws = static_cast<float>(z0);
    slice_camera.far_ws = static_cast<float>(z1);
    Polyhedron psr = box_polyhedron(scene.bounds());
    for (const auto& plane : camera_planes(slice_camera, request.camera_aspect)) psr = clip(psr, plane);
    const std::vector<glm::dvec3> v = vertices(psr);
    if (!v.empty()) {
      double lo_x = 1e300, hi_x = -1e300, lo_y = 1e300, hi_y = -1e300;
      for (const auto& p : v) {
        const glm::dvec4 q = light_view * glm::dvec4(p, 1);
        lo_x = std::min(lo_x, q.x), hi_x = std::max(hi_x, q.x), lo_y = std::min(lo_y, q.y), hi_y = std::max(hi_y, q.y);
      }
      cx = (lo_x + hi_x) / 2, cy = (lo_y + hi_y) / 2;
      half = std::max({hi_x - lo_x, hi_y - lo_y, 1e-6}) / 2;
    } else {
      // Nothing of the scene in the slice: the bounding sphere of its corners.
      const auto corners = slice_corners(cam, request.camera_aspect, z0, z1);
      glm::dvec3 centre(0);
      for (const auto& c : corners) centre += c / 8.0;
      for (const auto& c : corners) half = std::max(half, glm::distance(c, centre));
      const glm::dvec4 q = light_view * glm::dvec4(centre, 1);
      cx = q.x, cy = q.y;
    }
    half = padded_half(half, res, request.pad_texels, request.pad_ws);
    if (request.stabilize) {
      // Size in quarter-octave steps, so that small camera moves keep it; room for the snap
      // (< 1 texel per side); the window's corner snapped to whole texels, so that a translating
      // camera moves the window in texel steps and rasterized edges stay put between steps.
      half = std::exp2(std::ceil(std::log2(half) * 4) / 4);
      half *= static_cast<double>(res) / std::max(res - 2, 1);
      const double texel = 2 * half / res;
      cx = std::floor(cx / texel) * texel;
      cy = std::floor(cy / texel) * texel;
    }
    LightFrame f = base;
    f.projection = glm::ortho(static_cast<float>(cx - half), static_cast<float>(cx + half), static_cast<float>(cy - half),
                              static_cast<float>(cy + half), base.near_ws, base.far_ws);
    f.extent_ws = static_cast<float>(2 * half);
    f.s_xy = static_cast<float>(unfitted_side / (2 * half));
    f.fitted = true;
    out.frames.push_back(f);
  }
  return out;
}

}  // namespace penumbra::shadows
