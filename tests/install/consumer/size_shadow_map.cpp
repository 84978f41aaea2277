// Sizes a shadow map from a filter radius through the installed Penumbra::adaptive (CMake) or
// penumbra-adaptive (pkg-config), and checks the numbers: exit 0 when all hold, 1 naming the first
// that does not (tests/install/consumer_test.sh).
//   size_shadow_map PREFIX/share/penumbra/calibration/default.json
#include <penumbra/adaptive/calibration.h>
#include <penumbra/adaptive/cascades.h>
#include <penumbra/adaptive/resolution_rule.h>

#include <cmath>
#include <cstdio>
#include <vector>

using namespace penumbra::adaptive;

namespace {

bool check(bool ok, const char* what, double got) {
  if (!ok) std::fprintf(stderr, "size_shadow_map: %s: got %.17g\n", what, got);
  return ok;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: size_shadow_map CALIBRATION_JSON\n");
    return 2;
  }
  // The installed default calibration: the published PCF constant.
  const CalibrationChoice c = load_calibration(argv[1]).choose("pcf", "grid");
  if (!check(c.c == 3.47, "c of the installed default calibration", c.c)) return 1;

  // A PCF radius of 0.05 world units over a 20-unit light window: 3.47 · 20 / 0.05 = 1388 texels,
  // rounded up to a multiple of 32: 1408.
  const double required = required_texels_ws(c.c, LightExtentWs{20.0}, FilterRadiusWs{0.05});
  if (!check(std::abs(required - 1388.0) < 1e-9, "required_texels_ws(3.47, 20, 0.05)", required)) return 1;
  const ResolutionLimits limits{16, 8192, 32};
  const int resolution = clamp_resolution(required, limits);
  if (!check(resolution == 1408, "clamp_resolution(1388)", resolution)) return 1;

  // Hysteresis: grows at once, shrinks after shrink_delay_frames frames below 80 %.
  ResolutionController controller({limits, /*shrink_delay_frames=*/2, /*shrink_fraction=*/0.8});
  const int r0 = controller.update(required), r1 = controller.update(1000), r2 = controller.update(1000);
  if (!check(r0 == 1408 && r1 == 1408 && r2 == 1024, "controller 1388, 1000, 1000 (expected 1408, 1408, 1024)", r0 * 1e8 + r1 * 1e4 + r2))
    return 1;

  // Cascades: logarithmic splits of [1, 100] into 2, and the fewest of 4 whose maps fit 4096
  // texels when the view needs 10000 / n per cascade: 3.
  const std::vector<double> splits = cascade_splits(1.0, 100.0, 2, 1.0);
  if (!check(splits.size() == 3 && std::abs(splits[1] - 10.0) < 1e-9, "cascade_splits(1, 100, 2, 1)[1]", splits[1])) return 1;
  const CascadeChoice choice = choose_cascade_count(4, 4096, [](int n) { return std::vector<double>(n, 10000.0 / n); });
  if (!check(choice.count == 3 && choice.fits, "choose_cascade_count", choice.count)) return 1;

  std::printf("c = %.2f (%s): r = 0.05 ws over 20 ws needs %.0f texels, rendered at %d; %d cascades\n", c.c, c.from.c_str(), required,
              resolution, choice.count);
  return 0;
}
