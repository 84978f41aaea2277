// The sampling streams are pinned: stimuli, observers' answers, simulated studies, bootstrap
// resamples and the PCF/PCSS Poisson taps (and so every image) depend on these exact sequences.
// The values were taken from the implementations before they moved to common/sampling.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>

#include <glm/geometric.hpp>

#include "sampling/poisson_disk.h"
#include "sampling/random.h"

namespace penumbra::sampling {
namespace {

TEST(Random, SequenceIsPinned) {
  Random r(42);
  EXPECT_EQ(r.uniform(), 0x1.82a3befaddcbcp-1);
  EXPECT_EQ(r.uniform(), 0x1.472f1f73724ap-1);
  EXPECT_EQ(r.bits(), 13874630024467741450ull);
}

TEST(Random, DerivedSeedsArePinned) {
  EXPECT_EQ(derive_seed(42, 0), 13679457532755275413ull);
  EXPECT_EQ(derive_seed(7, 0x5717), 11494268257622618114ull);
}

TEST(PoissonDisk, TapsArePinnedAndFillTheUnitDisk) {
  struct Pinned {
    int taps;
    glm::vec2 first, last;
  };
  const Pinned pinned[] = {{1, {-0x1.f295fp-1f, 0x1.d1b9f2p-3f}, {-0x1.f295fp-1f, 0x1.d1b9f2p-3f}},
                           {16, {-0x1.395958p-1f, -0x1.5fd104p-2f}, {0x1.74afe2p-1f, -0x1.530aaap-1f}},
                           {64, {-0x1.11c41ap-1f, 0x1.16ec9ap-1f}, {-0x1.956decp-2f, -0x1.2870e6p-2f}}};
  for (const Pinned& p : pinned) {
    SCOPED_TRACE(p.taps);
    const auto taps = poisson_disk(p.taps);
    ASSERT_EQ(taps.size(), static_cast<std::size_t>(p.taps));
    EXPECT_EQ(taps.front(), p.first);
    EXPECT_EQ(taps.back(), p.last);
    float r_max = 0;
    for (const auto& t : taps) r_max = std::max(r_max, glm::length(t));
    EXPECT_FLOAT_EQ(r_max, 1.0f) << "the outermost tap is at radius 1";
  }
  EXPECT_EQ(poisson_disk(0).size(), 1u);
  EXPECT_EQ(poisson_disk(1000).size(), 64u);
}

// The frozen table holds a best-candidate set for every count: inside the unit disk, the farthest
// tap on its rim, and no two taps closer than 1.3/sqrt(n) (the tightest set has 1.40/sqrt(n)).
TEST(PoissonDisk, EveryFrozenSetIsAWellSpreadDiskSet) {
  for (int n = 1; n <= 64; ++n) {
    SCOPED_TRACE(n);
    const auto taps = poisson_disk(n);
    ASSERT_EQ(taps.size(), static_cast<std::size_t>(n));
    float r_max = 0, closest = 2;
    for (std::size_t i = 0; i < taps.size(); ++i) {
      r_max = std::max(r_max, glm::length(taps[i]));
      for (std::size_t j = 0; j < i; ++j) closest = std::min(closest, glm::distance(taps[i], taps[j]));
    }
    EXPECT_FLOAT_EQ(r_max, 1.0f);
    if (n > 1) {
      EXPECT_GT(closest * std::sqrt(static_cast<float>(n)), 1.3f);
    }
  }
}

}  // namespace
}  // namespace penumbra::sampling
