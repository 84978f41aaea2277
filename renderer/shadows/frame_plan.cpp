#include "shadows/frame_plan.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "adaptive/cascades.h"

namespace penumbra::shadows {
namespace {

// World units per map uv: directional 1 / L (the orthographic window); spot at the far end of
// the depth range, where a world-space length spans the fewest texels.
double uv_per_ws(const LightFrame& f) {
  if (!f.perspective) return 1.0 / std::max(static_cast<double>(f.extent_ws), 1e-12);
  return f.s_xy / (2.0 * std::max(f.far_ws, 1e-6f) * std::tan(glm::radians(f.fov_deg) / 2));
}

// The rule for one map: c / r_uv (directional: c · L / r_ws). The rule takes positive, finite
// lengths only; a frame has others by design: a technique without a shadow-map filter (radius 0:
// hard, screen-space) asks for the largest map, a light window with no extent for the smallest.
double rule_texels(float c, const LightFrame& f, float radius_ws) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  if (!(c > 0) || !std::isfinite(c)) throw std::runtime_error("render: adaptive.c must be positive and finite");
  if (!f.perspective && !(f.extent_ws > 0)) return 0;
  if (!(radius_ws > 0)) return kInf;
  if (!std::isfinite(radius_ws)) return 0;
  if (!f.perspective) {
    if (!std::isfinite(f.extent_ws)) return kInf;
    return adaptive::required_texels_ws(c, adaptive::LightExtentWs{f.extent_ws}, adaptive::FilterRadiusWs{radius_ws});
  }
  const double radius_uv = radius_ws * uv_per_ws(f);
  if (!(radius_uv > 0)) return kInf;
  if (!std::isfinite(radius_uv)) return 0;
  return adaptive::required_texels_uv(c, adaptive::FilterRadiusUv{radius_uv});
}

// The texels a map needs for texels no wider than adaptive.max_texel_ws; 0 without a ceiling.
double texel_ceiling_texels(const AdaptiveParams& ap, const LightFrame& f) {
  return ap.max_texel_ws > 0 ? 1.0 / (static_cast<double>(ap.max_texel_ws) * uv_per_ws(f)) : 0.0;
}

// Padding of the fitted frustum by the filter's reach: a fixed filter by its radius, a blocker
// search by its reach at the light's size, and whatever the technique reads beyond a texel.
FitRequest fit_request(const ShadowSettings& s, const TechniqueEntry& entry, const scene::Scene& scene, float aspect,
                       float tan_half_angle) {
  FitRequest fit{s.map.fit, aspect, s.map.resolution_texels, static_cast<float>(entry.pad_texels), 0};
  if (entry.filter_radius) {
    const FilterRadius r = entry.filter_radius(s);
    (r.unit == RadiusUnit::texels ? fit.pad_texels : fit.pad_ws) = r.radius;
  } else if (entry.search_scale) {
    const scene::Light& light = scene.light;
    fit.pad_ws = entry.search_scale(s) * (light.type == scene::Light::Type::spot
                                              ? light.size / 2
                                              : tan_half_angle * shadow_region_diagonal_ws(scene, aspect));
  }
  return fit;
}

}  // namespace

std::string page_reading_techniques() {
  std::vector<std::string_view> names;
  for (const std::string_view name : technique_names())
    if (technique_entry(technique_from_string(name)).pages != PageReading::none) names.push_back(name);
  std::string out;
  for (std::size_t i = 0; i < names.size(); ++i) out += (i == 0 ? "" : i + 1 == names.size() ? " or " : ", ") + std::string(names[i]);
  return out;
}

std::string virtual_marking_unsupported(const ShadowSettings& s) {
  const TechniqueEntry& e = technique_entry(s.technique);
  const std::string name(e.name);
  if (e.pages == PageReading::none) return "pages are marked for " + page_reading_techniques() + ", not " + name;
  if (e.filter_radius && e.filter_radius(s).unit != RadiusUnit::world)
    return name + " marks pages by a world radius (--" + name + ".radius_unit world)";
  return "";
}

std::string virtual_pages_unsupported(const ShadowSettings& s) {
  const TechniqueEntry& e = technique_entry(s.technique);
  const std::string name(e.name);
  if (e.pages == PageReading::none) return "pages are read by " + page_reading_techniques() + ", not " + describe(s);
  // Every setting it lacks, at once: the marking's world radius and the shading's own needs.
  std::string needs;
  if (e.filter_radius && e.filter_radius(s).unit != RadiusUnit::world) needs = "--" + name + ".radius_unit world";
  if (const std::string_view need = e.pages_need ? e.pages_need(s) : std::string_view(); !need.empty())
    needs += (needs.empty() ? "" : " ") + std::string(need);
  return needs.empty() ? "" : name + " reads pages only with " + needs + ", not " + describe(s);
}

std::string virtual_pages_refusal(const ShadowSettings& s, const scene::Scene& scene) {
  if (scene.light.type != scene::Light::Type::directional) return "the virtual shadow map is the sun's; this scene has a spot light";
  return virtual_pages_unsupported(s);
}

bool FramePlan::runs(PassId p) const { return std::find(passes.begin(), passes.end(), p) != passes.end(); }

bool FramePlan::camera_depth_first() const {
  return virtual_pages != VirtualPages::off || (technique && technique->screen_space()) || depth_prepass;
}

PassIo pass_io(PassId pass, const FramePlan& plan) {
  const bool moments = plan.moments.has_value();
  const bool screen = plan.technique && plan.technique->screen_space();
  const bool virtual_pages = plan.virtual_pages != VirtualPages::off;
  switch (pass) {
    case PassId::virtual_pages: return {kSceneMeshes, kVirtualPages | kCameraDepth};
    case PassId::shadow_map: return {kSceneMeshes, kDepthAtlas | (moments ? kMoments : 0u)};
    case PassId::moments_blur: return {kMoments, kMoments};
    case PassId::depth_minmax: return {kDepthAtlas, kDepthMinmax};
    case PassId::gbuffer: return {kSceneMeshes | kDepthAtlas, kGbuffer | kCameraDepth};
    case PassId::post: return {kGbuffer | kDepthAtlas, kScreenVisibility};
    case PassId::depth_prepass: return {kSceneMeshes, kCameraDepth};
    case PassId::shading:
      return {kSceneMeshes | (virtual_pages ? kVirtualPages : kDepthAtlas) | (moments ? kMoments : 0u) | (screen ? kScreenVisibility : 0u) |
                  (plan.runs(PassId::depth_minmax) ? kDepthMinmax : 0u) |
                  (plan.camera_depth_first() ? kCameraDepth : 0u),
              kColor | kVisibility | (plan.pcss_requirement ? kRequirementImage : 0u)};
    case PassId::pcss_requirement: return {kRequirementImage, kRequirementBuffer};
  }
  return {};
}

std::string_view pass_name(PassId pass) {
  switch (pass) {
    case PassId::virtual_pages: return "virtual_pages";
    case PassId::shadow_map: return "shadow_map";
    case PassId::moments_blur: return "vsm_blur";
    case PassId::depth_minmax: return "depth_minmax";
    case PassId::gbuffer: return "gbuffer";
    case PassId::post: return "post";
    case PassId::depth_prepass: return "depth_prepass";
    case PassId::shading: return "shading";
    case PassId::pcss_requirement: return "pcss_requirement";
  }
  return "?";
}

std::string resource_names(unsigned resources) {
  static constexpr std::pair<Resource, std::string_view> kNames[] = {
      {kSceneMeshes, "scene meshes"}, {kDepthAtlas, "depth atlas"},   {kMoments, "moments"},
      {kGbuffer, "G-buffer"},         {kScreenVisibility, "screen visibility"}, {kColor, "colour"},
      {kVisibility, "visibility"},    {kRequirementImage, "requirement image"}, {kRequirementBuffer, "requirement buffer"},
      {kDepthMinmax, "depth min-max pyramid"}, {kVirtualPages, "virtual pages"}, {kCameraDepth, "camera depth"}};
  std::string out;
  for (const auto& [bit, name] : kNames)
    if (resources & bit) out += (out.empty() ? "" : ", ") + std::string(name);
  return out;
}

std::string plan_problem(const FramePlan& plan) {
  unsigned written = kSceneMeshes;
  int last = -1;
  for (const PassId p : plan.passes) {
    if (static_cast<int>(p) <= last)
      return "pass " + std::string(pass_name(p)) + " runs twice or out of order";
    last = static_cast<int>(p);
    const PassIo io = pass_io(p, plan);
    if (const unsigned missing = io.reads & ~written)
      return "pass " + std::string(pass_name(p)) + " reads " + resource_names(missing) + ", which no earlier pass of the frame writes";
    written |= io.writes;
  }
  if (const unsigned missing = (kColor | kVisibility) & ~written) return "the frame never writes its " + resource_names(missing);
  return "";
}

float rule_radius_ws(const ShadowSettings& s, const LightFrame& single, float mid_depth_ws) {
  const TechniqueEntry& entry = technique_entry(s.technique);
  if (entry.filter_radius) {
    const FilterRadius r = entry.filter_radius(s);
    return r.unit == RadiusUnit::world ? r.radius : r.radius * single.texel_ws(mid_depth_ws, s.map.resolution_texels);
  }
  return entry.rule_radius_ws ? entry.rule_radius_ws(s) : 0.0f;
}

AtlasLayout layout_atlas(const std::vector<int>& cell_texels, int guard) {
  AtlasLayout a;
  a.guard = guard;
  int cell = 0;
  for (int t : cell_texels) cell = std::max(cell, t + 2 * guard);
  const int n = static_cast<int>(cell_texels.size());
  for (int i = 0; i < n; ++i) a.origin.emplace_back((i % 2) * cell + guard, (i / 2) * cell + guard);
  if (n == 1) {
    a.width = a.height = cell_texels[0] + 2 * guard;
  } else {
    a.width = std::min(n, 2) * cell;
    a.height = ((n + 1) / 2) * cell;
  }
  return a;
}

FramePlan plan_frame(const ShadowSettings& s, const scene::Scene& scene, int width_px, int height_px, AdaptiveState& ad) {
  if (width_px < 1 || height_px < 1) throw std::runtime_error("render: image size must be positive");
  if (s.map.resolution_texels < 1) throw std::runtime_error("render: shadow-map resolution must be at least 1 texel");
  const AdaptiveParams& ap = s.adaptive;
  if (ap.enabled && (ap.min_texels < 1 || ap.max_texels < ap.min_texels))
    throw std::runtime_error("render: adaptive.min_texels must be >= 1 and <= adaptive.max_texels");
  FramePlan plan;
  const TechniqueEntry& entry = technique_entry(s.technique);
  plan.technique = &entry;
  plan.width_px = width_px;
  plan.height_px = height_px;
  plan.aspect = static_cast<float>(width_px) / static_cast<float>(height_px);
  plan.moments = entry.moments ? entry.moments(s) : std::nullopt;
  if (entry.filter_radius) plan.filter_radius = entry.filter_radius(s);
  const scene::Light& light = scene.light;
  const bool directional = light.type == scene::Light::Type::directional;
  plan.tan_half_angle = std::tan(glm::radians(std::max(light.size, 0.0f)) / 2);
  const FitRequest fit = fit_request(s, entry, scene, plan.aspect, plan.tan_half_angle);

  // --- cascades and the rule ---
  const LightFrame single = compute_light_frame(scene, fit);
  if (s.map.virtual_pages != VirtualPages::off) {
    // The sun's virtual shadow map: pages instead of maps (virtual_shadow_map.h). The single fitted
    // frame stands for the light in the frame's uniforms; no map is drawn, the atlas is one texel.
    if (const std::string why = virtual_pages_refusal(s, scene); !why.empty()) throw std::runtime_error("render: map.virtual_pages: " + why);
    plan.virtual_pages = s.map.virtual_pages;
    plan.moments.reset();  // VSM's moments are the pages' (kVirtualPages), not a moments atlas's
    plan.resolution_source = s.map.virtual_pages == VirtualPages::rule ? "virtual_rule" : "virtual_footprint";
    CascadeInfo ci;
    ci.light = single;
    ci.resolution_texels = 1;
    ci.split_far_ws = std::numeric_limits<float>::max();
    plan.cascades.push_back(ci);
    plan.atlas = layout_atlas({1}, 0);
    plan.passes = {PassId::virtual_pages, PassId::shading};
    return plan;
  }
  const float radius_ws = rule_radius_ws(s, single, 0.5f * (single.near_ws + single.far_ws));
  const int fixed_res = s.map.resolution_texels;
  const int largest = ap.enabled ? ap.max_texels : fixed_res;
  auto cascades_for = [&](int count, const std::vector<int>& res) {
    return compute_cascades(scene, CascadeRequest{count, s.map.cascade_lambda, s.map.cascade_stabilize, plan.aspect, res,
                                                  fit.pad_texels, fit.pad_ws, s.map.fit});
  };
  // World width one pixel covers at view depth d, facing the camera.
  const scene::Camera& camera = scene.camera;
  auto pixel_ws = [&](double depth_ws) {
    if (camera.projection == scene::Camera::Projection::orthographic) return camera.ortho_height_ws / static_cast<double>(height_px);
    return 2.0 * depth_ws * std::tan(glm::radians(static_cast<double>(camera.fov_y_deg)) / 2) / static_cast<double>(height_px);
  };
  auto requirements = [&](const Cascades& c) {
    std::vector<double> req;
    for (std::size_t i = 0; i < c.frames.size(); ++i) {
      const LightFrame& f = c.frames[i];
      double r = rule_texels(ap.c, f, radius_ws);
      if (ap.min_texel_px > 0 && !f.perspective) {
        const double finest_ws = ap.min_texel_px * pixel_ws(c.splits_ws[i]);
        if (finest_ws > 0) r = std::min(r, f.extent_ws / finest_ws);
      }
      req.push_back(std::max(r, texel_ceiling_texels(ap, f)));
    }
    return req;
  };
  // Screen-space techniques work on one map.
  int count = directional && !entry.screen_space() ? s.map.cascades : 1;
  if (count == 0) {
    const adaptive::CascadeChoice choice = adaptive::choose_cascade_count(kMaxCascades, largest, [&](int n) {
      return requirements(cascades_for(n, std::vector<int>(static_cast<std::size_t>(n), largest)));
    });
    // Like each cascade's resolution: more cascades at once (a requirement above the largest map
    // would show its staircase), fewer only after the smaller count has sufficed for
    // shrink_delay_frames frames in a row (the count flipping with every small camera move
    // re-splits the view and restarts the resolutions: flicker).
    if (ad.auto_count == 0 || choice.count > ad.auto_count) {
      ad.auto_count = choice.count, ad.auto_count_frames_below = 0;
    } else if (choice.count < ad.auto_count) {
      if (++ad.auto_count_frames_below >= ap.shrink_delay_frames) ad.auto_count = choice.count, ad.auto_count_frames_below = 0;
    } else {
      ad.auto_count_frames_below = 0;
    }
    count = ad.auto_count;
  }
  count = std::clamp(count, 1, kMaxCascades);
  if (!single.receivers_visible) count = 1;  // nothing to split (compute_cascades returns one map)

  const auto n = static_cast<std::size_t>(count);
  std::vector<int> res(n, fixed_res);
  std::vector<double> req(n, 0.0);
  plan.resolution_source = "fixed";
  if (ap.enabled) {
    const std::string key = std::to_string(count) + "/" + std::to_string(ap.min_texels) + "/" + std::to_string(ap.max_texels) + "/" +
                            std::to_string(ap.quantum_texels) + "/" + std::to_string(ap.shrink_delay_frames) + "/" +
                            std::string(entry.name);
    if (key != ad.key) {
      ad.key = key;
      ad.controllers.clear();
      adaptive::ResolutionController::Params params;
      params.limits = {ap.min_texels, ap.max_texels, ap.quantum_texels};
      params.shrink_delay_frames = ap.shrink_delay_frames;
      for (int i = 0; i < count; ++i) ad.controllers.emplace_back(params);
    }
    // The requirement, from frames sized at the previous resolutions (padding and snapping are in
    // texels, so the extents move slightly with the resolution; the rule's answer barely does).
    std::vector<int> previous(n);
    for (std::size_t i = 0; i < n; ++i) {
      const int cur = ad.controllers[i].current();
      previous[i] = cur > 0 ? cur : largest;
    }
    const Cascades sized = cascades_for(count, previous);
    req = requirements(sized);
    plan.resolution_source = entry.per_pixel_requirement ? "pcss_min_penumbra" : "rule";
    if (entry.per_pixel_requirement && ap.pcss == PcssRequirement::per_pixel && ad.last.valid && ad.last_cascades == count) {
      // Measured last frame: c / r_filter over the visible pixels, never above the min-penumbra bound.
      // The texel ceiling holds here too.
      for (std::size_t i = 0; i < n; ++i)
        req[i] = std::max(std::min(req[i], ad.last.required_texels[i] * ap.c / ad.last_c), texel_ceiling_texels(ap, sized.frames[i]));
      plan.resolution_source = "pcss_per_pixel";
      plan.used_requirement = ad.last;
    }
    for (std::size_t i = 0; i < n; ++i) res[i] = ad.controllers[i].update(req[i]);
  }
  const Cascades cascades = cascades_for(count, res);
  for (std::size_t i = 0; i < n; ++i) {
    CascadeInfo ci;
    ci.light = cascades.frames[i];
    ci.resolution_texels = res[i];
    ci.required_texels = req[i];
    ci.split_near_ws = cascades.splits_ws[i];
    ci.split_far_ws = cascades.splits_ws[i + 1];
    plan.cascades.push_back(ci);
  }

  // --- storage ---
  plan.subrect = ap.enabled && ap.storage == Storage::subrect;
  std::vector<int> cells(n);
  for (std::size_t i = 0; i < n; ++i) cells[i] = plan.subrect ? ap.max_texels : res[i];
  // A single map that fills its texture needs no guard band: the sampler's border is lit.
  plan.atlas = layout_atlas(cells, count == 1 && !plan.subrect ? 0 : kGuardTexels);
  for (std::size_t i = 0; i < n; ++i) {
    plan.cascades[i].atlas_x = plan.atlas.origin[i].x;
    plan.cascades[i].atlas_y = plan.atlas.origin[i].y;
  }

  if (plan.filter_radius) {
    const LightFrame& lf = plan.light();
    const float texel_mid_ws = lf.texel_ws(0.5f * (lf.near_ws + lf.far_ws), plan.cascades.front().resolution_texels);
    plan.filter_radius_texels =
        plan.filter_radius->unit == RadiusUnit::texels ? plan.filter_radius->radius : plan.filter_radius->radius / texel_mid_ws;
  }

  // --- passes ---
  plan.pcss_requirement = entry.per_pixel_requirement && ap.enabled && ap.pcss == PcssRequirement::per_pixel;
  plan.passes.push_back(PassId::shadow_map);
  if (plan.moments) plan.passes.push_back(PassId::moments_blur);
  if (entry.depth_minmax && entry.depth_minmax(s)) plan.passes.push_back(PassId::depth_minmax);
  if (entry.screen_space()) {
    plan.passes.push_back(PassId::gbuffer);
    plan.passes.push_back(PassId::post);
  } else if (s.map.depth_prepass) {
    plan.depth_prepass = true;
    plan.passes.push_back(PassId::depth_prepass);
  }
  plan.passes.push_back(PassId::shading);
  if (plan.pcss_requirement) plan.passes.push_back(PassId::pcss_requirement);
  return plan;
}

}  // namespace penumbra::shadows
