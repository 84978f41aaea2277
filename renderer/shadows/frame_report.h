#pragma once
// The JSON report of a rendered frame: settings, light frame, passes and their times with the
// method that produced each time, the resolution used per cascade.
#include <vector>

#include <nlohmann/json.hpp>

#include <penumbra/gl/timer.h>
#include <penumbra/shadows/fitting.h>
#include <penumbra/shadows/renderer.h>
#include <penumbra/shadows/settings.h>

namespace penumbra::shadows {

nlohmann::json to_json(const LightFrame& light);
// FrameInfo::work as report.json holds it: {pass: {primitives, fragments, compute_invocations}}.
nlohmann::json work_json(const std::vector<PassWork>& work);
nlohmann::json frame_report(const FrameInfo& frame, const ShadowSettings& settings, const std::vector<gl::PassStats>& stats);

}  // namespace penumbra::shadows
