#pragma once
// The one line every image comparison of the metrics library (compare, LDR-FLIP, the frame
// observer) refuses a pair of different sizes with: "<who>: image sizes differ (reference W×H,
// test W×H)". Header-only: the three live in separate libraries.
#include <stdexcept>
#include <string>

namespace penumbra::metrics {

inline void check_same_size(const char* who, int reference_width, int reference_height, int test_width, int test_height) {
  if (reference_width != test_width || reference_height != test_height)
    throw std::invalid_argument(std::string(who) + ": image sizes differ (reference " + std::to_string(reference_width) + "×" +
                                std::to_string(reference_height) + ", test " + std::to_string(test_width) + "×" +
                                std::to_string(test_height) + ")");
}

}  // namespace penumbra::metrics
