#pragma once
// FNV-1a 64: a short, stable fingerprint of bytes, the same on every machine and standard
// library. Seeds from participant ids, and the fingerprints session.json records of what a
// participant was shown (a display calibration, the consent text).
#include <cstdint>
#include <cstdio>
#include <string>
#include <string_view>

namespace penumbra::text {

constexpr std::uint64_t fnv1a64(std::string_view bytes) {
  std::uint64_t h = 1469598103934665603ull;
  for (const char c : bytes) h = (h ^ static_cast<unsigned char>(c)) * 1099511628211ull;
  return h;
}

// fnv1a64 as 16 lower-case hex digits.
inline std::string fnv1a64_hex(std::string_view bytes) {
  char b[17];
  std::snprintf(b, sizeof b, "%016llx", static_cast<unsigned long long>(fnv1a64(bytes)));
  return b;
}

}  // namespace penumbra::text
