// Scene files (docs/scene-format.md) through scene::load_scene_file, as penumbra-render --scene
// FILE reads them; models/ beside the file is data/scenes/models, so the seeds load their models.
#include "fuzz_target.h"
#include "scene/scene.h"

PENUMBRA_FUZZ_TARGET(scene_file) {
  static const std::filesystem::path dir = [] {
    const std::filesystem::path d = penumbra::fuzz::scratch() / "scene";
    std::filesystem::create_directories(d);
    std::error_code ec;
    std::filesystem::create_directory_symlink(PENUMBRA_DATA_DIR "/scenes/models", d / "models", ec);
    return d;
  }();
  penumbra::fuzz::write(dir / "scene.json", input);
  penumbra::fuzz::expect_refusal_or_success([&] { penumbra::scene::load_scene_file(dir / "scene.json"); });
}
