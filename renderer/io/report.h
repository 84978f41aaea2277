#pragma once
// JSON for reports: the GL device, and per-pass times with the method that produced each time.
// A rendered frame's report is shadows/frame_report.h.
#include <vector>

#include <nlohmann/json.hpp>

#include <penumbra/gl/context.h>
#include <penumbra/gl/timer.h>

namespace penumbra::gl {

// {"vendor", "renderer", "version", "platform", "software", "max_texture_size"}: nlohmann::json(info).
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(ContextInfo, vendor, renderer, version, platform, software, max_texture_size)

}  // namespace penumbra::gl

namespace penumbra::io {

nlohmann::json to_json(const std::vector<gl::PassStats>& stats);

}  // namespace penumbra::io
