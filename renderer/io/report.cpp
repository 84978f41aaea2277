#include "io/report.h"

namespace penumbra::io {

nlohmann::json to_json(const gl::ContextInfo& info) {
  return {{"vendor", info.vendor},   {"renderer", info.renderer}, {"version", info.version},
          {"platform", info.platform}, {"software", info.software}, {"max_texture_size", info.max_texture_size}};
}

nlohmann::json to_json(const shadows::LightFrame& l) {
  return {{"projection", l.perspective ? "perspective" : "orthographic"},
          {"fitted", l.fitted},
          {"receivers_visible", l.receivers_visible},
          {"s_xy", l.s_xy},
          {"extent_ws", l.extent_ws},
          {"near_ws", l.near_ws},
          {"far_ws", l.far_ws}};
}

nlohmann::json to_json(const std::vector<gl::PassStats>& stats) {
  nlohmann::json passes = nlohmann::json::array();
  for (const auto& s : stats)
    passes.push_back({{"pass", s.pass}, {"method", gl::to_string(s.method)}, {"median_ms", s.median_ms},
                      {"min_ms", s.min_ms}, {"max_ms", s.max_ms}, {"samples", s.samples}});
  return passes;
}

nlohmann::json frame_report(const shadows::FrameInfo& frame, const shadows::ShadowSettings& settings,
                            const std::vector<gl::PassStats>& stats) {
  nlohmann::json j;
  j["settings"] = shadows::to_json(settings);
  j["resolution_texels"] = frame.resolution_texels;
  j["image_px"] = {frame.width_px, frame.height_px};
  j["light"] = to_json(frame.light);
  if (frame.filter_radius_texels > 0) j["filter_radius_texels"] = frame.filter_radius_texels;
  j["passes_run"] = frame.passes;
  j["timings"] = to_json(stats);
  return j;
}

}  // namespace penumbra::io
