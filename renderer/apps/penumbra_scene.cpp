// penumbra-scene: what a scene holds (objects, triangles, bounds, light, camera path, how long it
// took to build or load), and, with -o DIR, the scene written as a scene file DIR/scene.json with
// its meshes as glTF binaries in DIR/scene/, so that a user can swap in their own models.
#include <CLI/CLI.hpp>

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <set>
#include <string>

#include "apps/cli_options.h"
#include "cli/main.h"
#include "io/staged_dir.h"
#include "scene/outdoor.h"
#include "scene/scene.h"

using namespace penumbra;

int main(int argc, char** argv) {
  CLI::App app{"Describe a scene, and write it as a scene file with glTF models (-o)."};
  cli::describe_tool(app, "penumbra-scene", "scene-format.md");
  std::string scene_arg = "outdoor";
  std::int64_t seed = -1;
  std::string output;
  app.add_option("--scene", scene_arg, "built-in scene name or scene file (.json)");
  app.add_option("--seed", seed, "seed of the procedural outdoor scenes (default 1)")->check(CLI::Range(0LL, 4294967295LL));
  app.add_option("-o,--output", output, "write DIR/scene.json and DIR/scene/*.glb (DIR replaced as a whole on success)")
      ->check(cli::path_given());
  if (const auto status = cli::parse(app, argc, argv, "penumbra-scene")) return *status;
  try {
    const auto t0 = std::chrono::steady_clock::now();
    scene::Scene s;
    if (seed >= 0) {
      if (scene_arg != "outdoor" && scene_arg != "outdoor-spot")
        throw std::runtime_error("--seed: only the outdoor scenes (outdoor, outdoor-spot) take a seed, not '" + scene_arg + "'");
      scene::OutdoorOptions o;
      o.seed = static_cast<std::uint32_t>(seed);
      o.light = scene_arg == "outdoor" ? scene::OutdoorLight::sun : scene::OutdoorLight::floodlight;
      s = scene::make_outdoor_scene(o);
    } else {
      s = scene::load_scene(scene_arg);
    }
    const double build_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();

    // One row per run of objects with one name: its instances (objects), the distinct meshes they
    // share, the triangles drawn (every instance) and the vertices stored (every distinct mesh once).
    struct Row {
      std::string name;
      std::size_t objects = 0, triangles = 0, vertices = 0, units = 0;
      std::set<const scene::MeshData*> meshes;
    };
    std::vector<Row> rows;
    for (const auto& o : s.objects) {
      if (rows.empty() || rows.back().name != o.name) rows.push_back({o.name});
      Row& r = rows.back();
      ++r.objects;
      r.triangles += o.mesh->indices.size() / 3;
      r.units += o.mesh->draw_units().size();
      if (r.meshes.insert(o.mesh.get()).second) r.vertices += o.mesh->vertices.size();
    }
    std::printf("scene %s: built or loaded in %.0f ms\n", s.name.c_str(), build_ms);
    // units: what culling keeps or drops; instances: objects sharing the row's meshes
    std::printf("%-16s %9s %7s %12s %12s %8s\n", "object", "instances", "meshes", "triangles", "vertices", "units");
    Row total{"total"};
    for (const Row& r : rows) {
      std::printf("%-16s %9zu %7zu %12zu %12zu %8zu\n", r.name.c_str(), r.objects, r.meshes.size(), r.triangles, r.vertices, r.units);
      total.objects += r.objects, total.triangles += r.triangles, total.units += r.units;
      total.meshes.insert(r.meshes.begin(), r.meshes.end());
    }
    for (const scene::MeshData* m : total.meshes) total.vertices += m->vertices.size();
    std::printf("%-16s %9zu %7zu %12zu %12zu %8zu\n", "total", total.objects, total.meshes.size(), total.triangles, total.vertices, total.units);
    const scene::Aabb b = s.bounds();
    if (!b.empty())
      std::printf("bounds [%.2f, %.2f, %.2f] .. [%.2f, %.2f, %.2f]\n", b.lo.x, b.lo.y, b.lo.z, b.hi.x, b.hi.y, b.hi.z);
    const scene::Light& l = s.light;
    if (l.type == scene::Light::Type::directional)
      std::printf("light: directional, direction [%.3f, %.3f, %.3f], %.2f deg\n", l.direction.x, l.direction.y, l.direction.z, l.size);
    else
      std::printf("light: spot at [%.2f, %.2f, %.2f], cone %.0f deg, emitter %.2f wide\n", l.position.x, l.position.y, l.position.z,
                  l.spot_fov_deg, l.size);
    std::printf("camera path: %d frames, %zu keys\n", s.camera_path.frames(), s.camera_path.keys.size());

    if (!output.empty()) {
      io::StagedDirectory out(output, "scene.json");
      scene::write_scene_file(s, out.path() / "scene.json");
      out.commit();
      std::printf("wrote %s/scene.json\n", output.c_str());
    }
    return 0;
  } catch (const std::exception& e) {
    return cli::fail("penumbra-scene", e);
  }
}
