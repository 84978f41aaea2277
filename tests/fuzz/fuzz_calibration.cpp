// calibration.json through adaptive::load_calibration, as every renderer app's --calibration reads it.
#include "adaptive/resolution_rule.h"
#include "fuzz_target.h"

PENUMBRA_FUZZ_TARGET(calibration) {
  const std::filesystem::path path = penumbra::fuzz::scratch() / "calibration.json";
  penumbra::fuzz::write(path, input);
  penumbra::fuzz::expect_refusal_or_success([&] { penumbra::adaptive::load_calibration(path); });
}
