// .gltf models through the scene loader (Assimp, then the project's checks: finite vertices,
// triangles, normals): a fixed scene file whose one object is the fuzzed model.gltf.
#include "fuzz_target.h"
#include "scene/scene.h"

PENUMBRA_FUZZ_TARGET(model_gltf) {
  static const std::filesystem::path dir = [] {
    const std::filesystem::path d = penumbra::fuzz::scratch() / "model_gltf";
    std::filesystem::create_directories(d);
    penumbra::fuzz::write(d / "scene.json", R"({"name": "fuzz", "camera": {"position": [0, 4, 8], "target": [0, 0.5, 0], "fov_y_deg": 45},
 "light": {"type": "directional", "direction": [-0.4, -1, -0.3], "size": 1.5, "ambient": 0.2},
 "objects": [{"name": "model", "shape": "model", "path": "model.gltf"}]})");
    return d;
  }();
  penumbra::fuzz::write(dir / "model.gltf", input);
  penumbra::fuzz::expect_refusal_or_success([&] { penumbra::scene::load_scene_file(dir / "scene.json"); });
}
