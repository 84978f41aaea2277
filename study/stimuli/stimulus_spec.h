#pragma once
// What a stimulus is, without drawing it: the pattern, kernel and transfer names, the spec the
// procedure plans and the log records, and the radius a stimulus can show. No GL: the procedure
// and the fitter (analysis/) use it without the renderer; stimulus.h draws it.
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "display/display_calibration.h"
#include "shadows/settings_table.h"

namespace penumbra::stimuli {

enum class Pattern { stair, step };
// The renderer's PCF kernels (one enum: a stimulus is drawn with the renderer's kernel of that name).
using Kernel = shadows::Kernel;

// The display's transfer function: an assumed standard one (srgb, gamma2.2, linear) or the
// monitor's own, measured (display-calibration.json). stimulus.h's encode/decode apply it.
struct Transfer {
  enum class Kind { srgb, gamma22, linear, measured };
  Kind kind = Kind::srgb;
  std::shared_ptr<const display::DisplayCalibration> calibration;  // Kind::measured: the measurement

  static const Transfer srgb, gamma22, linear;
  static Transfer measured(display::DisplayCalibration calibration);
  // Equal kinds, and for measured ones equal calibrations (by content).
  friend bool operator==(const Transfer& a, const Transfer& b);
};
inline const Transfer Transfer::srgb{Transfer::Kind::srgb, nullptr};
inline const Transfer Transfer::gamma22{Transfer::Kind::gamma22, nullptr};
inline const Transfer Transfer::linear{Transfer::Kind::linear, nullptr};

// Parse/print; parse throws std::invalid_argument naming the accepted values. parse_transfer takes
// the assumed transfers only (a measured one comes from its file); to_string gives "measured" for it.
Pattern parse_pattern(const std::string& s);
Kernel parse_kernel(const std::string& s);
Transfer parse_transfer(const std::string& s);
std::string to_string(Pattern p);
std::string to_string(Kernel k);
std::string to_string(const Transfer& t);

struct StimulusSpec {
  Pattern pattern = Pattern::stair;
  double artifact_px = 10;       // one shadow-map texel on screen
  double filter_radius_px = 20;  // filter radius (as shown: clamp first, see clamp_filter_radius)
  double lit_linear = 1.0;       // lit level in linear light, (0, 1]
  Kernel kernel = Kernel::disk;
  int poisson_taps = 32;         // Poisson kernel only
  int size_px = 320;             // square stimulus side
  std::uint64_t seed = 1;        // edge phase, orientation, Poisson rotation
  Transfer transfer = Transfer::srgb;
  // The shadow technique of the renderer that draws the stimulus, by penumbra-render's names
  // ("pcf"), with its settings as "section.key" and value ("pcf.kernel", "grid"); its filter
  // radius is set from filter_radius_px / artifact_px texels. Empty: the renderer's PCF with
  // `kernel` and `poisson_taps` (as_renderer_pcf; the form of the earlier configs and logs).
  std::string technique;
  std::vector<std::pair<std::string, std::string>> technique_settings;
};
// The command line's technique settings (--set KEY=VALUE, repeatable) into spec.technique_settings;
// throws std::invalid_argument naming the bad one, or when settings come without spec.technique.
void set_technique_settings(StimulusSpec& spec, const std::vector<std::string>& key_values);
// Throws std::invalid_argument naming the field for a spec that cannot be drawn.
void validate(const StimulusSpec& spec);

// The filter radius that can actually be shown: at least 1 px, at most half the stimulus.
struct ShownRadius {
  double filter_radius_px;
  bool clamped;
};
ShownRadius clamp_filter_radius(double requested_px, int size_px);

}  // namespace penumbra::stimuli
