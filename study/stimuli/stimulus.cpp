#include "stimuli/stimulus.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <span>
#include <stdexcept>
#include <string_view>
#include <vector>

#include "gl/context.h"
#include "gl/objects.h"
#include "sampling/poisson_disk.h"
#include "sampling/random.h"
#include "shadows/renderer.h"
#include "shadows/technique.h"

namespace penumbra::stimuli {

Geometry make_geometry(const StimulusSpec& spec) {
  sampling::Random random(sampling::derive_seed(spec.seed, 0x5717));
  Geometry g;
  const double a = spec.artifact_px;
  g.orientation = static_cast<int>(random.bits() % 8);
  const int quarter = g.orientation % 4;
  const double c = std::cos(quarter * std::numbers::pi / 2), s = std::sin(quarter * std::numbers::pi / 2);
  // glm is column-major: dmat2(col0, col1).
  glm::dmat2 rotation(glm::dvec2(std::round(c), std::round(s)), glm::dvec2(-std::round(s), std::round(c)));
  glm::dmat2 mirror = g.orientation >= 4 ? glm::dmat2(glm::dvec2(-1, 0), glm::dvec2(0, 1)) : glm::dmat2(1.0);
  g.to_canonical = rotation * mirror;

  const glm::dvec2 grid_phase(random.uniform() * a, random.uniform() * a);
  const double u_line = random.uniform();
  if (spec.pattern == Pattern::stair) {
    g.line_m = 1.0;
    g.line_b = (u_line - 0.5) * a;
  } else {
    // Rises half a texel across the stimulus, so it crosses exactly one row of texel centres
    // (the one nearest the centre), at x_c inside the middle half.
    const double y_c = grid_phase.y + 0.5 * a - a * std::round((grid_phase.y + 0.5 * a) / a);
    const double x_c = (u_line - 0.5) * 0.5 * spec.size_px;
    g.line_m = 0.5 * a / spec.size_px;
    g.line_b = y_c - g.line_m * x_c;
  }
  const double radius = clamp_filter_radius(spec.filter_radius_px, spec.size_px).filter_radius_px;
  const int k = static_cast<int>(std::ceil((0.5 * spec.size_px + radius) / a)) + 2;
  g.map_origin_px = grid_phase - glm::dvec2(k * a);
  g.map_texels = 2 * k + 1;
  g.poisson_rotation = random.uniform() * 2 * std::numbers::pi;
  return g;
}

namespace {
const display::DisplayCalibration& measured(const Transfer& transfer) {
  if (!transfer.calibration) throw std::logic_error("a measured display transfer without its calibration");
  return *transfer.calibration;
}
}  // namespace

std::uint8_t encode(double linear, const Transfer& transfer) {
  const double v = std::clamp(linear, 0.0, 1.0);
  if (transfer.kind == Transfer::Kind::measured) return measured(transfer).encode(v);
  double e = v;
  if (transfer.kind == Transfer::Kind::srgb) e = v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1 / 2.4) - 0.055;
  if (transfer.kind == Transfer::Kind::gamma22) e = std::pow(v, 1 / 2.2);
  return static_cast<std::uint8_t>(std::lround(std::clamp(e, 0.0, 1.0) * 255.0));
}

double decode(std::uint8_t value, const Transfer& transfer) {
  if (transfer.kind == Transfer::Kind::measured) return measured(transfer).relative_luminance(value);
  const double e = value / 255.0;
  if (transfer.kind == Transfer::Kind::srgb) return e <= 0.04045 ? e / 12.92 : std::pow((e + 0.055) / 1.055, 2.4);
  if (transfer.kind == Transfer::Kind::gamma22) return std::pow(e, 2.2);
  return e;
}

// Hand-written: two structs in one object, enums as names, renamed keys (contrast) and fixed explanations.
nlohmann::json to_json(const StimulusSpec& spec, const Geometry& g) {
  return {{"pattern", to_string(spec.pattern)},
          {"artifact_px", spec.artifact_px},
          {"filter_radius_px", spec.filter_radius_px},
          {"contrast", spec.lit_linear},
          {"contrast_meaning", "lit level in linear light, fraction of display white"},
          {"kernel", to_string(spec.kernel)},
          {"poisson_taps", spec.poisson_taps},
          {"size_px", spec.size_px},
          {"seed", spec.seed},
          {"transfer_function", to_string(spec.transfer)},
          {"orientation", g.orientation},
          {"line", {{"m", g.line_m}, {"b", g.line_b}, {"frame", "canonical px, origin at centre, y up; occluder below"}}},
          {"shadow_map", {{"texels", g.map_texels}, {"texel_px", spec.artifact_px},
                          {"origin_px", {g.map_origin_px.x, g.map_origin_px.y}}}},
          {"poisson_rotation_rad", g.poisson_rotation}};
}

namespace {

// The part of the rectangle [lo, hi] below the line y = m x + b (Sutherland–Hodgman, one plane).
std::vector<glm::dvec2> occluder_polygon(glm::dvec2 lo, glm::dvec2 hi, double m, double b) {
  const std::vector<glm::dvec2> square = {{lo.x, lo.y}, {hi.x, lo.y}, {hi.x, hi.y}, {lo.x, hi.y}};
  auto inside = [&](glm::dvec2 p) { return p.y - m * p.x - b; };  // < 0: occluded side
  std::vector<glm::dvec2> out;
  for (std::size_t i = 0; i < square.size(); ++i) {
    const glm::dvec2 p = square[i], q = square[(i + 1) % square.size()];
    const double fp = inside(p), fq = inside(q);
    if (fp < 0) out.emplace_back(p);
    if ((fp < 0) != (fq < 0)) out.emplace_back(p + (q - p) * (fp / (fp - fq)));
  }
  return out;
}

// Canonical offset -> screen offset (y up): to_canonical is a dihedral map, its inverse its transpose.
glm::dvec2 to_screen(const Geometry& g, glm::dvec2 q) { return glm::transpose(g.to_canonical) * q; }
// Screen offset at `height` -> world (the camera looks down -y with screen up = world -z).
glm::vec3 to_world(glm::dvec2 screen, double height) {
  return {static_cast<float>(screen.x), static_cast<float>(height), static_cast<float>(-screen.y)};
}

// Height of the occluder over the receiver: clear of the receiver's depth and normal-offset
// biases (0.5 + 0.75 texels toward the light by default) by far.
double occluder_height(const StimulusSpec& spec) { return 4 * spec.artifact_px + 4; }

// Antiderivative of clamp(u, 0, L).
double clamp_antiderivative(double u, double L) {
  if (u <= 0) return 0;
  if (u <= L) return 0.5 * u * u;
  return 0.5 * L * L + L * (u - L);
}

// The lit fraction of the square q +- r against the edge y = m x + b (lit above): the lit height
// of the column at x is clamp(q.y + r - (m x + b), 0, 2r), linear in x.
double box_over_edge(glm::dvec2 q, double r, double m, double b) {
  const double u_left = q.y + r - m * (q.x - r) - b, u_right = q.y + r - m * (q.x + r) - b, L = 2 * r;
  const double lit = std::abs(m) < 1e-12 ? L * std::clamp(u_left, 0.0, L)
                                         : (clamp_antiderivative(u_left, L) - clamp_antiderivative(u_right, L)) / m;
  return std::clamp(lit / (L * L), 0.0, 1.0);
}

// The lit fraction of the disk of radius r around q against the edge y = m x + b (lit above):
// one minus the circular segment beyond the chord at the centre's signed distance s from the edge.
double disk_over_edge(glm::dvec2 q, double r, double m, double b) {
  const double s = (q.y - m * q.x - b) / std::sqrt(1 + m * m);
  if (s >= r) return 1;
  if (s <= -r) return 0;
  const double segment = r * r * std::acos(s / r) - s * std::sqrt(r * r - s * s);
  return std::clamp(1 - segment / (std::numbers::pi * r * r), 0.0, 1.0);
}

[[noreturn]] void refuse_setting(const std::string& key, const std::string& what) {
  throw std::invalid_argument(key + ": " + what);
}

}  // namespace

scene::Scene stimulus_scene(const StimulusSpec& spec, const Geometry& g) {
  const double a = spec.artifact_px, h = occluder_height(spec);
  const glm::dvec2 lo = g.map_origin_px, hi = g.map_origin_px + glm::dvec2(a * g.map_texels);
  auto polygon = [&](const std::vector<glm::dvec2>& corners, double height) {
    scene::MeshData m;
    for (const glm::dvec2& c : corners) m.vertices.push_back({to_world(to_screen(g, c), height), {0, 1, 0}});
    for (std::uint32_t i = 1; i + 1 < corners.size(); ++i) m.indices.insert(m.indices.end(), {0, i, i + 1});
    return std::make_shared<const scene::MeshData>(std::move(m));
  };
  scene::Scene s;
  s.name = "stimulus";
  // The receiver is the map's footprint exactly: the unfitted map spans the scene's bounds.
  s.objects.push_back({"receiver", polygon({{lo.x, lo.y}, {hi.x, lo.y}, {hi.x, hi.y}, {lo.x, hi.y}}, 0), glm::mat4(1), glm::vec3(1)});
  if (const auto occluder = occluder_polygon(lo, hi, g.line_m, g.line_b); occluder.size() >= 3)
    s.objects.push_back({"occluder", polygon(occluder, h), glm::mat4(1), glm::vec3(1)});
  s.light.type = scene::Light::Type::directional;
  s.light.direction = {0, -1, 0};
  s.light.size = 0.5f;
  s.light.ambient = 0;
  s.camera.projection = scene::Camera::Projection::orthographic;
  s.camera.position = {0, static_cast<float>(h / 2), 0};  // under the occluder: it sees only the receiver
  s.camera.target = {0, 0, 0};
  s.camera.up = {0, 0, -1};
  s.camera.ortho_height_ws = static_cast<float>(spec.size_px);
  s.camera.near_ws = static_cast<float>(h / 8);
  s.camera.far_ws = static_cast<float>(h);
  return s;
}

shadows::ShadowSettings stimulus_settings(const StimulusSpec& spec, int map_texels, double texel_px) {
  using namespace shadows;
  ShadowSettings s;
  try {
    s.technique = technique_from_string(spec.technique);
  } catch (const std::invalid_argument& e) {
    refuse_setting("technique", e.what());
  }
  const TechniqueEntry& entry = technique_entry(s.technique);
  if (!entry.set_filter_radius) {
    std::vector<std::string> names;  // from the registry: every technique whose radius a trial can set
    for (const auto name : technique_names())
      if (technique_entry(technique_from_string(name)).set_filter_radius) names.emplace_back(name);
    std::string with;
    for (std::size_t i = 0; i < names.size(); ++i)
      with += (i == 0 ? "" : i + 1 == names.size() ? " and " : ", ") + names[i];
    refuse_setting("technique", "'" + spec.technique + "' has no fixed filter radius for the trial to set (" + with + " have)");
  }
  s.pcf.rotate = false;          // one tap pattern for every pixel (a rotated one is noise)
  s.pcf.max_grid_taps = 256;     // exact box up to a radius of 127 texels
  s.rpcf.max_grid_taps = 256;
  for (const auto& [key, value] : spec.technique_settings) {
    const std::size_t dot = key.find('.');
    if (dot == std::string::npos) refuse_setting(key, "expected section.key, e.g. pcf.kernel");
    const std::string section = key.substr(0, dot), row_key = key.substr(dot + 1);
    bool found = false;
    auto apply = [&](auto& params) {
      for (const auto& row : settings_table(&params)) {
        if (row.key != row_key) continue;
        try {
          set_from_string(row, params, value);
        } catch (const std::invalid_argument& e) {
          refuse_setting(key, e.what());
        }
        found = true;
      }
    };
    if (section == "map") {
      for (std::string_view own : {"resolution_texels", "fit", "cascades", "cascade_lambda", "cascade_blend", "cascade_stabilize"})
        if (row_key == own) refuse_setting(key, "set by the study (one unfitted map whose texel is the artifact)");
      apply(s.map);
    } else if (section == spec.technique) {
      if (row_key == "radius" || row_key == "radius_unit") refuse_setting(key, "set by the study from the trial's filter radius");
      for_each_technique_section(s, [&](std::string_view name, auto& params) {
        if (name == section) apply(params);
      });
    } else {
      refuse_setting(key, "not a setting of technique '" + spec.technique + "' (expected " + spec.technique + ".* or map.*)");
    }
    if (!found) refuse_setting(key, "no such setting");
  }
  s.map.resolution_texels = map_texels;
  s.map.fit = false;
  s.map.cascades = 1;
  s.adaptive.enabled = false;
  const double radius_px = clamp_filter_radius(spec.filter_radius_px, spec.size_px).filter_radius_px;
  entry.set_filter_radius(s, {static_cast<float>(radius_px / (texel_px > 0 ? texel_px : spec.artifact_px)), RadiusUnit::texels});
  return s;
}

PartnerMethod partner_for(const shadows::ShadowSettings& s) {
  using shadows::Technique;
  const shadows::TechniqueEntry& entry = shadows::technique_entry(s.technique);
  if (s.technique == Technique::pcf && s.pcf.kernel == shadows::Kernel::poisson) {
    if (s.pcf.rotate) throw std::invalid_argument("pcf.rotate: a disk rotated per pixel has no partner here (set it false)");
    return PartnerMethod::edge_taps;
  }
  if (s.technique == Technique::pcf && s.pcf.kernel == shadows::Kernel::disk) return PartnerMethod::disk_integral;
  if (s.technique == Technique::pcf || s.technique == Technique::rpcf) return PartnerMethod::box_integral;
  if (entry.moments && entry.moments(s)) return PartnerMethod::fine_map;
  throw std::invalid_argument("technique: '" + std::string(shadows::to_string(s.technique)) +
                              "' has no artifact-free partner here (pcf, rpcf and the filtered-moments techniques have)");
}

std::string partner_unavailable(const shadows::ShadowSettings& s) {
  try {
    partner_for(s);
    return "";
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
}

StimulusSpec as_renderer_pcf(const StimulusSpec& spec) {
  if (!spec.technique.empty()) return spec;
  StimulusSpec out = spec;
  out.technique = "pcf";
  out.technique_settings = {{"pcf.kernel", to_string(spec.kernel)}};
  if (spec.kernel == Kernel::poisson) out.technique_settings.emplace_back("pcf.poisson_taps", std::to_string(spec.poisson_taps));
  return out;
}

int fine_map_texels(const StimulusSpec& spec, const Geometry& g) {
  const double radius = clamp_filter_radius(spec.filter_radius_px, spec.size_px).filter_radius_px;
  const double extent = spec.artifact_px * g.map_texels, wanted_texel = std::min(spec.artifact_px, radius) / 64;
  const double texels = std::ceil(extent / wanted_texel);
  return static_cast<int>(std::clamp(texels, static_cast<double>(g.map_texels), static_cast<double>(kMaxFineMapTexels)));
}

struct StimulusRenderer::Impl {
  std::unique_ptr<shadows::Renderer> renderer;  // made on the first stimulus
};

StimulusRenderer::StimulusRenderer() : impl_(std::make_unique<Impl>()) {}
StimulusRenderer::~StimulusRenderer() = default;

StimulusPair StimulusRenderer::render(const StimulusSpec& spec) { return render(spec, make_geometry(spec)); }

StimulusPair StimulusRenderer::render(const StimulusSpec& spec, const Geometry& geometry) {
  validate(spec);
  return render_with_technique(spec.technique.empty() ? as_renderer_pcf(spec) : spec, geometry);
}

StimulusPair StimulusRenderer::render_with_technique(const StimulusSpec& spec_in, const Geometry& g) {
  StimulusSpec spec = spec_in;
  spec.filter_radius_px = clamp_filter_radius(spec.filter_radius_px, spec.size_px).filter_radius_px;
  const shadows::ShadowSettings settings = stimulus_settings(spec, g.map_texels);
  const PartnerMethod partner = partner_for(settings);
  if (!impl_->renderer) impl_->renderer = std::make_unique<shadows::Renderer>();
  shadows::Renderer& renderer = *impl_->renderer;
  renderer.set_scene(stimulus_scene(spec, g));
  renderer.reset_adaptive();
  const int n = spec.size_px, texels = g.map_texels;
  renderer.render(settings, n, n);

  // The map as the light sees it (u = screen x, v = screen y, top row first), indexed canonically.
  const io::ImageF depth = renderer.read_shadow_depth(0);
  const double a = spec.artifact_px;
  glm::dvec2 lo_screen(1e300);
  for (const glm::dvec2 corner : {glm::dvec2(0, 0), glm::dvec2(1, 0), glm::dvec2(0, 1), glm::dvec2(1, 1)})
    lo_screen = glm::min(lo_screen, to_screen(g, g.map_origin_px + corner * (a * texels)));
  last_map_.assign(static_cast<std::size_t>(texels) * texels, 1);
  for (int j = 0; j < texels; ++j) {
    for (int i = 0; i < texels; ++i) {
      const glm::dvec2 centre = to_screen(g, g.map_origin_px + (glm::dvec2(i, j) + 0.5) * a);
      const int u = static_cast<int>(std::floor((centre.x - lo_screen.x) / a));
      const int v = static_cast<int>(std::floor((centre.y - lo_screen.y) / a));
      if (u >= 0 && v >= 0 && u < depth.width && v < depth.height)
        last_map_[static_cast<std::size_t>(j) * texels + i] = depth.at(u, depth.height - 1 - v) < 0.5f ? 0 : 1;
    }
  }

  StimulusPair pair;
  pair.geometry = g;
  pair.artifact_visibility = renderer.read_visibility();
  pair.line_visibility = {n, n, 1, std::vector<float>(static_cast<std::size_t>(n) * n)};
  std::optional<io::ImageF> fine;  // the fine_map partner's visibility
  if (partner == PartnerMethod::fine_map) {
    const int fine_texels = fine_map_texels(spec, g);
    renderer.render(stimulus_settings(spec, fine_texels, a * texels / fine_texels), n, n);
    fine = renderer.read_visibility();
  }
  pair.artifact = {n, n, 1, std::vector<std::uint8_t>(static_cast<std::size_t>(n) * n)};
  pair.line = pair.artifact;
  // The partner: the same filter over the original edge (partner_unavailable says which have one).
  const double r = spec.filter_radius_px;
  std::vector<glm::dvec2> taps;  // canonical offsets of the Poisson taps (the renderer's disk, unrotated)
  if (partner == PartnerMethod::edge_taps)
    for (const glm::vec2 t : sampling::poisson_disk(settings.pcf.poisson_taps)) taps.push_back(g.to_canonical * (r * glm::dvec2(t)));
  for (int y = 0; y < n; ++y) {
    for (int x = 0; x < n; ++x) {
      const glm::dvec2 q = g.to_canonical * glm::dvec2(x + 0.5 - 0.5 * n, (n - 1 - y) + 0.5 - 0.5 * n);
      double v = 0;
      if (fine) {
        v = fine->at(x, y);
      } else if (partner == PartnerMethod::box_integral) {
        v = box_over_edge(q, r, g.line_m, g.line_b);
      } else if (partner == PartnerMethod::disk_integral) {
        v = disk_over_edge(q, r, g.line_m, g.line_b);
      } else {
        for (const glm::dvec2 t : taps) v += (q + t).y >= g.line_m * (q + t).x + g.line_b ? 1 : 0;
        v /= static_cast<double>(taps.size());
      }
      pair.line_visibility.at(x, y) = static_cast<float>(v);
      pair.line.at(x, y) = encode(spec.lit_linear * v, spec.transfer);
      pair.artifact.at(x, y) = encode(spec.lit_linear * pair.artifact_visibility.at(x, y), spec.transfer);
    }
  }
  gl::check_errors("stimulus render (renderer)");
  return pair;
}

}  // namespace penumbra::stimuli
