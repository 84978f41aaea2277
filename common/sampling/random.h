#pragma once
// The project's one convention for seeded randomness, the same sequence on every platform:
// std::mt19937_64 is fully specified by the standard, std::uniform_real_distribution is not, so
// uniforms are made here; independent streams come from derive_seed. Where a sequence must not
// change (the Poisson taps every image used), it is frozen as a table instead.

#include <cstdint>
#include <random>

namespace penumbra::sampling {

class Random {
 public:
  explicit Random(std::uint64_t seed) : engine_(seed) {}
  // Uniform in [0, 1) with 53 random bits.
  double uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }
  // Uniform in [lo, hi).
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  // Uniform integer in [lo, hi], lo <= hi.
  int integer(int lo, int hi) { return lo + static_cast<int>(uniform() * (static_cast<double>(hi) - lo + 1)); }
  // True with probability p.
  bool chance(double p) { return uniform() < p; }
  std::uint64_t bits() { return engine_(); }

 private:
  std::mt19937_64 engine_;
};

// A well-mixed seed for stream `index` derived from `seed` (SplitMix64), so run k of a simulation
// is reproducible on its own.
inline std::uint64_t derive_seed(std::uint64_t seed, std::uint64_t index) {
  std::uint64_t z = seed + 0x9E3779B97F4A7C15ull * (index + 1);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

}  // namespace penumbra::sampling
