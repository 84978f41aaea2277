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
// A virtual map's page counts (VirtualMapStats) and a frame's virtual map (FrameInfo::Virtual) as
// every report holds them: penumbra-render's report.json, the main job's `last_frame`, the pages
// run's pages.json (one writer, one key set; issue 47).
nlohmann::json virtual_pages_json(const VirtualMapStats& pages);
nlohmann::json virtual_map_json(const FrameInfo::Virtual& v);
// FrameInfo::work as report.json holds it: {pass: {primitives, fragments, compute_invocations}}.
nlohmann::json work_json(const std::vector<PassWork>& work);
nlohmann::json frame_report(const FrameInfo& frame, const ShadowSettings& settings, const std::vector<gl::PassStats>& stats);

}  // namespace penumbra::shadows
