#include "scene/outdoor.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "sampling/random.h"

namespace penumbra::scene {
namespace {

constexpr float kPi = std::numbers::pi_v<float>;

using sampling::Random;

// The town is built in float: a draw from the one Random, narrowed.
float uniform(Random& rng, float lo, float hi) { return static_cast<float>(rng.uniform(lo, hi)); }

// Independent streams per part of the scene, so that changing one part leaves the others as
// they were for the same seed.
std::uint64_t stream(std::uint64_t seed, std::uint64_t part) { return sampling::derive_seed(seed, part); }

glm::mat4 translate(glm::vec3 t) { return glm::translate(glm::mat4(1), t); }

void add_box(MeshData& m, glm::vec3 centre, glm::vec3 size) { m.append(make_box(size), translate(centre)); }
void add_beam(MeshData& m, glm::vec3 a, glm::vec3 b, float width) { m.append(make_beam(a, b, width), glm::mat4(1)); }

// --- the layout -----------------------------------------------------------------------------

constexpr float kTownHalf = 140;     // the town: blocks on a 40 m grid inside ±140 m
constexpr float kBlockPitch = 40;
constexpr float kBlockHalf = 14;     // blocks 28 m wide, streets 12 m wide
constexpr float kGroundHalf = 300;
constexpr int kGroundCells = 320;    // per side: 1.9 m cells
constexpr int kGroundTile = 20;      // cells per side of one draw unit: 16 × 16 tiles of 37.5 m
const glm::vec3 kCraneBase{-4, 0, 4};  // in the construction-site block centred on the origin
constexpr float kMastHeight = 45;

// Block centres -120, -80, ..., 120.
float block_centre(int k) { return -kTownHalf + kBlockPitch / 2 + kBlockPitch * static_cast<float>(k); }
constexpr int kBlocks = 7;
// Street centre lines run at ±20, ±60, ±100, ±140.
float street_centre(int k) { return -kTownHalf + kBlockPitch * static_cast<float>(k); }

// Smooth value noise in [0, 1) on a grid of `cell` metres.
float lattice_value(int ix, int iz, std::uint64_t seed) {
  const std::uint64_t cell = static_cast<std::uint64_t>(static_cast<std::uint32_t>(ix)) << 32 | static_cast<std::uint32_t>(iz);
  return static_cast<float>(stream(seed, cell) >> 40) * 0x1p-24f;
}
float value_noise(float x, float z, float cell, std::uint64_t seed) {
  const float fx = x / cell, fz = z / cell;
  const float x0 = std::floor(fx), z0 = std::floor(fz);
  const auto fade = [](float t) { return t * t * t * (t * (t * 6 - 15) + 10); };
  const float tx = fade(fx - x0), tz = fade(fz - z0);
  const int ix = static_cast<int>(x0), iz = static_cast<int>(z0);
  const float a = lattice_value(ix, iz, seed), b = lattice_value(ix + 1, iz, seed);
  const float c = lattice_value(ix, iz + 1, seed), d = lattice_value(ix + 1, iz + 1, seed);
  return (a + (b - a) * tx) * (1 - tz) + (c + (d - c) * tx) * tz;
}

// Terrain height: flat under the town, hills up to ~14 m rising over the 150-230 m ring.
float terrain_height(float x, float z, std::uint64_t seed) {
  const float d = std::max(std::abs(x), std::abs(z));
  const float t = std::clamp((d - 150) / 80, 0.0f, 1.0f);
  const float w = t * t * (3 - 2 * t);
  if (w == 0) return 0;
  const float n = 10 * value_noise(x, z, 120, seed) + 4 * value_noise(x, z, 55, seed + 1) + 1.5f * value_noise(x, z, 23, seed + 2);
  return w * n;
}

MeshData make_ground(std::uint64_t seed) {
  MeshData m;
  const int n = kGroundCells;
  const float cell = 2 * kGroundHalf / static_cast<float>(n);
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) {
      const float x = -kGroundHalf + cell * static_cast<float>(i), z = -kGroundHalf + cell * static_cast<float>(j);
      const float e = 0.5f;  // central differences for the normal
      const float dx = terrain_height(x + e, z, seed) - terrain_height(x - e, z, seed);
      const float dz = terrain_height(x, z + e, seed) - terrain_height(x, z - e, seed);
      m.vertices.push_back({{x, terrain_height(x, z, seed), z}, glm::normalize(glm::vec3(-dx, 2 * e, -dz))});
    }
  }
  // One draw unit per tile of kGroundTile × kGroundTile cells, so that culling can drop ground
  // outside a map or the view.
  const auto row = static_cast<std::uint32_t>(n + 1);
  const auto tile = static_cast<std::uint32_t>(kGroundTile), cells = static_cast<std::uint32_t>(n);
  for (std::uint32_t tj = 0; tj < cells; tj += tile)
    for (std::uint32_t ti = 0; ti < cells; ti += tile) {
      for (std::uint32_t j = tj; j < std::min(tj + tile, cells); ++j)
        for (std::uint32_t i = ti; i < std::min(ti + tile, cells); ++i) {
          const std::uint32_t a = j * row + i, b = a + 1, c = a + row, d = c + 1;
          m.indices.insert(m.indices.end(), {a, c, b, b, c, d});  // counter-clockwise seen from above
        }
      m.close_unit();
    }
  return m;
}

// --- buildings ------------------------------------------------------------------------------

void add_building(MeshData& m, Random& rng, glm::vec2 centre, glm::vec2 size, float height) {
  const glm::vec3 c(centre.x, 0, centre.y);
  add_box(m, c + glm::vec3(0, height / 2, 0), {size.x, height, size.y});
  float top = height;
  glm::vec2 roof = size;
  // A setback tower on some tall buildings.
  if (height > 25 && rng.chance(0.4f)) {
    const glm::vec2 tower = size - glm::vec2(uniform(rng, 4, 7), uniform(rng, 4, 7));
    if (tower.x > 5 && tower.y > 5) {
      const float extra = 3.5f * static_cast<float>(rng.integer(2, 6));
      add_box(m, c + glm::vec3(0, height + extra / 2, 0), {tower.x, extra, tower.y});
      top = height + extra;
      roof = tower;
    }
  }
  m.close_unit();  // body and tower
  // Floor ledges (thin slabs around the facade) on about half of the buildings.
  if (rng.chance(0.5f)) {
    const float protrude = uniform(rng, 0.2f, 0.5f);
    for (float y = 3.5f; y < height - 1; y += 3.5f) add_box(m, c + glm::vec3(0, y, 0), {size.x + 2 * protrude, 0.2f, size.y + 2 * protrude});
    m.close_unit();  // ledges
  }
  // Parapet around the roof.
  const float ph = 1.0f, pw = 0.3f;
  const float hx = roof.x / 2 - pw / 2, hz = roof.y / 2 - pw / 2;
  add_box(m, c + glm::vec3(0, top + ph / 2, hz), {roof.x, ph, pw});
  add_box(m, c + glm::vec3(0, top + ph / 2, -hz), {roof.x, ph, pw});
  add_box(m, c + glm::vec3(hx, top + ph / 2, 0), {pw, ph, roof.y - 2 * pw});
  add_box(m, c + glm::vec3(-hx, top + ph / 2, 0), {pw, ph, roof.y - 2 * pw});
  m.close_unit();  // parapet
  // Rooftop units, one draw unit each.
  for (int i = rng.integer(0, 3); i > 0; --i) {
    const glm::vec3 unit(uniform(rng, 1.5f, 4), uniform(rng, 1.2f, 3), uniform(rng, 1.5f, 4));
    const float ux = uniform(rng, -1, 1) * std::max(roof.x / 2 - unit.x / 2 - 1, 0.0f);
    const float uz = uniform(rng, -1, 1) * std::max(roof.y / 2 - unit.z / 2 - 1, 0.0f);
    add_box(m, c + glm::vec3(ux, top + unit.y / 2, uz), unit);
    m.close_unit();
  }
  // A thin antenna on the tallest.
  if (top > 40) {
    const glm::vec3 base = c + glm::vec3(uniform(rng, -1, 1) * roof.x / 4, top, uniform(rng, -1, 1) * roof.y / 4);
    m.append(make_tube({base, base + glm::vec3(0, uniform(rng, 5, 9), 0)}, {0.06f, 0.04f}, 6), glm::mat4(1));
  }
}

MeshData make_buildings(std::uint64_t seed) {
  Random rng(stream(seed, 1));
  MeshData m;
  for (int bz = 0; bz < kBlocks; ++bz) {
    for (int bx = 0; bx < kBlocks; ++bx) {
      const glm::vec2 block(block_centre(bx), block_centre(bz));
      if (block == glm::vec2(0, 0) || block == glm::vec2(-40, 0)) continue;  // construction site, park
      // Whole block, two halves (along x or z) or four quarters.
      const int split = rng.integer(0, 3);
      std::vector<std::pair<glm::vec2, glm::vec2>> lots;  // centre, size
      const float b = kBlockHalf;
      if (split == 0) {
        lots.push_back({block, {2 * b, 2 * b}});
      } else if (split == 1) {
        lots.push_back({block + glm::vec2(-b / 2, 0), {b, 2 * b}});
        lots.push_back({block + glm::vec2(b / 2, 0), {b, 2 * b}});
      } else if (split == 2) {
        lots.push_back({block + glm::vec2(0, -b / 2), {2 * b, b}});
        lots.push_back({block + glm::vec2(0, b / 2), {2 * b, b}});
      } else {
        for (float sx : {-1.0f, 1.0f})
          for (float sz : {-1.0f, 1.0f}) lots.push_back({block + glm::vec2(sx, sz) * (b / 2), {b, b}});
      }
      const float from_centre = glm::length(block);
      const float from_crane = glm::length(block - glm::vec2(kCraneBase.x, kCraneBase.z));
      for (const auto& [centre, lot] : lots) {
        const glm::vec2 size = lot - glm::vec2(uniform(rng, 1, 3), uniform(rng, 1, 3));
        float floors = static_cast<float>(rng.integer(2, 6)) + std::round(uniform(rng, 0, 14) * std::exp(-from_centre * from_centre / 9000));
        if (from_crane < 70) floors = std::min(floors, 10.0f);  // the jib swings at 45 m
        add_building(m, rng, centre, size, 3.5f * floors);
        m.close_unit();  // the antenna, if any
      }
    }
  }
  return m;
}

// --- the construction site ------------------------------------------------------------------

MeshData make_site() {
  MeshData m;
  add_box(m, kCraneBase + glm::vec3(0, 0.5f, 0), {6, 1, 6});                    // crane footing
  m.close_unit();
  add_box(m, {8, 1.3f, 9}, {6.1f, 2.6f, 2.45f});                               // container
  m.close_unit();
  for (int i = 0; i < 3; ++i) add_box(m, {-10 + 1.4f * static_cast<float>(i), 0.4f, -9}, {1.2f, 0.8f, 1.2f});  // pallets
  m.close_unit();
  // A three-storey concrete frame: columns on a 5 m grid and floor slabs, the top one half done.
  const float x0 = 2, z0 = -10;
  for (int level = 0; level < 3; ++level) {
    const float y = 3.5f * static_cast<float>(level);
    const float depth = level == 2 ? 5.0f : 10.0f;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < (level == 2 ? 2 : 3); ++j)
        add_box(m, {x0 + 5 * static_cast<float>(i), y + 1.75f, z0 + 5 * static_cast<float>(j)}, {0.4f, 3.5f, 0.4f});
    add_box(m, {x0 + 5, y + 3.65f, z0 + depth / 2}, {10.6f, 0.3f, depth + 0.6f});
    m.close_unit();  // one storey of the frame
  }
  return m;
}

// Repeating parts are instances: one mesh, placed by each instance's model matrix (an engine's
// instanced draw; here one object per instance sharing the mesh, so that every consumer of
// Scene::objects, the GPU upload included, sees them without a second path).
struct Instanced {
  std::string name;
  std::shared_ptr<const MeshData> mesh;
  std::vector<glm::mat4> at;
};

std::shared_ptr<const MeshData> share(MeshData m) { return std::make_shared<const MeshData>(std::move(m)); }

// Tower crane: mast of square lattice panels, a triangular jib to the south (+z) and a flat
// counter-jib to the north, all at the mast's top. Each mast and jib panel (with its pieces of
// the chords) is an instance of one of two panels, their diagonals zigzagging in turn; the rest
// (slewing unit, cab, apex, counter-jib, pendants, trolley and hook) is one mesh.
struct Crane {
  MeshData body;
  std::vector<Instanced> panels;
};

Crane make_crane() {
  Crane crane;
  MeshData& m = crane.body;
  const glm::vec3 b = kCraneBase + glm::vec3(0, 1, 0);  // on the footing
  const float half = 0.9f, panel = 1.8f, chord = 0.14f, member = 0.08f;
  const int panels = static_cast<int>(std::round(kMastHeight / panel));
  const float top = b.y + panel * static_cast<float>(panels);
  const std::array<glm::vec2, 4> corner = {glm::vec2(-half, -half), glm::vec2(half, -half), glm::vec2(half, half), glm::vec2(-half, half)};
  // A corner at height y, relative to the mast's axis (panels) or in the world (the body).
  const auto local = [&](int c, float y) { return glm::vec3(corner[static_cast<std::size_t>(c)].x, y, corner[static_cast<std::size_t>(c)].y); };
  const auto at = [&](int c, float y) { return glm::vec3(b.x, 0, b.z) + local(c, y); };
  for (int parity = 0; parity < 2; ++parity) {
    MeshData p;  // from y = 0 to y = panel about the mast's axis
    for (int c = 0; c < 4; ++c) {
      const int d = (c + 1) % 4;
      add_beam(p, local(c, 0), local(c, panel), chord);
      add_beam(p, local(c, panel), local(d, panel), member);
      if (parity == 0) add_beam(p, local(c, 0), local(d, panel), member);  // zigzag diagonals on every face
      else add_beam(p, local(d, 0), local(c, panel), member);
    }
    Instanced mast{"crane", share(std::move(p)), {}};
    for (int i = parity; i < panels; i += 2) mast.at.push_back(translate({b.x, b.y + panel * static_cast<float>(i), b.z}));
    crane.panels.push_back(std::move(mast));
  }
  // Slewing unit, cab and apex.
  add_box(m, {b.x, top + 0.75f, b.z}, {2.4f, 1.5f, 2.4f});
  add_box(m, {b.x + 1.9f, top + 1.2f, b.z + 1.0f}, {1.4f, 2.0f, 1.8f});
  const float deck = top + 1.5f;
  const glm::vec3 apex(b.x, deck + 7, b.z);
  for (int c = 0; c < 4; ++c) add_beam(m, at(c, deck), apex, chord);
  m.close_unit();  // slewing unit, cab and apex

  // Jib: bottom chords at x = ±0.7, top chord 1.5 m above the middle, 1.25 m panels to 50 m.
  const float jib_length = 50, jib_panel = 1.25f, jib_half = 0.7f, jib_height = 1.5f, jib_member = 0.06f, jib_chord = 0.12f;
  const int jib_panels = static_cast<int>(jib_length / jib_panel);
  const auto left = [&](float z) { return glm::vec3(-jib_half, 0, z); };  // about the jib's root
  const auto right = [&](float z) { return glm::vec3(jib_half, 0, z); };
  const auto ridge = [&](float z) { return glm::vec3(0, jib_height, z); };
  const glm::vec3 root(b.x, deck, b.z + half);
  for (int parity = 0; parity < 2; ++parity) {
    MeshData p;  // from z = 0 to z = jib_panel along the jib
    const float z1 = jib_panel;
    add_beam(p, left(0), left(z1), jib_chord);
    add_beam(p, right(0), right(z1), jib_chord);
    add_beam(p, ridge(0), ridge(z1), jib_chord);
    add_beam(p, left(0), right(0), jib_member);
    add_beam(p, left(0), ridge(0), jib_member);
    add_beam(p, right(0), ridge(0), jib_member);
    add_beam(p, left(0), ridge(z1), jib_member);
    add_beam(p, right(0), ridge(z1), jib_member);
    if (parity == 0) add_beam(p, left(0), right(z1), jib_member);
    else add_beam(p, right(0), left(z1), jib_member);
    Instanced jib{"crane", share(std::move(p)), {}};
    for (int i = parity; i < jib_panels; i += 2) jib.at.push_back(translate(root + glm::vec3(0, 0, jib_panel * static_cast<float>(i))));
    crane.panels.push_back(std::move(jib));
  }
  const glm::vec3 tip = root + glm::vec3(0, 0, jib_length);  // the last panel's far end
  add_beam(m, tip + left(0), tip + right(0), jib_member);
  add_beam(m, tip + left(0), tip + ridge(0), jib_member);
  add_beam(m, tip + right(0), tip + ridge(0), jib_member);
  m.close_unit();
  // Counter-jib: flat, 15 m to the north, with counterweights at its end.
  const float counter_length = 15, counter_half = 0.9f;
  const auto cl = [&](float z) { return glm::vec3(b.x - counter_half, deck, b.z - half - z); };
  const auto cr = [&](float z) { return glm::vec3(b.x + counter_half, deck, b.z - half - z); };
  add_beam(m, cl(0), cl(counter_length), jib_chord);
  add_beam(m, cr(0), cr(counter_length), jib_chord);
  for (int p = 0; p <= 10; ++p) {
    const float z = 1.5f * static_cast<float>(p);
    add_beam(m, cl(z), cr(z), jib_member);
    if (p < 10) add_beam(m, cl(z), cr(z + 1.5f), jib_member);
  }
  for (int i = 0; i < 3; ++i) add_box(m, {b.x, deck - 1.3f, b.z - half - 11.5f - 1.1f * static_cast<float>(i)}, {2.2f, 2.6f, 1.0f});
  m.close_unit();  // counter-jib and counterweights
  // Pendants from the apex to the jib and the counter-jib; the trolley's hook cable and block.
  m.append(make_tube({apex, root + ridge(32)}, {0.03f, 0.03f}, 4), glm::mat4(1));
  m.append(make_tube({apex, glm::vec3(b.x, deck, b.z - half - counter_length)}, {0.03f, 0.03f}, 4), glm::mat4(1));
  const glm::vec3 trolley(b.x, deck - 0.3f, b.z + half + 28);
  add_box(m, trolley, {1.6f, 0.5f, 1.2f});
  m.append(make_tube({trolley, trolley - glm::vec3(0, 24, 0)}, {0.025f, 0.025f}, 4), glm::mat4(1));
  add_box(m, trolley - glm::vec3(0, 24.5f, 0), {0.6f, 1.0f, 0.4f});
  m.close_unit();  // pendants, trolley and hook
  return crane;
}

// 2 m mesh fence along the site block's edges (vertical bars every ~0.17 m), with a gate gap on
// the north side: instances of one panel (its lattice and the post at its -x end).
Instanced make_fence() {
  const float edge = kBlockHalf - 0.5f, panel = 2.5f, height = 2.0f;
  MeshData p;
  p.append(make_lattice(panel, height, 16, 3, 0.035f), translate({0, height / 2 + 0.05f, 0}));
  add_box(p, {-panel / 2, 1.1f, 0}, {0.08f, 2.2f, 0.08f});
  Instanced fence{"fence", share(std::move(p)), {}};
  const int panels = static_cast<int>(std::floor(2 * edge / panel));
  const float start = -panel * static_cast<float>(panels) / 2;
  for (int side = 0; side < 4; ++side) {
    // Along x on the south and north sides, along z (the panel's -x end toward -z) on the others.
    const float angle = side < 2 ? 0.0f : -kPi / 2;
    const float offset = side % 2 == 0 ? edge : -edge;
    for (int i = 0; i < panels; ++i) {
      const float u = start + panel * (static_cast<float>(i) + 0.5f);
      if (side == 1 && std::abs(u) < panel) continue;  // the gate, on the north (street) side
      const glm::vec3 at = side < 2 ? glm::vec3(u, 0, offset) : glm::vec3(offset, 0, u);
      fence.at.push_back(glm::rotate(translate(at), angle, glm::vec3(0, 1, 0)));
    }
  }
  return fence;
}

// --- trees ----------------------------------------------------------------------------------

constexpr int kTreeLevels = 5;

// Any unit vector perpendicular to `v`.
glm::vec3 perpendicular(glm::vec3 v) {
  const glm::vec3 helper = std::abs(v.y) < 0.9f ? glm::vec3(0, 1, 0) : glm::vec3(1, 0, 0);
  return glm::normalize(glm::cross(helper, v));
}

// One branch (a slightly bent tapered tube) and, recursively, its children.
void grow(MeshData& m, Random& rng, glm::vec3 base, glm::vec3 dir, float length, float radius, int level) {
  const glm::vec3 side = perpendicular(dir);
  const glm::vec3 bend = glm::normalize(side * std::cos(uniform(rng, 0, 2 * kPi)) + glm::cross(dir, side) * std::sin(uniform(rng, 0, 2 * kPi)));
  const glm::vec3 mid = base + dir * (0.5f * length) + bend * (0.06f * length);
  const glm::vec3 tip = base + dir * length + bend * (0.02f * length);
  const int sides = std::max(3, 8 - level);
  m.append(make_tube({base, mid, tip}, {radius, 0.85f * radius, 0.7f * radius}, sides), glm::mat4(1));
  if (level == 0) m.close_unit();  // the trunk
  if (level == kTreeLevels) return;
  const int children = level == 0 ? rng.integer(3, 4) : rng.integer(2, 3);
  const float spin = uniform(rng, 0, 2 * kPi);
  for (int c = 0; c < children; ++c) {
    const bool leader = c == 0;
    const float t = leader ? 1.0f : uniform(rng, 0.55f, 0.95f);
    const glm::vec3 from = t < 0.5f ? base + (mid - base) * (2 * t) : mid + (tip - mid) * (2 * t - 1);
    const float azimuth = spin + 2 * kPi * static_cast<float>(c) / static_cast<float>(children) + uniform(rng, -0.4f, 0.4f);
    const float tilt = glm::radians(leader ? uniform(rng, 10, 25) : uniform(rng, 30, 55));
    const glm::vec3 out = side * std::cos(azimuth) + glm::cross(dir, side) * std::sin(azimuth);
    glm::vec3 child = glm::normalize(dir * std::cos(tilt) + out * std::sin(tilt) + glm::vec3(0, 0.12f, 0));
    grow(m, rng, from, child, length * uniform(rng, 0.66f, 0.8f), radius * (leader ? 0.68f : uniform(rng, 0.5f, 0.62f)), level + 1);
    if (level == 0) m.close_unit();  // each main limb with its branches: one draw unit
  }
}

void add_tree(MeshData& m, Random& rng, glm::vec3 at) {
  const float trunk = uniform(rng, 2.6f, 4.0f);
  const glm::vec3 lean = glm::vec3(uniform(rng, -0.08f, 0.08f), 1, uniform(rng, -0.08f, 0.08f));
  grow(m, rng, at - glm::vec3(0, 0.2f, 0), glm::normalize(lean), trunk, uniform(rng, 0.16f, 0.26f), 0);
}

MeshData make_trees(std::uint64_t seed) {
  Random rng(stream(seed, 2));
  MeshData m;
  // Street trees on both sides of the two main streets (z = -20 and x = -20), clear of crossings.
  for (float along = -132; along <= 132; along += 11) {
    bool crossing = false;
    for (int k = 0; k <= kBlocks; ++k) crossing = crossing || std::abs(along - street_centre(k)) < 8;
    if (crossing) continue;
    for (float side : {-4.6f, 4.6f}) {
      add_tree(m, rng, {along + uniform(rng, -0.5f, 0.5f), 0, -20 + side});
      if (along > -112 && along < 112) add_tree(m, rng, {-20 + side, 0, along + uniform(rng, -0.5f, 0.5f)});
    }
  }
  // The park block west of the site.
  for (int i = 0; i < 14; ++i) add_tree(m, rng, {-40 + uniform(rng, -12, 12), 0, uniform(rng, -12, 12)});
  // Countryside: scattered outside the town, on the terrain.
  for (int planted = 0; planted < 150;) {
    const float x = uniform(rng, -285, 285), z = uniform(rng, -285, 285);
    if (std::max(std::abs(x), std::abs(z)) < 152) continue;
    add_tree(m, rng, {x, terrain_height(x, z, seed), z});
    ++planted;
  }
  return m;
}

// --- poles and wires ------------------------------------------------------------------------

struct PoleLine {
  std::vector<glm::vec3> feet;  // pole positions on the ground
};

// A sagging wire from a to b: a parabola through both ends `sag` below their midpoint.
MeshData make_wire(glm::vec3 a, glm::vec3 b, float sag) {
  std::vector<glm::vec3> points;
  std::vector<float> radii;
  const int segments = 20;
  for (int i = 0; i <= segments; ++i) {
    const float t = static_cast<float>(i) / segments;
    points.push_back(a + (b - a) * t - glm::vec3(0, 4 * sag * t * (1 - t), 0));
    radii.push_back(0.0125f);
  }
  return make_tube(points, radii, 4);
}

void make_pole_lines(std::uint64_t seed, MeshData& poles, MeshData& wires) {
  Random rng(stream(seed, 3));
  std::vector<PoleLine> lines(2);
  // Along the south side of the walking street and on into the country; along the site's east street.
  for (float x = -130; x <= 270; x += 40) lines[0].feet.push_back({x, terrain_height(x, -14.8f, seed), -14.8f});
  for (float z = -130; z <= 110; z += 40)
    if (std::abs(z + 14.8f) > 3) lines[1].feet.push_back({15.2f, 0, z});
  const float height = 10, arm = 2.2f;
  for (const PoleLine& line : lines) {
    std::vector<std::array<glm::vec3, 3>> attach;
    for (std::size_t i = 0; i < line.feet.size(); ++i) {
      const glm::vec3 foot = line.feet[i];
      const glm::vec3 along = glm::normalize(line.feet[i + 1 < line.feet.size() ? i + 1 : i] - line.feet[i > 0 ? i - 1 : 0]);
      const glm::vec3 across = glm::normalize(glm::cross(glm::vec3(0, 1, 0), along));
      const float h = height + uniform(rng, -0.3f, 0.3f);
      poles.append(make_tube({foot - glm::vec3(0, 0.3f, 0), foot + glm::vec3(0, h, 0)}, {0.13f, 0.1f}, 8), glm::mat4(1));
      const glm::vec3 arm_centre = foot + glm::vec3(0, h - 0.6f, 0);
      add_beam(poles, arm_centre - across * (arm / 2), arm_centre + across * (arm / 2), 0.1f);
      std::array<glm::vec3, 3> points{};
      for (int w = 0; w < 3; ++w) {
        const glm::vec3 p = arm_centre + across * (0.9f * static_cast<float>(w - 1)) + glm::vec3(0, 0.15f, 0);
        add_box(poles, p, {0.07f, 0.2f, 0.07f});  // insulator
        points[static_cast<std::size_t>(w)] = p + glm::vec3(0, 0.1f, 0);
      }
      poles.close_unit();
      attach.push_back(points);
    }
    for (std::size_t i = 0; i + 1 < attach.size(); ++i)
      for (std::size_t w = 0; w < 3; ++w) {
        wires.append(make_wire(attach[i][w], attach[i + 1][w], uniform(rng, 0.7f, 1.0f)), glm::mat4(1));
        wires.close_unit();  // one span
      }
  }
}

// The walk: east along the street at z = -20, past the fenced site and under the crane's jib,
// then up over the street, looking back at the site, and on over the crossing at (60, -60) to look
// down on the town from 140 m; never through a building.
CameraPath outdoor_path() {
  CameraPath p;
  p.keys = {
      {0, {-75, 1.7f, -21.5f}, {-45, 2.0f, -17}},
      {60, {-45, 1.7f, -22}, {-15, 3.0f, -14}},
      {120, {-15, 1.7f, -22.5f}, {10, 5.0f, -6}},
      {180, {15, 1.7f, -22}, {40, 4.0f, -17}},
      {230, {30, 26, -20}, {10, 4, -8}},
      {290, {60, 60, -60}, {5, 0, -5}},
      {359, {70, 140, -150}, {0, 0, 0}},
  };
  return p;
}

}  // namespace

Scene make_outdoor_scene(const OutdoorOptions& options) {
  const std::uint64_t seed = options.seed;
  Scene s;
  s.name = options.light == OutdoorLight::sun ? "outdoor" : "outdoor-spot";
  if (seed != OutdoorOptions{}.seed) s.name += "-seed" + std::to_string(seed);
  MeshData poles, wires;
  make_pole_lines(seed, poles, wires);
  s.objects.push_back({"ground", share(make_ground(stream(seed, 0))), glm::mat4(1), {0.72f, 0.7f, 0.64f}});
  s.objects.push_back({"buildings", share(make_buildings(seed)), glm::mat4(1), {0.82f, 0.8f, 0.75f}});
  s.objects.push_back({"site", share(make_site()), glm::mat4(1), {0.7f, 0.7f, 0.68f}});
  const auto place = [&](const Instanced& parts, glm::vec3 albedo) {
    for (const glm::mat4& at : parts.at) s.objects.push_back({parts.name, parts.mesh, at, albedo});
  };
  const glm::vec3 crane_yellow{0.95f, 0.75f, 0.1f}, fence_grey{0.62f, 0.64f, 0.62f};
  Crane crane = make_crane();
  s.objects.push_back({"crane", share(std::move(crane.body)), glm::mat4(1), crane_yellow});
  for (const Instanced& panels : crane.panels) place(panels, crane_yellow);
  place(make_fence(), fence_grey);
  s.objects.push_back({"trees", share(make_trees(seed)), glm::mat4(1), {0.45f, 0.36f, 0.28f}});
  s.objects.push_back({"poles", share(std::move(poles)), glm::mat4(1), {0.42f, 0.32f, 0.24f}});
  s.objects.push_back({"wires", share(std::move(wires)), glm::mat4(1), {0.15f, 0.15f, 0.15f}});
  // A van driving up the street ahead of the walk and back (0.6 m a frame, then 0.43): the caster
  // that moves, so that the virtual shadow map's cache has pages to redraw in every frame.
  MeshData van = make_box({4.8f, 2.0f, 2.0f});
  const glm::vec3 van_at{-60, terrain_height(-60, -18.5f, seed) + 1.0f, -18.5f};  // in world space, as the other meshes
  for (Vertex& v : van.vertices) v.position += van_at;
  s.objects.push_back({"van", share(std::move(van)), glm::mat4(1), {0.3f, 0.45f, 0.7f}});
  s.object_paths.push_back({"van", {{0, {0, 0, 0}}, {150, {90, 0, 0}}, {359, {0, 0, 0}}}});

  s.camera_path = outdoor_path();
  s.camera.projection = Camera::Projection::perspective;
  s.camera.fov_y_deg = 55;
  s.camera.near_ws = 0.1f;
  s.camera.far_ws = 900;
  s.camera = s.camera_path.at(s.camera, 120);

  if (options.light == OutdoorLight::sun) {
    const float elevation = glm::radians(40.0f);
    const glm::vec2 heading = glm::normalize(glm::vec2(-0.25f, -1.0f));  // shadows fall north, a little west
    s.light.type = Light::Type::directional;
    s.light.direction = glm::normalize(glm::vec3(std::cos(elevation) * heading.x, -std::sin(elevation), std::cos(elevation) * heading.y));
    s.light.size = 1.0f;
    s.light.color = {1.0f, 0.97f, 0.92f};
    s.light.ambient = 0.25f;
  } else {
    const glm::vec3 mount = kCraneBase + glm::vec3(1.0f, 30, -1.0f);
    s.light.type = Light::Type::spot;
    s.light.position = mount;
    s.light.direction = glm::normalize(glm::vec3(-4, 0, -22) - mount);
    s.light.spot_fov_deg = 110;
    s.light.size = 0.5f;
    s.light.color = {1.0f, 0.85f, 0.62f};
    s.light.ambient = 0.08f;
  }
  return s;
}

}  // namespace penumbra::scene
