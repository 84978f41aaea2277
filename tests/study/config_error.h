#pragma once
// The one line a study config is refused with ("no error" when it loads), for the config tests.
#include <stdexcept>
#include <string>

#include <nlohmann/json.hpp>

#include "procedure/config.h"

namespace penumbra::test {

inline std::string config_error(const nlohmann::json& j) {
  try {
    procedure::parse_config(j, "study.json");
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "no error";
}

}  // namespace penumbra::test
