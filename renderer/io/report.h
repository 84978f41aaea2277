#pragma once
// JSON reports of rendered frames: settings, light frame, passes and their times with the
// method that produced each time, and the GL device.
#include <vector>

#include <nlohmann/json.hpp>

#include "gl/context.h"
#include "gl/timer.h"
#include "shadows/renderer.h"

namespace penumbra::io {

nlohmann::json to_json(const gl::ContextInfo& info);
nlohmann::json to_json(const shadows::LightFrame& light);
nlohmann::json to_json(const std::vector<gl::PassStats>& stats);
nlohmann::json frame_report(const shadows::FrameInfo& frame, const shadows::ShadowSettings& settings,
                            const std::vector<gl::PassStats>& stats);

}  // namespace penumbra::io
