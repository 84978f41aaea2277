#include "io/report.h"

namespace penumbra::io {

// Hand-written: the timing method is an enum, written as its name.
nlohmann::json to_json(const std::vector<gl::PassStats>& stats) {
  nlohmann::json passes = nlohmann::json::array();
  for (const auto& s : stats)
    passes.push_back({{"pass", s.pass}, {"method", gl::to_string(s.method)}, {"median_ms", s.median_ms},
                      {"min_ms", s.min_ms}, {"max_ms", s.max_ms}, {"samples", s.samples}});
  return passes;
}

}  // namespace penumbra::io
