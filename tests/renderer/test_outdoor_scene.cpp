// The procedural outdoor scene: deterministic for a seed, about a million triangles, quick to build
// and to load back from its scene file, with the documented objects, light and camera path.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <string>

#include <gtest/gtest.h>
#include <unistd.h>

#include "scene/outdoor.h"
#include "scene/scene.h"

namespace fs = std::filesystem;
using namespace penumbra::scene;

namespace {

std::size_t triangles(const Scene& s) {
  std::size_t n = 0;
  for (const auto& o : s.objects) n += o.mesh->indices.size() / 3;
  return n;
}

// Every vertex position, in order, folded into one number: equal scenes give equal sums.
double fingerprint(const Scene& s) {
  double sum = 0;
  std::size_t i = 0;
  for (const auto& o : s.objects)
    for (const auto& v : o.mesh->vertices) sum += static_cast<double>(++i % 7 + 1) * (v.position.x + 2.0 * v.position.y + 3.0 * v.position.z);
  return sum;
}

const Object& find(const Scene& s, const std::string& name) {
  for (const auto& o : s.objects)
    if (o.name == name) return o;
  throw std::runtime_error("no object " + name);
}

double cpu_seconds(std::clock_t since) { return static_cast<double>(std::clock() - since) / CLOCKS_PER_SEC; }

}  // namespace

TEST(OutdoorScene, SameSeedSameScene) {
  const Scene a = make_outdoor_scene({});
  const Scene b = make_outdoor_scene({});
  EXPECT_EQ(triangles(a), triangles(b));
  EXPECT_EQ(a.bounds().lo, b.bounds().lo);
  EXPECT_EQ(a.bounds().hi, b.bounds().hi);
  EXPECT_EQ(fingerprint(a), fingerprint(b));
  EXPECT_EQ(a.name, "outdoor");

  OutdoorOptions other;
  other.seed = 2;
  const Scene c = make_outdoor_scene(other);
  EXPECT_NE(fingerprint(a), fingerprint(c));
  EXPECT_EQ(c.name, "outdoor-seed2");
  // The built-in name is seed 1.
  EXPECT_EQ(fingerprint(make_builtin_scene("outdoor")), fingerprint(a));
}

TEST(OutdoorScene, AboutAMillionTrianglesOnSeveralHundredMetres) {
  const std::clock_t t0 = std::clock();
  const Scene s = make_outdoor_scene({});
  const double build_s = cpu_seconds(t0);
  EXPECT_LT(build_s, 5.0) << "building took " << build_s << " s of CPU time";
  const std::size_t n = triangles(s);
  EXPECT_GT(n, 700'000u);
  EXPECT_LT(n, 1'500'000u);
  const Aabb b = s.bounds();
  EXPECT_LE(b.lo.x, -299.0f);
  EXPECT_GE(b.hi.x, 299.0f);
  EXPECT_LE(b.lo.z, -299.0f);
  EXPECT_GE(b.hi.z, 299.0f);
  EXPECT_GT(b.hi.y, 50.0f);  // the crane's apex and the tallest towers
  for (const char* name : {"ground", "buildings", "site", "crane", "fence", "trees", "poles", "wires"}) {
    SCOPED_TRACE(name);
    EXPECT_GT(find(s, name).mesh->indices.size(), 0u);
  }
  // The crane stands over the site: a lattice mast about 45 m high.
  const Aabb crane = find(s, "crane").mesh->bounds();
  EXPECT_NEAR(crane.hi.y, 1 + 45 + 1.5f + 7, 1.0f);
  EXPECT_GT(crane.hi.z - crane.lo.z, 60.0f);  // jib plus counter-jib
}

TEST(OutdoorScene, PathWalksThenRisesToAnOverview) {
  const Scene s = make_outdoor_scene({});
  ASSERT_FALSE(s.camera_path.empty());
  EXPECT_EQ(s.camera_path.frames(), 360);
  for (int f = 0; f <= 180; f += 10) {
    const Camera c = s.camera_path.at(s.camera, f);
    EXPECT_NEAR(c.position.y, 1.7f, 0.3f) << "frame " << f;  // eye height while walking
  }
  EXPECT_GT(s.camera_path.at(s.camera, 359).position.y, 100.0f);
  float previous = 0;
  for (int f = 180; f < 360; f += 10) {
    const float y = s.camera_path.at(s.camera, f).position.y;
    EXPECT_GE(y, previous - 0.01f) << "frame " << f;  // the rise never dips
    previous = y;
  }
  // Everything the overview sees lies inside the far plane.
  const Aabb b = s.bounds();
  const Camera top = s.camera_path.at(s.camera, 359);
  for (int i = 0; i < 8; ++i) EXPECT_LT(glm::distance(top.position, b.corner(i)), top.far_ws);
}

TEST(OutdoorScene, SunAndFloodlight) {
  const Scene sun = make_builtin_scene("outdoor");
  EXPECT_EQ(sun.light.type, Light::Type::directional);
  EXPECT_FLOAT_EQ(sun.light.size, 1.0f);
  EXPECT_NEAR(std::asin(-sun.light.direction.y), glm::radians(40.0f), 1e-4);
  const Scene spot = make_builtin_scene("outdoor-spot");
  EXPECT_EQ(spot.name, "outdoor-spot");
  EXPECT_EQ(spot.light.type, Light::Type::spot);
  EXPECT_NEAR(spot.light.position.y, 30.0f, 1e-4);
  EXPECT_LT(spot.light.direction.y, 0.0f);
  EXPECT_EQ(triangles(spot), triangles(sun));  // the same town
}

TEST(OutdoorScene, WrittenSceneLoadsBackQuickly) {
  // Per process: another checkout running the same test at the same time must not share it.
  const fs::path dir = fs::path(::testing::TempDir()) / ("penumbra_outdoor_scene_write-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  const Scene s = make_outdoor_scene({});
  write_scene_file(s, dir / "outdoor.json");
  const std::clock_t t0 = std::clock();
  const Scene back = load_scene(dir.string() + "/outdoor.json");
  const double load_s = cpu_seconds(t0);
  EXPECT_LT(load_s, 5.0) << "loading took " << load_s << " s of CPU time";
  EXPECT_EQ(triangles(back), triangles(s));
  ASSERT_EQ(back.objects.size(), s.objects.size());
  for (std::size_t i = 0; i < s.objects.size(); ++i) {
    SCOPED_TRACE(s.objects[i].name);
    EXPECT_EQ(back.objects[i].name, s.objects[i].name);
    // Each glTF mesh loads as a draw unit: up to 16 runs of the written units per object.
    const std::size_t units = s.objects[i].mesh->draw_units().size();
    EXPECT_EQ(back.objects[i].mesh->draw_units().size(), std::min<std::size_t>(units, 16));
  }
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(back.bounds().lo[c], s.bounds().lo[c], 1e-3f);
    EXPECT_NEAR(back.bounds().hi[c], s.bounds().hi[c], 1e-3f);
  }
  EXPECT_EQ(back.camera_path.frames(), s.camera_path.frames());
  EXPECT_EQ(glm::distance(back.camera_path.at(back.camera, 200).position, s.camera_path.at(s.camera, 200).position), 0.0f);
  fs::remove_all(dir);
}
