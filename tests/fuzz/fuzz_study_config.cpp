// Study configs (data/studies/*.json) through procedure::load_config, as penumbra-study run
// --config reads them.
#include "fuzz_target.h"
#include "procedure/config.h"

PENUMBRA_FUZZ_TARGET(study_config) {
  const std::filesystem::path path = penumbra::fuzz::scratch() / "config.json";
  penumbra::fuzz::write(path, input);
  penumbra::fuzz::expect_refusal_or_success([&] { penumbra::procedure::load_config(path); });
}
