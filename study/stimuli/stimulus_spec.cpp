#include "stimuli/stimulus_spec.h"

#include <cmath>
#include <stdexcept>

#include "text/printable.h"

namespace penumbra::stimuli {

Pattern parse_pattern(const std::string& s) {
  if (s == "stair") return Pattern::stair;
  if (s == "step") return Pattern::step;
  throw std::invalid_argument("pattern '" + text::printable(s) + "': expected stair or step");
}
Kernel parse_kernel(const std::string& s) {
  if (s == "disk") return Kernel::disk;
  if (s == "grid") return Kernel::grid;
  if (s == "poisson") return Kernel::poisson;
  throw std::invalid_argument("kernel '" + text::printable(s) + "': expected disk, grid or poisson");
}
Transfer parse_transfer(const std::string& s) {
  if (s == "srgb") return Transfer::srgb;
  if (s == "gamma2.2") return Transfer::gamma22;
  if (s == "linear") return Transfer::linear;
  throw std::invalid_argument("transfer function '" + text::printable(s) + "': expected srgb, gamma2.2 or linear");
}
std::string to_string(Pattern p) { return p == Pattern::stair ? "stair" : "step"; }
std::string to_string(Kernel k) { return k == Kernel::disk ? "disk" : k == Kernel::grid ? "grid" : "poisson"; }
std::string to_string(const Transfer& t) {
  switch (t.kind) {
    case Transfer::Kind::srgb: return "srgb";
    case Transfer::Kind::gamma22: return "gamma2.2";
    case Transfer::Kind::linear: return "linear";
    case Transfer::Kind::measured: return "measured";
  }
  return "";
}

Transfer Transfer::measured(display::DisplayCalibration calibration) {
  return {Kind::measured, std::make_shared<const display::DisplayCalibration>(std::move(calibration))};
}

bool operator==(const Transfer& a, const Transfer& b) {
  if (a.kind != b.kind) return false;
  if (a.kind != Transfer::Kind::measured || a.calibration == b.calibration) return true;
  return a.calibration && b.calibration && display::to_json(*a.calibration) == display::to_json(*b.calibration);
}

void validate(const StimulusSpec& s) {
  auto fail = [](const std::string& field, const std::string& what) {
    throw std::invalid_argument(field + ": " + what);
  };
  if (!(s.artifact_px >= 1 && s.artifact_px <= 1000)) fail("artifact_px", "expected a value in [1, 1000] px");
  if (!(s.filter_radius_px > 0 && std::isfinite(s.filter_radius_px))) fail("filter_radius_px", "expected > 0 px");
  if (!(s.lit_linear > 0 && s.lit_linear <= 1)) fail("contrast", "expected a linear lit level in (0, 1]");
  if (s.size_px < 16 || s.size_px > 4096) fail("size_px", "expected 16..4096");
  if (s.poisson_taps < 1 || s.poisson_taps > 64) fail("poisson_taps", "expected 1..64");
}

void set_technique_settings(StimulusSpec& spec, const std::vector<std::string>& key_values) {
  for (const std::string& kv : key_values) {
    const std::size_t eq = kv.find('=');
    if (eq == std::string::npos || eq == 0) throw std::invalid_argument("--set '" + text::printable(kv) + "': expected KEY=VALUE");
    const std::string key = kv.substr(0, eq);
    // A key given twice is refused, as the JSON readers refuse a repeated key: the last would
    // silently win.
    for (const auto& [given, value] : spec.technique_settings)
      if (given == key) throw std::invalid_argument("--set " + text::printable(key) + ": given twice");
    spec.technique_settings.emplace_back(key, kv.substr(eq + 1));
  }
  if (!spec.technique_settings.empty() && spec.technique.empty()) throw std::invalid_argument("--set: needs --technique");
}

ShownRadius clamp_filter_radius(double requested_px, int size_px) {
  const double lo = 1.0, hi = 0.5 * size_px;
  if (!(requested_px >= lo)) return {lo, true};  // also catches NaN
  if (requested_px > hi) return {hi, true};
  return {requested_px, false};
}

}  // namespace penumbra::stimuli
