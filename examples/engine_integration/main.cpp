// How an engine asks Penumbra's adaptive rule for its shadow maps, each frame: how many cascades,
// which resolution each one is rendered at, and when a resolution may change (docs/adaptive.md,
// "Using the rule from another engine"). Uses only the installed headers of Penumbra::adaptive
// (CMake) or penumbra-adaptive (pkg-config): no GL, no GLM, nothing else of Penumbra's.
//
//   engine_integration [--allow-unusable] [calibration.json]
//
// An entry penumbra-fit judged unusable (written only with its --allow-unusable: "usable": false)
// is refused, one line on stderr and exit 1, unless --allow-unusable is given here too; what the
// fitter flagged, and why an entry is unusable, goes on the line that says which c is used, as
// Penumbra's own tools print it (docs/fit.md).
//
// Copy the pattern: the parts marked ENGINE are what your engine has already (its camera, its
// light fitting, its filter); everything else is the calls to make, in that order.
#include <penumbra/adaptive/calibration.h>
#include <penumbra/adaptive/cascades.h>
#include <penumbra/adaptive/resolution_rule.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

namespace adaptive = penumbra::adaptive;

namespace {

// ENGINE: the camera of this frame and the shadow filter it renders with.
struct EngineFrame {
  double near_ws, far_ws;      // the view depth range that receives shadows
  double fov_y_rad, aspect;    // the camera's perspective
  double filter_radius_ws;     // the PCF radius, in world units
};

// ENGINE: the side of the orthographic light window your fitting puts around the view slice
// [z0, z1]. Here a bound that holds for any light direction: no two points of the slice lie
// farther apart than the far face's diagonal and the slice's depth together. Use your own fit: the
// rule needs the extent the map is really spread over.
double light_extent_ws(const EngineFrame& f, double z0, double z1) {
  const double far_diagonal = 2.0 * z1 * std::tan(0.5 * f.fov_y_rad) * std::sqrt(1.0 + f.aspect * f.aspect);
  return std::hypot(far_diagonal, z1 - z0);
}

// ENGINE: frames in which the filter narrows from 0.2 to 0.065 world units and widens again (48
// frames), as a quality setting or the light's angular size might change it.
EngineFrame frame_at(int i) {
  const double t = 0.5 + 0.5 * std::cos(i * 0.13);
  return EngineFrame{0.5, 40.0, 0.8, 16.0 / 9.0, 0.065 + 0.135 * t};
}

}  // namespace

int main(int argc, char** argv) {
  const char* file = nullptr;
  bool allow_unusable = false;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--allow-unusable") == 0) {
      allow_unusable = true;
    } else if (argv[i][0] == '-' || file) {
      std::fprintf(stderr, "engine_integration: unexpected argument '%s' (usage: engine_integration [--allow-unusable] [calibration.json])\n",
                   argv[i]);
      return 2;
    } else {
      file = argv[i];
    }
  }

  // Once: the constant c for the filter the engine uses. calibration.json as penumbra-fit writes it
  // (or the package's share/penumbra/calibration/default.json); without a file, the published c.
  adaptive::Calibration calibration;
  if (file) {
    try {
      calibration = adaptive::load_calibration(file);
    } catch (const adaptive::CalibrationError& e) {
      std::fprintf(stderr, "engine_integration: %s\n", e.what());  // names the file and the field
      return 1;
    }
  }
  const adaptive::CalibrationChoice c = calibration.choose("pcf", "grid");
  // A fit the fitter judged unusable (not converged, an open interval, c outside [0.5, 20] texels)
  // is no calibration: a pilot's c = 0.03 would size every map at the smallest the limits allow, and
  // the staircase would show everywhere. Refuse it unless the engine's user asked for it.
  if (c.entry && !c.entry->usable && !allow_unusable) {
    std::string why;
    for (const std::string& reason : c.entry->unusable_because) why += (why.empty() ? "" : ", ") + reason;
    std::fprintf(stderr,
                 "engine_integration: %s: the %s entry has \"usable\": false (%s): penumbra-fit judged its c = %.3g unusable; "
                 "fit more data, or pass --allow-unusable to use it anyway\n",
                 calibration.source.c_str(), c.entry->label().c_str(), why.empty() ? "no reason given" : why.c_str(), c.c);
    return 1;
  }
  // What to know before trusting c, as the tools print it: "NOT USABLE: ..." (only with
  // --allow-unusable) and the fitter's flags ("flags: one_participant"). An engine logs it.
  const std::string warnings = c.warnings();
  std::printf("c = %.2f texels (%s)%s%s\n", c.c, c.from.c_str(), warnings.empty() ? "" : "; ", warnings.c_str());

  // Once: the limits of the maps the engine can allocate, and up to how many cascades it renders.
  constexpr int kMaxCascades = 4;
  constexpr double kLambda = 0.75;  // practical split scheme: 1 logarithmic, 0 uniform
  adaptive::ResolutionController::Params params;
  params.limits = {/*min_texels=*/64, /*max_texels=*/4096, /*quantum_texels=*/32};
  params.shrink_delay_frames = 30;  // shrink only after 30 frames of needing less
  std::vector<adaptive::ResolutionController> controllers;  // one per cascade

  for (int frame = 0; frame < 64; ++frame) {
    const EngineFrame f = frame_at(frame);

    // 1. What n cascades would need: the rule res = c · L / r for each slice of the view.
    auto required_texels = [&](int n) {
      const std::vector<double> splits = adaptive::cascade_splits(f.near_ws, f.far_ws, n, kLambda);
      std::vector<double> texels;
      for (int i = 0; i < n; ++i)
        texels.push_back(adaptive::required_texels_ws(c.c, adaptive::LightExtentWs{light_extent_ws(f, splits[i], splits[i + 1])},
                                                  adaptive::FilterRadiusWs{f.filter_radius_ws}));
      return texels;
    };
    // 2. The fewest cascades whose every map fits the largest resolution (fits = false: even
    //    kMaxCascades need more, and the filter will show texels; widen it or allow larger maps).
    const adaptive::CascadeChoice choice = adaptive::choose_cascade_count(kMaxCascades, params.limits.max_texels, required_texels);
    // 3. One hysteresis controller per cascade; a new count means new slices, so start them again.
    if (controllers.size() != static_cast<std::size_t>(choice.count))
      controllers.assign(static_cast<std::size_t>(choice.count), adaptive::ResolutionController(params));
    // 4. The resolution to render each cascade at this frame: grows at once, shrinks only after
    //    shrink_delay_frames frames below 80 % of it, so edges do not wobble.
    std::printf("frame %2d  r = %.3f ws  %d cascade%s%s:", frame, f.filter_radius_ws, choice.count, choice.count > 1 ? "s" : "",
                choice.fits ? "" : " (do not fit)");
    for (std::size_t i = 0; i < controllers.size(); ++i) {
      const int resolution_texels = controllers[i].update(choice.required_texels[i]);
      std::printf("  %4.0f -> %4d", choice.required_texels[i], resolution_texels);
      // ENGINE: render cascade i into a resolution_texels² region of your shadow atlas.
    }
    std::printf("\n");
  }
  return 0;
}
