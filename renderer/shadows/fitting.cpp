#include "shadows/fitting.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <glm/gtc/matrix_transform.hpp>

#include "adaptive/cascades.h"

namespace penumbra::shadows {

namespace {

// A convex hexahedron from its eight corners (bit 0: x, bit 1: y, bit 2: z picks the far one).
Polyhedron hexahedron(const std::array<glm::dvec3, 8>& c) {
  const int faces[6][4] = {{0, 2, 6, 4}, {1, 5, 7, 3}, {0, 4, 5, 1}, {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 6, 7, 5}};
  Polyhedron p;
  for (const auto& f : faces) p.push_back({c[f[0]], c[f[1]], c[f[2]], c[f[3]]});
  return p;
}

}  // namespace

Polyhedron box_polyhedron(const scene::Aabb& b) {
  if (b.empty()) return {};
  std::array<glm::dvec3, 8> c{};
  for (int i = 0; i < 8; ++i) c[static_cast<std::size_t>(i)] = glm::dvec3(b.corner(i));
  return hexahedron(c);
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

// The camera frustum as clipping planes (world space).
std::array<glm::dvec4, 6> camera_planes(const scene::Camera& camera, float aspect) {
  return frustum_planes(glm::dmat4(camera.projection_matrix(aspect) * camera.view()));
}

// Whether every corner of `b` lies outside one of the planes (then b misses the convex volume
// they bound; a box that passes may still miss it near an edge, which only keeps a little more).
bool outside_a_plane(const scene::Aabb& b, const std::array<glm::dvec4, 6>& planes) {
  for (const auto& plane : planes) {
    bool all_out = true;
    for (int i = 0; i < 8 && all_out; ++i) all_out = glm::dot(glm::dvec3(plane), glm::dvec3(b.corner(i))) + plane.w < 0;
    if (all_out) return true;
  }
  return false;
}

// The bounds of the objects whose boxes reach into the volume the planes bound.
scene::Aabb bounds_within(const scene::Scene& scene, const std::array<glm::dvec4, 6>& planes) {
  scene::Aabb out;
  for (const auto& o : scene.objects) {
    const scene::Aabb b = o.mesh->bounds().transformed(o.model);
    if (!b.empty() && !outside_a_plane(b, planes)) out.extend(b);
  }
  return out;
}

// S of PSR = L ∩ V ∩ S: the bounds of the objects the camera sees or that lie within 1000 times
// the view's size of what it sees, not the scene's bounds: one object at x = 1e20 would stretch
// those across the whole view (and overflow the fit).
scene::Aabb near_view_bounds(const scene::Scene& scene, float aspect) {
  const scene::Camera& cam = scene.camera;
  scene::Aabb view;
  for (const auto& p : slice_corners(cam, aspect, cam.near_ws, cam.far_ws)) view.extend(glm::vec3(p));
  const double reach = 1000.0 * glm::length(glm::dvec3(view.hi - view.lo));
  const auto planes = camera_planes(cam, aspect);
  scene::Aabb out;
  for (const auto& o : scene.objects) {
    const scene::Aabb b = o.mesh->bounds().transformed(o.model);
    if (b.empty()) continue;
    double gap = 0;  // the distance between the two boxes
    for (int axis = 0; axis < 3; ++axis)
      gap = std::max({gap, static_cast<double>(b.lo[axis]) - view.hi[axis], static_cast<double>(view.lo[axis]) - b.hi[axis]});
    if (!outside_a_plane(b, planes) || gap <= reach) out.extend(b);
  }
  return out;
}

// The part of the box `b` inside the camera frustum between view depths z0 and z1. The frustum is
// clipped by the box's planes, not the box by the frustum: a box reaching 1e30 (one far-away
// object) would put cut points at 1e30 ± 1e14 in double precision; the frustum's corners stay
// where the camera is.
Polyhedron visible_part(const scene::Aabb& b, const scene::Camera& cam, float aspect, double z0, double z1) {
  if (b.empty()) return {};
  Polyhedron p = hexahedron(slice_corners(cam, aspect, z0, z1));
  for (int axis = 0; axis < 3; ++axis) {
    glm::dvec4 lo(0), hi(0);
    lo[axis] = 1, lo.w = -static_cast<double>(b.lo[axis]);  // x >= lo.x
    hi[axis] = -1, hi.w = static_cast<double>(b.hi[axis]);  // x <= hi.x
    p = clip(clip(p, lo), hi);
  }
  return p;
}

// A box in the light's rotation frame: x and y across the light, z the depth along it.
struct LightBox {
  glm::dvec3 lo{1e300}, hi{-1e300};
  bool empty() const { return lo.x > hi.x; }
  void extend(const glm::dvec3& p) { lo = glm::min(lo, p), hi = glm::max(hi, p); }
};

// World → the directional light's rotation frame (x, y across the light, depth along it).
glm::dmat3 light_rotation(const scene::Light& light) {
  const glm::dvec3 dir = glm::normalize(glm::dvec3(light.direction));
  const glm::dvec3 up = std::abs(dir.y) < 0.99 ? glm::dvec3(0, 1, 0) : glm::dvec3(0, 0, -1);
  return glm::dmat3(glm::lookAt(glm::dvec3(0), dir, up));
}

glm::dvec3 in_light_frame(const glm::dmat3& rotation, const glm::dvec3& p) {
  const glm::dvec3 q = rotation * p;
  return {q.x, q.y, -q.z};
}

LightBox light_box(const scene::Aabb& b, const glm::dmat3& rotation) {
  LightBox out;
  if (!b.empty())
    for (int i = 0; i < 8; ++i) out.extend(in_light_frame(rotation, glm::dvec3(b.corner(i))));
  return out;
}

// How far beyond the receivers (in multiples of their size) a directional map holds casters: a
// caster farther toward the light is depth-clamped onto the near plane (it still shadows), and no
// part of the scene farther across the light can cast onto a receiver. 1000 sizes keep every
// scene of the project whole and a far-away object (x = 1e20) out of the fit.
constexpr double kReachInReceiverSizes = 1000;

// The region a directional light's frame holds, in its rotation frame: the bounds of the objects
// that can cast onto the potential receivers (their boxes overlap the receivers' window across the
// light, padded by the receivers' size, and begin nearer the light than the farthest receiver),
// with the receivers, clipped to kReachInReceiverSizes around them. With nothing visible, the
// camera's frustum stands for the receivers.
LightBox shadow_region(const scene::Scene& scene, const std::vector<glm::dvec3>& psr, float aspect,
                       const glm::dmat3& rotation) {
  LightBox receivers;
  for (const auto& p : psr) receivers.extend(in_light_frame(rotation, p));
  if (receivers.empty())
    for (const auto& p : slice_corners(scene.camera, aspect, scene.camera.near_ws, scene.camera.far_ws))
      receivers.extend(in_light_frame(rotation, p));
  const glm::dvec3 extent = receivers.hi - receivers.lo;
  const double size = std::max({extent.x, extent.y, extent.z, 1e-3});
  scene::Aabb kept;
  for (const auto& o : scene.objects) {
    const scene::Aabb b = o.mesh->bounds().transformed(o.model);
    const LightBox l = light_box(b, rotation);
    if (l.empty()) continue;
    const bool across = l.lo.x <= receivers.hi.x + size && l.hi.x >= receivers.lo.x - size && l.lo.y <= receivers.hi.y + size &&
                        l.hi.y >= receivers.lo.y - size;
    if (across && l.lo.z <= receivers.hi.z + size) kept.extend(b);
  }
  LightBox region = light_box(kept, rotation);  // the box of the kept objects' bounds, as the map's unfitted extent
  region.extend(receivers.lo);
  region.extend(receivers.hi);
  const double reach = kReachInReceiverSizes * size;
  region.lo = glm::max(region.lo, receivers.lo - reach);
  region.hi = glm::min(region.hi, receivers.hi + reach);
  return region;
}


// What a directional light's shadows hold in `rotation`'s frame: shadow_region, or for a scene
// without objects the unit box around the origin (every matrix stays finite).
LightBox sun_region(const scene::Scene& scene, const std::vector<glm::dvec3>& psr, float aspect, const glm::dmat3& rotation) {
  if (!scene.objects.empty()) return shadow_region(scene, psr, aspect, rotation);
  scene::Aabb unit;
  unit.extend(glm::vec3(-0.5f));
  unit.extend(glm::vec3(0.5f));
  return light_box(unit, rotation);
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
  const scene::Aabb seen = near_view_bounds(scene, camera_aspect);
  Polyhedron psr = visible_part(seen, scene.camera, camera_aspect, scene.camera.near_ws, scene.camera.far_ws);
  if (scene.light.type == scene::Light::Type::spot && !psr.empty()) {
    // The cone's far end: the farthest visible receiver (the scene's bounds may reach 1e30).
    const glm::dmat4 view(light_view(scene.light, {}, 0));
    double far = 0;
    for (const auto& p : vertices(psr)) far = std::max(far, -(view * glm::dvec4(p, 1)).z);
    // 1 % beyond it: receivers lying on the far plane (a flat ground seen from above) must not be
    // lost to the float rounding of the cone's planes.
    const float far_ws = static_cast<float>(far * 1.01);
    const glm::mat4 proj = spot_projection(scene.light, std::max(far_ws * 1e-4f, 1e-3f), std::max(far_ws, 1e-2f));
    for (const auto& plane : frustum_planes(glm::dmat4(proj) * view)) psr = clip(psr, plane);
  }
  return vertices(psr);
}

namespace {

// Every number of a light frame is finite and its depth range is not empty: the fit bounds what it
// holds (shadow_region), so a frame that is not is a defect here, refused before it reaches a map
// or a report.json as null.
LightFrame checked(const LightFrame& f) {
  bool finite = std::isfinite(f.near_ws) && std::isfinite(f.far_ws) && std::isfinite(f.extent_ws) && std::isfinite(f.s_xy) &&
                f.far_ws > f.near_ws && f.extent_ws > 0;
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) finite = finite && std::isfinite(f.view[c][r]) && std::isfinite(f.projection[c][r]);
  if (!finite)
    throw std::runtime_error("light fit: the shadow map's frame is not finite (near " + std::to_string(f.near_ws) + ", far " +
                             std::to_string(f.far_ws) + ", extent " + std::to_string(f.extent_ws) + ")");
  return f;
}

}  // namespace

LightFrame compute_light_frame(const scene::Scene& scene, const FitRequest& request) {
  LightFrame f;
  const scene::Light& light = scene.light;
  scene::Aabb bounds = scene.bounds();
  if (bounds.empty()) {  // nothing to shadow: a unit box keeps every matrix finite
    bounds.extend(glm::vec3(-0.5f));
    bounds.extend(glm::vec3(0.5f));
  }
  f.perspective = light.type == scene::Light::Type::spot;
  const std::vector<glm::dvec3> psr = potential_receivers(scene, request.camera_aspect);
  f.receivers_visible = !psr.empty();
  const bool fit = request.fit && f.receivers_visible;
  f.fitted = fit;

  if (!f.perspective) {
    // The view is centred on the region that can cast onto what the camera sees, not on the
    // scene's bounds: one object at 1e20 would otherwise put every receiver 1e20 from the origin
    // of a float matrix.
    const glm::dmat3 rotation = light_rotation(light);
    const LightBox region = sun_region(scene, psr, request.camera_aspect, rotation);
    glm::dvec3 mid = (region.lo + region.hi) * 0.5;
    const double radius = std::max(glm::length(region.hi - region.lo) * 0.5, 1e-3);
    // The view's axis through the scene's centre, as long as that lies within the region's reach:
    // it does not move with the camera, so stabilized cascades snap to a fixed texel grid.
    const glm::dvec3 scene_mid = in_light_frame(rotation, glm::dvec3((bounds.lo + bounds.hi) * 0.5f));
    if (std::abs(scene_mid.x - mid.x) <= kReachInReceiverSizes * radius && std::abs(scene_mid.y - mid.y) <= kReachInReceiverSizes * radius)
      mid.x = scene_mid.x, mid.y = scene_mid.y;
    const glm::dvec3 centre_ws = glm::transpose(rotation) * glm::dvec3(mid.x, mid.y, -mid.z);
    f.view = light_view(light, glm::vec3(centre_ws), static_cast<float>(2 * radius));
    // Light-view depth range of the region (all casters that matter and the receivers). A margin
    // keeps surfaces lying exactly on the near or far plane off the depth range's ends, where
    // quantization would make a receiver shadow itself.
    const double to_view_depth = 2 * radius - mid.z;
    const double margin = 0.01 * std::max(region.hi.z - region.lo.z, 1e-3);
    const double zmin = region.lo.z + to_view_depth - margin, zmax = region.hi.z + to_view_depth + margin;
    // Across the light, relative to the view's axis.
    double lo_x = region.lo.x - mid.x, hi_x = region.hi.x - mid.x, lo_y = region.lo.y - mid.y, hi_y = region.hi.y - mid.y;
    double far_z = zmax;
    auto extend = [&](const glm::dvec3& p) {
      const glm::dvec4 q = glm::dmat4(f.view) * glm::dvec4(p, 1);
      lo_x = std::min(lo_x, q.x), hi_x = std::max(hi_x, q.x);
      lo_y = std::min(lo_y, q.y), hi_y = std::max(hi_y, q.y);
    };
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
    f.near_ws = static_cast<float>(zmin);
    f.far_ws = static_cast<float>(std::max(fit ? far_z + margin : far_z, zmin + 1e-4));
    f.projection = glm::ortho(static_cast<float>(cx - half), static_cast<float>(cx + half),
                              static_cast<float>(cy - half), static_cast<float>(cy + half), f.near_ws, f.far_ws);
    f.extent_ws = static_cast<float>(2 * half);
    f.s_xy = fit ? static_cast<float>(unfitted_side / (2 * half)) : 1.0f;
    return checked(f);
  }

  // Spot light: the scene's depth range along the light, its far end the farthest visible
  // receiver when there is one (nothing beyond it can cast onto what the camera sees).
  f.view = light_view(light, {}, 0);
  const glm::dmat4 view(f.view);
  auto depth_range = [&](const scene::Aabb& b) {
    double lo = 1e300, hi = -1e300;
    for (int i = 0; i < 8; ++i) {
      const double z = -(view * glm::dvec4(glm::dvec3(b.corner(i)), 1)).z;
      lo = std::min(lo, z), hi = std::max(hi, z);
    }
    return std::array<double, 2>{lo, hi};
  };
  auto [zmin, zmax] = depth_range(bounds);
  if (!psr.empty()) {
    double receivers_far = -1e300;
    for (const auto& p : psr) receivers_far = std::max(receivers_far, -(view * glm::dvec4(p, 1)).z);
    // The casters: the objects in the cone up to the farthest receiver.
    const glm::dmat4 cone(spot_projection(light, std::max(static_cast<float>(receivers_far) * 1e-4f, 1e-3f),
                                          std::max(static_cast<float>(receivers_far), 1e-2f)));
    const scene::Aabb casters = bounds_within(scene, frustum_planes(cone * view));
    if (!casters.empty()) zmin = depth_range(casters)[0];
    zmax = std::min(zmax, receivers_far);
    zmin = std::min(zmin, zmax);
  }
  // Nothing behind the light by more than the far end can matter (it casts away from the cone).
  const double margin = 0.01 * std::max(zmax - std::max(zmin, -zmax), 1e-3);
  zmin -= margin;
  zmax += margin;

  // Perspective projection, then a crop (fitting) matrix in clip space.
  f.fov_deg = light.spot_fov_deg;
  f.far_ws = std::max(static_cast<float>(zmax), 1e-2f);
  f.near_ws = std::clamp(static_cast<float>(zmin), f.far_ws * 1e-4f, f.far_ws * 0.999f);
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
  return checked(f);
}

float shadow_region_diagonal_ws(const scene::Scene& scene, float camera_aspect) {
  if (scene.objects.empty()) return 1.0f;
  const SunRegion region = sun_shadow_region(scene, camera_aspect, light_rotation(scene.light));
  return static_cast<float>(glm::length(region.hi - region.lo));
}

SunRegion sun_shadow_region(const scene::Scene& scene, float camera_aspect, const glm::dmat3& rotation) {
  const LightBox region = sun_region(scene, potential_receivers(scene, camera_aspect), camera_aspect, rotation);
  return {region.lo, region.hi};
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

  const scene::Aabb seen = near_view_bounds(scene, request.camera_aspect);
  const std::vector<double> splits = adaptive::cascade_splits(range[0], range[1], request.count, request.lambda);
  for (double z : splits) out.splits_ws.push_back(static_cast<float>(z));
  const scene::Camera& cam = scene.camera;
  for (int i = 0; i < request.count; ++i) {
    const double z0 = splits[static_cast<std::size_t>(i)], z1 = splits[static_cast<std::size_t>(i) + 1];
    const int res = res_of(i);
    double cx = 0, cy = 0, half = 0;
    // The slice's receivers, clipped like the single fitted map.
    const std::vector<glm::dvec3> v = vertices(visible_part(seen, cam, request.camera_aspect, z0, z1));
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
