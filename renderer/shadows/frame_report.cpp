#include "shadows/frame_report.h"

#include <cmath>

#include "io/report.h"

namespace penumbra::shadows {

// Hand-written: "projection" names the bool `perspective`.
nlohmann::json to_json(const LightFrame& l) {
  return {{"projection", l.perspective ? "perspective" : "orthographic"},
          {"fitted", l.fitted},
          {"receivers_visible", l.receivers_visible},
          {"s_xy", l.s_xy},
          {"extent_ws", l.extent_ws},
          {"near_ws", l.near_ws},
          {"far_ws", l.far_ws}};
}

nlohmann::json virtual_pages_json(const VirtualMapStats& p) {
  return {{"requested", p.requested}, {"cached", p.cached},   {"drawn", p.drawn},
          {"missing", p.missing},     {"evicted", p.evicted}, {"invalidated", p.invalidated}, {"widened", p.widened},
          {"resident", p.resident},   {"floor", p.floor},     {"floor_level", p.floor_level},
          {"triangles", p.triangles}, {"draws", p.draws}};
}

nlohmann::json virtual_map_json(const FrameInfo::Virtual& v) {
  nlohmann::json pages = virtual_pages_json(v.pages);
  pages["search"] = v.search_pages;
  return {{"pages", pages},
          {"pool_pages_per_side", v.pool_pages_per_side},
          {"light", {{"near_ws", v.near_ws}, {"far_ws", v.far_ws}}},
          {"pixels_per_level", v.pixels_per_level},
          {"unmarked_pixels", v.unmarked},
          {"bytes", {{"resident_pages", v.resident_bytes}, {"tables", v.table_bytes}, {"pool_allocated", v.pool_bytes}}},
          {"shaded_pixels", {{"at_level", v.at_level}, {"coarser", v.coarser}, {"none", v.none}}},
          {"marks",
           {{"late", v.marks_late},
            {"region_floor_pages", v.region_floor},
            {"shaded_pixels_of_previous_frame", v.shaded_of_previous_frame},
            {"sync_reads", v.sync_reads}}}};
}

nlohmann::json work_json(const std::vector<PassWork>& work) {
  nlohmann::json j = nlohmann::json::object();
  for (const PassWork& w : work)
    j[w.pass] = {{"primitives", w.primitives}, {"fragments", w.fragments}, {"compute_invocations", w.compute_invocations}};
  return j;
}

nlohmann::json frame_report(const FrameInfo& frame, const ShadowSettings& settings, const std::vector<gl::PassStats>& stats) {
  nlohmann::json j;
  j["settings"] = to_json(settings);
  j["resolution_texels"] = frame.resolution_texels;
  j["image_px"] = {frame.width_px, frame.height_px};
  j["light"] = to_json(frame.light);
  if (frame.filter_radius_texels > 0) j["filter_radius_texels"] = frame.filter_radius_texels;
  j["passes_run"] = frame.passes;
  j["timings"] = io::to_json(stats);
  j["adaptive"] = frame.adaptive;
  j["resolution_source"] = frame.resolution_source;
  j["storage"] = frame.storage;
  j["atlas_texels"] = {frame.atlas_width, frame.atlas_height};
  nlohmann::json cascades = nlohmann::json::array();
  for (const auto& c : frame.cascades) {
    nlohmann::json cj{{"resolution_texels", c.resolution_texels},
                      {"split_view_depth_ws", {c.split_near_ws, c.split_far_ws}},
                      {"extent_ws", c.light.extent_ws},
                      {"s_xy", c.light.s_xy},
                      {"atlas_origin_texels", {c.atlas_x, c.atlas_y}}};
    if (frame.adaptive) cj["required_texels"] = std::isfinite(c.required_texels) ? nlohmann::json(c.required_texels) : nlohmann::json("inf");
    cascades.push_back(cj);
  }
  j["cascades"] = cascades;
  j["triangles"] = {{"maps", frame.map_triangles}, {"camera", frame.camera_triangles}, {"scene", frame.scene_triangles}};
  if (frame.pcss_requirement.valid) {
    const auto& r = frame.pcss_requirement;
    j["pcss_requirement"] = {{"required_texels", r.required_texels},
                             {"evaluated_pixels", r.evaluated_pixels},
                             {"clamped_fraction", r.clamped_fraction},
                             {"above_max_fraction", r.above_max_fraction}};
  }
  if (!frame.work.empty()) j["work"] = work_json(frame.work);
  if (frame.virtual_map) j["virtual_map"] = virtual_map_json(*frame.virtual_map);
  return j;
}

}  // namespace penumbra::shadows
