#pragma once
// What a staircase asks an observer: one 2AFC trial. The simulated psychometric observer answers
// from a planted model; the study app's image-based observer (a later issue) answers from the
// rendered stimuli. Both implement `Observer`, so simulations and the study share one loop.

#include <cmath>
#include <string>

namespace penumbra::observers {

struct Stimulus {
  std::string condition;    // e.g. "stair/full": selects the observer's per-condition parameters
  double artifact_px;       // staircase step on screen (one shadow-map texel)
  double filter_radius_px;  // PCF radius; at radius = c * artifact the artifact is detected at the criterion

  // The study's QUEST intensity, log10(artifact_px / filter_radius_px): rises as the filter
  // shrinks, i.e. as the artifact becomes easier to see.
  double intensity() const { return std::log10(artifact_px / filter_radius_px); }
};

struct Response {
  bool correct;
};

class Observer {
 public:
  virtual ~Observer() = default;
  // Throws std::invalid_argument for a stimulus it cannot judge (unknown condition, bad sizes).
  virtual Response respond(const Stimulus& stimulus) = 0;
};

}  // namespace penumbra::observers
