// The procedural outdoor scene: deterministic for a seed, about a million triangles, quick to build
// and to load back from its scene file, with the documented objects, light and camera path.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <map>
#include <set>
#include <tuple>
#include <string>
#include <vector>

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
    for (const auto& v : o.mesh->vertices) {
      const glm::vec3 p = glm::vec3(o.model * glm::vec4(v.position, 1));  // instances share vertices, not places
      sum += static_cast<double>(++i % 7 + 1) * (p.x + 2.0 * p.y + 3.0 * p.z);
    }
  return sum;
}

const Object& find(const Scene& s, const std::string& name) {
  for (const auto& o : s.objects)
    if (o.name == name) return o;
  throw std::runtime_error("no object " + name);
}

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
  const Scene s = make_outdoor_scene({});
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
  Aabb crane;
  for (const auto& o : s.objects)
    if (o.name == "crane") crane.extend(o.mesh->bounds().transformed(o.model));
  EXPECT_NEAR(crane.hi.y, 1 + 45 + 1.5f + 7, 1.0f);
  EXPECT_GT(crane.hi.z - crane.lo.z, 60.0f);  // jib plus counter-jib
}

// Repeating parts are instances of one mesh each: the crane's 25 mast and 40 jib panels (two
// panels each, their diagonals alternating) and the fence's 38 panels; no two instances of a mesh
// stand in one place, and the mast's panels stack from the footing to the slewing unit.
TEST(OutdoorScene, RepeatingPartsAreInstancesOfOneMesh) {
  const Scene s = make_outdoor_scene({});
  std::map<std::string, std::set<const MeshData*>> meshes;
  std::map<const MeshData*, std::vector<glm::vec3>> places;
  std::map<std::string, std::size_t> objects;
  for (const auto& o : s.objects) {
    meshes[o.name].insert(o.mesh.get());
    ++objects[o.name];
    places[o.mesh.get()].push_back(glm::vec3(o.model[3]));
  }
  EXPECT_EQ(objects["crane"], 1u + 25u + 40u);
  EXPECT_EQ(meshes["crane"].size(), 5u) << "the body, two mast panels, two jib panels";
  EXPECT_EQ(objects["fence"], 38u);
  EXPECT_EQ(meshes["fence"].size(), 1u);
  EXPECT_EQ(s.objects.size(), 111u) << "and the van";
  for (auto& [mesh, at] : places) {
    std::sort(at.begin(), at.end(), [](glm::vec3 a, glm::vec3 b) { return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z); });
    EXPECT_EQ(std::adjacent_find(at.begin(), at.end()), at.end()) << "two instances in one place";
  }
  // The mast: 25 panels of 1.8 m, one above the other, from y = 1 (the footing's top) to 46.
  std::vector<float> mast;
  for (const auto& o : s.objects) {
    const Aabb b = o.mesh->bounds().transformed(o.model);
    if (o.name == "crane" && b.hi.y - b.lo.y > 1.75f && b.hi.y - b.lo.y < 2.5f) mast.push_back(o.model[3].y);  // jib panels: 1.6 m
  }
  ASSERT_EQ(mast.size(), 25u);
  std::sort(mast.begin(), mast.end());
  for (std::size_t i = 0; i < mast.size(); ++i) EXPECT_NEAR(mast[i], 1 + 1.8f * static_cast<float>(i), 1e-4f);
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

// The camera walks and climbs in the open: at no frame of the path is it inside a building's,
// the site's or the crane's draw unit (a camera inside a building sees its walls from within, all
// in shadow: a station of the main job would measure nothing).
TEST(OutdoorScene, PathNeverEntersABuilding) {
  const Scene s = make_outdoor_scene({});
  std::vector<std::pair<std::string, Aabb>> solids;
  for (const auto& o : s.objects)
    if (o.name == "buildings" || o.name == "site" || o.name == "crane")
      for (const DrawUnit& u : o.mesh->draw_units()) solids.emplace_back(o.name, u.bounds.transformed(o.model));
  ASSERT_GT(solids.size(), 100u);
  for (int f = 0; f < s.camera_path.frames(); ++f) {
    const glm::vec3 p = s.camera_path.at(s.camera, f).position;
    for (const auto& [name, b] : solids) {
      const bool inside = glm::all(glm::greaterThan(p, b.lo - 0.3f)) && glm::all(glm::lessThan(p, b.hi + 0.3f));
      EXPECT_FALSE(inside) << "frame " << f << ": the camera at (" << p.x << ", " << p.y << ", " << p.z << ") is within 0.3 m of a "
                           << name << " unit [" << b.lo.x << ", " << b.lo.y << ", " << b.lo.z << "] - [" << b.hi.x << ", " << b.hi.y
                           << ", " << b.hi.z << "]";
    }
  }
}

// The van drives up the street and back along the camera path's frames (straight between its
// keys, held past the last): posing moves it, and nothing else, by its path's translation.
TEST(OutdoorScene, TheVanDrivesAlongItsPathAndPosingMovesOnlyIt) {
  const Scene s = make_outdoor_scene({});
  ASSERT_EQ(s.object_paths.size(), 1u);
  const ObjectPath& path = s.object_paths[0];
  const std::size_t van = path_object(s, path);
  EXPECT_EQ(s.objects[van].name, "van");
  EXPECT_EQ(path.translate_at(0), glm::vec3(0));
  EXPECT_EQ(path.translate_at(75), glm::vec3(45, 0, 0));   // halfway to the first turn
  EXPECT_EQ(path.translate_at(150), glm::vec3(90, 0, 0));  // the turn
  EXPECT_EQ(path.translate_at(-5), glm::vec3(0)) << "held before the first key";
  EXPECT_EQ(path.translate_at(1000), glm::vec3(0)) << "held after the last key";
  const float step = glm::distance(path.translate_at(1), path.translate_at(0));
  EXPECT_NEAR(step, 0.6f, 1e-5f) << "it moves every frame: a moving caster in each station";
  const Scene at = posed_at(s, 100);
  for (std::size_t i = 0; i < s.objects.size(); ++i) {
    if (i == van) continue;
    EXPECT_EQ(at.objects[i].model, s.objects[i].model) << s.objects[i].name;
  }
  EXPECT_EQ(glm::vec3(at.objects[van].model[3]), glm::vec3(60, 0, 0));
  // A scene holding some of the objects (the thin casters left out) is posed by name.
  Scene some;
  some.objects.push_back(s.objects[van]);
  pose_objects(s, 100, some);
  EXPECT_EQ(some.objects[0].model, at.objects[van].model);
  Scene none;
  EXPECT_THROW(pose_objects(s, 100, none), SceneError) << "the van is not in it";
  Scene twice = s;
  twice.objects.push_back(s.objects[van]);
  EXPECT_THROW(path_object(twice, path), SceneError) << "two objects named van";
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

// What keeps loading cheap is asserted as work, not seconds: every instance of a glTF mesh shares one
// MeshData, so the file's meshes are read once each.
TEST(OutdoorScene, WrittenSceneLoadsBackWithItsMeshesShared) {
  // Per process: another checkout running the same test at the same time must not share it.
  const fs::path dir = fs::path(::testing::TempDir()) / ("penumbra_outdoor_scene_write-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  const Scene s = make_outdoor_scene({});
  write_scene_file(s, dir / "outdoor.json");
  const Scene back = load_scene(dir.string() + "/outdoor.json");
  EXPECT_EQ(triangles(back), triangles(s));
  ASSERT_EQ(back.objects.size(), s.objects.size());
  for (std::size_t i = 0; i < s.objects.size(); ++i) {
    SCOPED_TRACE(s.objects[i].name);
    EXPECT_EQ(back.objects[i].name, s.objects[i].name);
    for (int c = 0; c < 4; ++c)  // an instance is written with its placement, the rest in world space
      for (int r = 0; r < 4; ++r) EXPECT_NEAR(back.objects[i].model[c][r], s.objects[i].model[c][r], 1e-5f);
    // Each glTF mesh loads as a draw unit: up to 16 runs of the written units per object.
    const std::size_t units = s.objects[i].mesh->draw_units().size();
    EXPECT_EQ(back.objects[i].mesh->draw_units().size(), std::min<std::size_t>(units, 16));
  }
  std::set<const MeshData*> written, read;
  for (std::size_t i = 0; i < s.objects.size(); ++i) written.insert(s.objects[i].mesh.get()), read.insert(back.objects[i].mesh.get());
  EXPECT_EQ(read.size(), written.size()) << "instances share one model file and load as one mesh";
  EXPECT_EQ(std::distance(fs::directory_iterator(dir / "outdoor"), fs::directory_iterator()), 13);
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(back.bounds().lo[c], s.bounds().lo[c], 1e-3f);
    EXPECT_NEAR(back.bounds().hi[c], s.bounds().hi[c], 1e-3f);
  }
  EXPECT_EQ(back.camera_path.frames(), s.camera_path.frames());
  EXPECT_EQ(glm::distance(back.camera_path.at(back.camera, 200).position, s.camera_path.at(s.camera, 200).position), 0.0f);
  ASSERT_EQ(back.object_paths.size(), 1u) << "the van's path";
  EXPECT_EQ(back.object_paths[0].object, "van");
  for (const double f : {0.0, 77.5, 150.0, 359.0})
    EXPECT_EQ(back.object_paths[0].translate_at(f), s.object_paths[0].translate_at(f)) << "frame " << f;
  fs::remove_all(dir);
}
