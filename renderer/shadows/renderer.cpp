#include "shadows/renderer.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <optional>
#include <random>
#include <stdexcept>
#include <utility>

#include <glm/gtc/type_ptr.hpp>

#include "adaptive/cascades.h"
#include "adaptive/resolution_rule.h"
#include "shadows/moments.h"
#include "shadows/scoped_pass.h"
#include "shadows/screen_space.h"
#include "shadows/technique.h"

namespace penumbra::shadows {

std::vector<glm::vec2> poisson_disk(int taps) {
  taps = std::clamp(taps, 1, 64);
  std::mt19937 rng(20170815u + static_cast<unsigned>(taps));
  std::uniform_real_distribution<float> u(-1, 1);
  std::vector<glm::vec2> pts;
  auto random_in_disk = [&] {
    for (;;) {
      glm::vec2 p(u(rng), u(rng));
      if (glm::dot(p, p) <= 1) return p;
    }
  };
  // Mitchell's best candidate: each new tap is the candidate farthest from those placed so far.
  for (int i = 0; i < taps; ++i) {
    glm::vec2 best{};
    float best_d = -1;
    for (int c = 0; c < 32 * (i + 1); ++c) {
      const glm::vec2 p = random_in_disk();
      float d = 1e9f;
      for (const auto& q : pts) d = std::min(d, glm::distance(p, q));
      if (d > best_d) best_d = d, best = p;
    }
    pts.push_back(best);
  }
  float r_max = 0;
  for (const auto& p : pts) r_max = std::max(r_max, glm::length(p));
  if (r_max > 0)
    for (auto& p : pts) p /= r_max;
  return pts;
}

namespace {

constexpr int kGuardTexels = 2;  // far-depth band around each map in a shared atlas (see atlas_uv in common.glsl)
constexpr int kMaxCascades = 4;

}  // namespace

struct Renderer::Maps {
  int width = 0, height = 0;
  GLenum moments_format = 0;  // 0: depth only
  gl::Texture depth;
  gl::Framebuffer depth_fbo;
  gl::Texture moments_tex, moments_tmp;
  gl::Framebuffer moments_fbo;
};

struct Renderer::Targets {
  int width = 0, height = 0;
  bool requirement = false;
  gl::Texture color, visibility, requirement_tex, depth;
  gl::Framebuffer fbo;
};

// Hysteresis per cascade, and the PCSS requirement buffers (two, so that the frame reads the one
// written a frame earlier and never waits for the GPU).
struct Renderer::Adaptive {
  std::string key;  // what the controllers were made for; a change restarts them
  std::vector<adaptive::ResolutionController> controllers;
  gl::Buffer requirement[2];
  bool requirement_pending[2] = {false, false};
  int requirement_cascades[2] = {0, 0};
  float requirement_c[2] = {0, 0};
  int frame = 0;
  PcssRequirementInfo last;  // the newest measured requirement
  int last_cascades = 0;     // cascade count it was measured with
  float last_c = 0;
};

Renderer::Renderer() : adaptive_(std::make_unique<Adaptive>()) {
  depth_program_ = shaders_.program({{GL_VERTEX_SHADER, "shadow_depth.vert"}, {GL_FRAGMENT_SHADER, "shadow_depth.frag"}});
  requirement_program_ = shaders_.program({{GL_COMPUTE_SHADER, "pcss_requirement.comp"}});
  gl::SamplerDesc d;
  d.depth_compare = true;
  cmp_linear_ = gl::Sampler(d);
  d.min_filter = d.mag_filter = GL_NEAREST;
  cmp_nearest_ = gl::Sampler(d);
  d.depth_compare = false;
  raw_nearest_ = gl::Sampler(d);
  // Beyond the map the border reads as the far depth: lit, like the depth samplers' border and the
  // guard band of an atlas region. Each frame sets the border to its technique's far moments.
  moments_linear_ = gl::Sampler(gl::SamplerDesc{});
  gl::check_errors("renderer setup");
}

Renderer::~Renderer() = default;

void Renderer::set_scene(const scene::Scene& s) {
  scene_ = s;
  meshes_.clear();
  for (const auto& o : scene_.objects) meshes_.push_back(std::make_unique<scene::GpuMesh>(*o.mesh));
  reset_adaptive();
  gl::check_errors("scene upload");
}

void Renderer::reset_adaptive() {
  adaptive_->key.clear();
  adaptive_->controllers.clear();
  adaptive_->requirement_pending[0] = adaptive_->requirement_pending[1] = false;
  adaptive_->last = {};
  adaptive_->last_cascades = 0;
}

const gl::Program& Renderer::cached_program(const std::string& key, const std::vector<gl::ShaderStage>& stages,
                                            const std::vector<gl::ShaderDefine>& defines) {
  auto it = programs_.find(key);
  if (it == programs_.end()) it = programs_.emplace(key, shaders_.program(stages, defines)).first;
  return it->second;
}

const gl::Program& Renderer::shading_program(const ShadowSettings& s, bool gbuffer) {
  const TechniqueEntry& entry = technique_entry(s.technique);
  std::vector<gl::ShaderDefine> defines;
  if (gbuffer) {
    // The first pass of a screen-space technique: its input shadows, revectorized or hard.
    const bool rbsm = entry.rbsm_input && entry.rbsm_input(s);
    defines.push_back({std::string(technique_entry(rbsm ? Technique::rbsm : Technique::hard).define), "1"});
    defines.push_back({"SCREEN_SPACE_GBUFFER", "1"});
  } else {
    defines.push_back({std::string(entry.define), "1"});
    if (entry.variant_defines) entry.variant_defines(s, defines);
  }
  if (entry.per_pixel_requirement && s.adaptive.enabled && s.adaptive.pcss == PcssRequirement::per_pixel)
    defines.push_back({"PCSS_REQUIREMENT", "1"});
  std::string key = "shading:";
  for (const auto& d : defines) key += d.name + ";";
  return cached_program(key, {{GL_VERTEX_SHADER, "shading.vert"}, {GL_FRAGMENT_SHADER, "shading.frag"}}, defines);
}

void Renderer::draw_scene(const gl::Program& program, bool shading) {
  const GLint model_loc = program.location("u_model");
  const GLint normal_loc = program.location("u_normal_matrix");
  const GLint albedo_loc = program.location("u_albedo");
  for (std::size_t i = 0; i < meshes_.size(); ++i) {
    const auto& o = scene_.objects[i];
    glProgramUniformMatrix4fv(program.id(), model_loc, 1, GL_FALSE, glm::value_ptr(o.model));
    if (shading) {
      const glm::mat3 nm = glm::transpose(glm::inverse(glm::mat3(o.model)));
      glProgramUniformMatrix3fv(program.id(), normal_loc, 1, GL_FALSE, glm::value_ptr(nm));
      glProgramUniform3fv(program.id(), albedo_loc, 1, glm::value_ptr(o.albedo));
    }
    meshes_[i]->draw();
  }
}

namespace {

void set_float(const gl::Program& p, const char* name, float v) { glProgramUniform1f(p.id(), p.location(name), v); }
void set_int(const gl::Program& p, const char* name, int v) { glProgramUniform1i(p.id(), p.location(name), v); }
void set_vec3(const gl::Program& p, const char* name, const glm::vec3& v) {
  glProgramUniform3fv(p.id(), p.location(name), 1, glm::value_ptr(v));
}
void set_mat4(const gl::Program& p, const char* name, const glm::mat4& m) {
  glProgramUniformMatrix4fv(p.id(), p.location(name), 1, GL_FALSE, glm::value_ptr(m));
}

// World-space radius the adaptive rule hides texels with, for the technique's filter; 0 when the
// technique has none (hard shadows). Radii given in texels are taken at map.resolution_texels of
// the single fitted map: "the filter the user sees at the configured resolution".
float rule_radius_ws(const ShadowSettings& s, const LightFrame& single, float mid_depth_ws) {
  const TechniqueEntry& entry = technique_entry(s.technique);
  if (entry.filter_radius) {
    const FilterRadius r = entry.filter_radius(s);
    return r.unit == RadiusUnit::world ? r.radius : r.radius * single.texel_ws(mid_depth_ws, s.map.resolution_texels);
  }
  return entry.rule_radius_ws ? entry.rule_radius_ws(s) : 0.0f;
}

// The rule for one map: directional c · L / r_ws; spot: c / r_uv at the far end of the depth
// range, where a world-space radius spans the fewest texels.
double rule_texels(float c, const LightFrame& f, float radius_ws) {
  if (!f.perspective) return adaptive::required_texels_ws(c, f.extent_ws, radius_ws);
  const double uv_per_ws = f.s_xy / (2.0 * std::max(f.far_ws, 1e-6f) * std::tan(glm::radians(f.fov_deg) / 2));
  return adaptive::required_texels_uv(c, radius_ws * uv_per_ws);
}

// Region corners for `res` per cascade: one row of up to two cells, then a second row.
struct AtlasLayout {
  int width = 0, height = 0;
  std::vector<glm::ivec2> origin;  // inner corner of each region
};
AtlasLayout layout_atlas(const std::vector<int>& cell_texels, int guard) {
  AtlasLayout a;
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

}  // namespace

FrameInfo Renderer::render(const ShadowSettings& s, int width_px, int height_px, gl::PassTimer* timer) {
  if (width_px < 1 || height_px < 1) throw std::runtime_error("render: image size must be positive");
  if (s.map.resolution_texels < 1) throw std::runtime_error("render: shadow-map resolution must be at least 1 texel");
  const AdaptiveParams& ap = s.adaptive;
  if (ap.enabled && (ap.min_texels < 1 || ap.max_texels < ap.min_texels))
    throw std::runtime_error("render: adaptive.min_texels must be >= 1 and <= adaptive.max_texels");
  FrameInfo info;
  info.width_px = width_px;
  info.height_px = height_px;
  info.adaptive = ap.enabled;
  const TechniqueEntry& entry = technique_entry(s.technique);
  const std::optional<MomentsLayout> moments = entry.moments ? entry.moments(s) : std::nullopt;
  const std::optional<FilterRadius> filter_radius = entry.filter_radius ? std::optional(entry.filter_radius(s)) : std::nullopt;
  const scene::Light& light = scene_.light;
  const bool directional = light.type == scene::Light::Type::directional;
  const float aspect = static_cast<float>(width_px) / static_cast<float>(height_px);
  Adaptive& ad = *adaptive_;

  // Padding of the fitted frustum by the filter's reach.
  FitRequest fit{s.map.fit, aspect, s.map.resolution_texels, 0, 0};
  const float tan_half_angle = std::tan(glm::radians(std::max(light.size, 0.0f)) / 2);
  fit.pad_texels = static_cast<float>(entry.pad_texels);
  if (filter_radius) {
    (filter_radius->unit == RadiusUnit::texels ? fit.pad_texels : fit.pad_ws) = filter_radius->radius;
  } else if (entry.search_scale) {
    const scene::Aabb b = scene_.bounds();
    const float depth_range = b.empty() ? 1.0f : glm::length(b.hi - b.lo);
    fit.pad_ws = entry.search_scale(s) * (light.type == scene::Light::Type::spot ? light.size / 2 : tan_half_angle * depth_range);
  }

  // The PCSS requirement measured by the previous frame (its buffer's GPU work is done by now on
  // any pipelined GPU; reading it here costs no stall).
  if (const int other = 1 - ad.frame % 2; ad.requirement_pending[other]) {
    std::uint32_t raw[16] = {};
    glGetNamedBufferSubData(ad.requirement[other].id(), 0, sizeof raw, raw);
    ad.requirement_pending[other] = false;
    PcssRequirementInfo r;
    r.valid = true;
    double evaluated = 0, clamped = 0, above = 0;
    for (int i = 0; i < ad.requirement_cascades[other]; ++i) {
      float max_inverse_uv = 0;
      std::memcpy(&max_inverse_uv, &raw[i], sizeof max_inverse_uv);
      r.required_texels.push_back(static_cast<double>(ad.requirement_c[other]) * max_inverse_uv);
      evaluated += raw[4 + i];
      clamped += raw[8 + i];
      above += raw[12 + i];
    }
    r.evaluated_pixels = evaluated;
    r.clamped_fraction = evaluated > 0 ? clamped / evaluated : 0;
    r.above_max_fraction = evaluated > 0 ? above / evaluated : 0;
    ad.last = r;
    ad.last_cascades = ad.requirement_cascades[other];
    ad.last_c = ad.requirement_c[other];
  }

  // --- plan: cascades, the rule, resolutions ---------------------------------------------------
  const LightFrame single = compute_light_frame(scene_, fit);
  const float radius_ws = rule_radius_ws(s, single, 0.5f * (single.near_ws + single.far_ws));
  const int fixed_res = s.map.resolution_texels;
  const int largest = ap.enabled ? ap.max_texels : fixed_res;
  auto cascades_for = [&](int count, const std::vector<int>& res) {
    return compute_cascades(scene_, CascadeRequest{count, s.map.cascade_lambda, s.map.cascade_stabilize, aspect, res,
                                                   fit.pad_texels, fit.pad_ws, s.map.fit});
  };
  auto requirements = [&](const Cascades& c) {
    std::vector<double> req;
    for (const auto& f : c.frames) req.push_back(rule_texels(ap.c, f, radius_ws));
    return req;
  };
  // Screen-space techniques work on one map.
  int count = directional && !entry.screen_space() ? s.map.cascades : 1;
  if (count == 0) {
    const adaptive::CascadeChoice choice = adaptive::choose_cascade_count(kMaxCascades, largest, [&](int n) {
      return requirements(cascades_for(n, std::vector<int>(static_cast<std::size_t>(n), largest)));
    });
    count = choice.count;
  }
  count = std::clamp(count, 1, kMaxCascades);
  if (!single.receivers_visible) count = 1;  // nothing to split (compute_cascades returns one map)

  std::vector<int> res(static_cast<std::size_t>(count), fixed_res);
  std::vector<double> req(static_cast<std::size_t>(count), 0.0);
  info.resolution_source = "fixed";
  if (ap.enabled) {
    const std::string key = std::to_string(count) + "/" + std::to_string(ap.min_texels) + "/" + std::to_string(ap.max_texels) + "/" +
                            std::to_string(ap.quantum_texels) + "/" + std::to_string(ap.shrink_delay_frames) + "/" +
                            std::string(to_string(s.technique));
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
    std::vector<int> previous(static_cast<std::size_t>(count));
    for (int i = 0; i < count; ++i) {
      const int cur = ad.controllers[static_cast<std::size_t>(i)].current();
      previous[static_cast<std::size_t>(i)] = cur > 0 ? cur : largest;
    }
    req = requirements(cascades_for(count, previous));
    info.resolution_source = entry.per_pixel_requirement ? "pcss_min_penumbra" : "rule";
    if (entry.per_pixel_requirement && ap.pcss == PcssRequirement::per_pixel && ad.last.valid &&
        ad.last_cascades == count) {
      // Measured last frame: c / r_filter over the visible pixels, never above the min-penumbra bound.
      for (int i = 0; i < count; ++i) {
        const double measured = ad.last.required_texels[static_cast<std::size_t>(i)] * ap.c / ad.last_c;
        req[static_cast<std::size_t>(i)] = std::min(req[static_cast<std::size_t>(i)], measured);
      }
      info.resolution_source = "pcss_per_pixel";
      info.pcss_requirement = ad.last;
    }
    for (int i = 0; i < count; ++i) res[static_cast<std::size_t>(i)] = ad.controllers[static_cast<std::size_t>(i)].update(req[static_cast<std::size_t>(i)]);
  }
  const Cascades cascades = cascades_for(count, res);
  for (int i = 0; i < count; ++i) {
    const auto k = static_cast<std::size_t>(i);
    CascadeInfo ci;
    ci.light = cascades.frames[k];
    ci.resolution_texels = res[k];
    ci.required_texels = req[k];
    ci.split_near_ws = cascades.splits_ws[k];
    ci.split_far_ws = cascades.splits_ws[k + 1];
    info.cascades.push_back(ci);
  }
  info.light = info.cascades.front().light;
  info.resolution_texels = info.cascades.front().resolution_texels;
  const LightFrame& lf = info.light;
  const float mid_depth = 0.5f * (lf.near_ws + lf.far_ws);
  const float texel_mid_ws = lf.texel_ws(mid_depth, info.resolution_texels);

  // --- storage -------------------------------------------------------------------------------
  const bool subrect = ap.enabled && ap.storage == Storage::subrect;
  info.storage = subrect ? "subrect" : "realloc";
  std::vector<int> cells(static_cast<std::size_t>(count));
  for (int i = 0; i < count; ++i) cells[static_cast<std::size_t>(i)] = subrect ? ap.max_texels : res[static_cast<std::size_t>(i)];
  // A single map that fills its texture needs no guard band: the sampler's border is lit.
  const int guard = count == 1 && !subrect ? 0 : kGuardTexels;
  const AtlasLayout layout = layout_atlas(cells, guard);
  for (int i = 0; i < count; ++i) {
    info.cascades[static_cast<std::size_t>(i)].atlas_x = layout.origin[static_cast<std::size_t>(i)].x;
    info.cascades[static_cast<std::size_t>(i)].atlas_y = layout.origin[static_cast<std::size_t>(i)].y;
  }
  info.atlas_width = layout.width;
  info.atlas_height = layout.height;
  const GLenum moments_format = moments ? moments->format : 0;
  if (!maps_ || maps_->width != layout.width || maps_->height != layout.height || maps_->moments_format != moments_format) {
    GLint max_size = 0;
    glGetIntegerv(GL_MAX_TEXTURE_SIZE, &max_size);
    if (layout.width > max_size || layout.height > max_size)
      throw std::runtime_error("render: shadow atlas " + std::to_string(layout.width) + "x" + std::to_string(layout.height) +
                               " exceeds GL_MAX_TEXTURE_SIZE " + std::to_string(max_size) +
                               " (lower map.resolution_texels, adaptive.max_texels or map.cascades)");
    maps_.reset();
    auto m = std::make_unique<Maps>();
    m->width = layout.width;
    m->height = layout.height;
    m->moments_format = moments_format;
    m->depth = gl::Texture({GL_DEPTH_COMPONENT32F, layout.width, layout.height, 1}, "shadow depth atlas");
    const GLint grey[4] = {GL_RED, GL_RED, GL_RED, GL_ONE};  // debug views show depth as grey
    glTextureParameteriv(m->depth.id(), GL_TEXTURE_SWIZZLE_RGBA, grey);
    const gl::Framebuffer::Attachment depth_only[] = {{&m->depth, GL_DEPTH_ATTACHMENT}};
    m->depth_fbo = gl::Framebuffer(depth_only, "shadow depth framebuffer");
    if (moments) {
      m->moments_tex = gl::Texture({moments_format, layout.width, layout.height, 1}, "shadow moments");
      m->moments_tmp = gl::Texture({moments_format, layout.width, layout.height, 1}, "moments blur temporary");
      const gl::Framebuffer::Attachment att[] = {{&m->moments_tex, GL_COLOR_ATTACHMENT0}, {&m->depth, GL_DEPTH_ATTACHMENT}};
      m->moments_fbo = gl::Framebuffer(att, "moments framebuffer");
    }
    maps_ = std::move(m);
    info.reallocated = true;
  }
  const bool want_requirement = entry.per_pixel_requirement && ap.enabled && ap.pcss == PcssRequirement::per_pixel;
  if (!targets_ || targets_->width != width_px || targets_->height != height_px || targets_->requirement != want_requirement) {
    targets_.reset();
    auto t = std::make_unique<Targets>();
    t->width = width_px;
    t->height = height_px;
    t->requirement = want_requirement;
    t->color = gl::Texture({GL_SRGB8_ALPHA8, width_px, height_px, 1}, "lit colour");
    t->visibility = gl::Texture({GL_R32F, width_px, height_px, 1}, "visibility");
    t->depth = gl::Texture({GL_DEPTH_COMPONENT32F, width_px, height_px, 1}, "camera depth");
    if (want_requirement) {
      t->requirement_tex = gl::Texture({GL_RG32F, width_px, height_px, 1}, "PCSS requirement");
      const gl::Framebuffer::Attachment att[] = {{&t->color, GL_COLOR_ATTACHMENT0},
                                                 {&t->visibility, GL_COLOR_ATTACHMENT1},
                                                 {&t->requirement_tex, GL_COLOR_ATTACHMENT2},
                                                 {&t->depth, GL_DEPTH_ATTACHMENT}};
      t->fbo = gl::Framebuffer(att, "camera framebuffer");
    } else {
      const gl::Framebuffer::Attachment att[] = {{&t->color, GL_COLOR_ATTACHMENT0}, {&t->visibility, GL_COLOR_ATTACHMENT1}, {&t->depth, GL_DEPTH_ATTACHMENT}};
      t->fbo = gl::Framebuffer(att, "camera framebuffer");
    }
    targets_ = std::move(t);
  }

  glDisable(GL_CULL_FACE);  // thin planes and open meshes cast from both sides
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDepthMask(GL_TRUE);

  // --- shadow map ----------------------------------------------------------------------------
  {
    ScopedPass pass(timer, "shadow_map", info.passes);
    const gl::Program& prog =
        moments ? cached_program(std::string("moments:") + moments->fragment_shader,
                                 {{GL_VERTEX_SHADER, "shadow_depth.vert"}, {GL_FRAGMENT_SHADER, moments->fragment_shader}})
                : depth_program_;
    (moments ? maps_->moments_fbo : maps_->depth_fbo).bind();
    glEnable(GL_DEPTH_CLAMP);  // casters in front of the fitted near plane still occlude
    glEnable(GL_SCISSOR_TEST);
    prog.use();
    for (const auto& c : info.cascades) {
      // Clear the region and its guard band only: the rest of a sub-rectangle atlas is never read.
      const int r = c.resolution_texels;
      glScissor(c.atlas_x - guard, c.atlas_y - guard, r + 2 * guard, r + 2 * guard);
      if (moments) glClearBufferfv(GL_COLOR, 0, moments->far_moments.data());
      const float one = 1;
      glClearBufferfv(GL_DEPTH, 0, &one);
      glViewport(c.atlas_x, c.atlas_y, r, r);
      glScissor(c.atlas_x, c.atlas_y, r, r);
      if (!moments) {
        glEnable(GL_POLYGON_OFFSET_FILL);
        glPolygonOffset(s.map.slope_bias, s.map.offset_bias);
      }
      set_mat4(prog, "u_light_view_projection", c.light.view_projection());
      set_mat4(prog, "u_light_view", c.light.view);
      if (moments) {
        set_float(prog, "u_light_near_ws", c.light.near_ws);
        set_float(prog, "u_light_far_ws", c.light.far_ws);
        if (entry.set_uniforms) entry.set_uniforms(prog, s);
      }
      draw_scene(prog, false);
    }
    glDisable(GL_SCISSOR_TEST);
    glDisable(GL_POLYGON_OFFSET_FILL);
    glDisable(GL_DEPTH_CLAMP);
    gl::check_errors("shadow_map pass");
  }

  if (filter_radius)
    info.filter_radius_texels = filter_radius->unit == RadiusUnit::texels ? filter_radius->radius : filter_radius->radius / texel_mid_ws;

  // --- moments blur (VSM, MSM, EVSM) ---------------------------------------------------------
  if (moments) {
    const char* qualifier = image_format_qualifier(moments->format);
    std::vector<gl::ShaderDefine> blur_defines = {{"MOMENTS_CHANNELS", std::to_string(channel_count(moments->format))},
                                                  {"MOMENTS_FORMAT", qualifier}};
    if (moments->direct_sums) blur_defines.push_back({"DIRECT_SUMS", "1"});
    const gl::Program& blur = cached_program(std::string("blur:") + qualifier + (moments->direct_sums ? ":direct" : ""),
                                             {{GL_COMPUTE_SHADER, "vsm_blur.comp"}}, blur_defines);
    ScopedPass pass(timer, "vsm_blur", info.passes);
    blur.use();
    glBindSampler(0, 0);
    for (const auto& c : info.cascades) {
      // World-space radii span a different number of texels in each cascade.
      const float texel = c.light.texel_ws(mid_depth, c.resolution_texels);
      set_float(blur, "u_radius_texels", filter_radius->unit == RadiusUnit::texels ? filter_radius->radius : filter_radius->radius / texel);
      glProgramUniform2i(blur.id(), blur.location("u_origin"), c.atlas_x, c.atlas_y);
      set_int(blur, "u_size", c.resolution_texels);
      const GLuint groups = static_cast<GLuint>((c.resolution_texels + 63) / 64);
      // Sliding sums: one invocation per line (x); direct sums: one per texel, x along the line and
      // y the line (vsm_blur.comp). The map is square, so both grids are `groups` x (1 or res).
      const GLuint lines_y = moments->direct_sums ? static_cast<GLuint>(c.resolution_texels) : 1;
      set_int(blur, "u_axis", 0);
      maps_->moments_tex.bind(0);
      glBindImageTexture(0, maps_->moments_tmp.id(), 0, GL_FALSE, 0, GL_WRITE_ONLY, moments->format);
      glDispatchCompute(groups, lines_y, 1);
      glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
      set_int(blur, "u_axis", 1);
      maps_->moments_tmp.bind(0);
      glBindImageTexture(0, maps_->moments_tex.id(), 0, GL_FALSE, 0, GL_WRITE_ONLY, moments->format);
      glDispatchCompute(groups, lines_y, 1);
      glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
    }
    gl::check_errors("vsm_blur pass");
  }

  // --- shading (and, for screen-space techniques, the G-buffer and post passes) --------------
  const scene::Camera& cam = scene_.camera;
  // Light frame, cascades, biases and the technique's uniforms: shared by both camera passes and
  // the screen-space compute passes (uniforms a program lacks are ignored).
  auto set_shading_uniforms = [&](const gl::Program& prog) {
    set_mat4(prog, "u_view_projection", cam.projection_matrix(aspect) * cam.view());
    set_mat4(prog, "u_camera_view", cam.view());
    set_mat4(prog, "u_light_view", lf.view);
    set_int(prog, "u_light_perspective", lf.perspective ? 1 : 0);
    set_float(prog, "u_light_near_ws", lf.near_ws);
    set_float(prog, "u_light_far_ws", lf.far_ws);
    set_float(prog, "u_light_s_xy", lf.s_xy);
    set_float(prog, "u_light_tan_half_fov", std::tan(glm::radians(lf.fov_deg) / 2));
    set_int(prog, "u_cascade_count", count);
    set_float(prog, "u_cascade_blend", count > 1 ? s.map.cascade_blend : 0.0f);
    set_int(prog, "u_show_cascades", show_cascades_ ? 1 : 0);
    for (int i = 0; i < count; ++i) {
      const CascadeInfo& c = info.cascades[static_cast<std::size_t>(i)];
      const std::string at = "[" + std::to_string(i) + "]";
      set_mat4(prog, ("u_cascade_view_projection" + at).c_str(), c.light.view_projection());
      const glm::vec4 region(static_cast<float>(c.atlas_x) / layout.width, static_cast<float>(c.atlas_y) / layout.height,
                             static_cast<float>(c.resolution_texels) / layout.width, static_cast<float>(c.resolution_texels) / layout.height);
      glProgramUniform4fv(prog.id(), prog.location(("u_cascade_region" + at).c_str()), 1, glm::value_ptr(region));
      set_float(prog, ("u_cascade_res" + at).c_str(), static_cast<float>(c.resolution_texels));
      set_float(prog, ("u_cascade_extent_ws" + at).c_str(), c.light.extent_ws);
      set_float(prog, ("u_cascade_far_ws" + at).c_str(), c.split_far_ws);
    }
    // Trust receiver slopes up to 85° from the light: |d depth/d uv| ≤ tan 85° · extent / depth range.
    set_float(prog, "u_rpdb_max", std::tan(glm::radians(85.0f)) * texel_mid_ws * static_cast<float>(info.resolution_texels) / std::max(lf.far_ws - lf.near_ws, 1e-6f));
    set_int(prog, "u_receiver_plane_bias", s.map.receiver_plane_bias ? 1 : 0);
    set_vec3(prog, "u_light_direction", glm::normalize(light.direction));
    set_vec3(prog, "u_light_position", light.position);
    const float half_cone = glm::radians(light.spot_fov_deg) / 2;
    set_float(prog, "u_spot_cos_outer", std::cos(half_cone));
    set_float(prog, "u_spot_cos_inner", std::cos(half_cone * 0.9f));
    set_vec3(prog, "u_light_color", light.color);
    set_float(prog, "u_ambient", light.ambient);
    set_float(prog, "u_normal_offset_texels", s.map.normal_offset_texels);
    set_float(prog, "u_depth_bias_texels", s.map.depth_bias_texels);
    set_vec3(prog, "u_camera_position", cam.position);
    set_vec3(prog, "u_camera_forward", glm::normalize(cam.target - cam.position));

    if (filter_radius) {
      set_float(prog, "u_filter_radius", filter_radius->radius);
      set_int(prog, "u_filter_radius_world", filter_radius->unit == RadiusUnit::world ? 1 : 0);
    }
    if (entry.set_uniforms) entry.set_uniforms(prog, s);
    if (entry.rbsm_input && entry.rbsm_input(s)) set_rbsm_uniforms(prog, s.rbsm);  // the G-buffer's revectorized input
    if (entry.uses_light_size()) {
      set_float(prog, "u_pcss_light_radius_uv", light.size / 2 * lf.s_xy / std::max(lf.extent_ws, 1e-9f));
      set_float(prog, "u_pcss_tan_half_angle", tan_half_angle);
      set_float(prog, "u_pcss_min_penumbra_ws", s.pcss.min_penumbra_ws);
    }
    const int taps = entry.poisson_taps ? entry.poisson_taps(s) : 0;
    if (taps > 0) {
      auto it = poisson_.find(taps);
      if (it == poisson_.end()) it = poisson_.emplace(taps, poisson_disk(taps)).first;
      glProgramUniform2fv(prog.id(), prog.location("u_poisson"), static_cast<GLsizei>(it->second.size()),
                          glm::value_ptr(it->second[0]));
    }
  };
  auto bind_shadow_maps = [&] {
    maps_->depth.bind(0);
    maps_->depth.bind(1);
    maps_->depth.bind(2);
    cmp_linear_.bind(0);
    cmp_nearest_.bind(1);
    raw_nearest_.bind(2);
    if (moments) {
      glSamplerParameterfv(moments_linear_.id(), GL_TEXTURE_BORDER_COLOR, moments->far_moments.data());
      maps_->moments_tex.bind(3);
      moments_linear_.bind(3);
    }
  };

  const gl::Texture* screen_result = nullptr;
  if (entry.screen_space()) {
    if (!screen_space_) screen_space_ = std::make_unique<ScreenSpace>(shaders_);
    screen_space_->resize(targets_->depth);
    {
      ScopedPass pass(timer, "gbuffer", info.passes);
      const gl::Program& prog = shading_program(s, true);
      screen_space_->gbuffer_framebuffer().bind();
      glViewport(0, 0, width_px, height_px);
      const float nothing[4] = {0, 0, 0, 0}, far_depth = 1;
      glClearBufferfv(GL_COLOR, 0, nothing);
      glClearBufferfv(GL_COLOR, 1, nothing);
      glClearBufferfv(GL_DEPTH, 0, &far_depth);
      prog.use();
      bind_shadow_maps();
      set_shading_uniforms(prog);
      draw_scene(prog, true);
      gl::check_errors("gbuffer pass");
    }
    PostPassContext ctx;
    ctx.view.perspective = cam.projection == scene::Camera::Projection::perspective;
    ctx.view.px_scale = ctx.view.perspective ? static_cast<float>(height_px) / (2 * std::tan(glm::radians(cam.fov_y_deg) / 2))
                                             : static_cast<float>(height_px) / cam.ortho_height_ws;
    ctx.set_light_uniforms = set_shading_uniforms;
    ctx.timer = timer;
    ctx.passes = &info.passes;
    bind_shadow_maps();
    screen_result = &entry.post(*screen_space_, s, ctx);
  }
  {
    ScopedPass pass(timer, "shading", info.passes);
    const gl::Program& prog = shading_program(s);
    targets_->fbo.bind();
    if (want_requirement) {
      const GLenum bufs[] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1, GL_COLOR_ATTACHMENT2};
      glNamedFramebufferDrawBuffers(targets_->fbo.id(), 3, bufs);
    }
    glViewport(0, 0, width_px, height_px);
    glEnable(GL_FRAMEBUFFER_SRGB);
    const float sky[4] = {0.45f, 0.55f, 0.7f, 1};
    const float lit = 1, far_depth = 1;
    glClearBufferfv(GL_COLOR, 0, sky);
    glClearBufferfv(GL_COLOR, 1, &lit);
    if (want_requirement) {
      const float none[4] = {0, 0, 0, 0};
      glClearBufferfv(GL_COLOR, 2, none);
    }
    if (screen_result) {
      // The G-buffer pass left the depth: shade exactly the fragments it kept.
      glDepthFunc(GL_LEQUAL);
      glDepthMask(GL_FALSE);
      glBindSampler(4, 0);
      screen_result->bind(4);
    } else {
      glClearBufferfv(GL_DEPTH, 0, &far_depth);
    }
    prog.use();
    bind_shadow_maps();
    set_shading_uniforms(prog);
    draw_scene(prog, true);
    glDisable(GL_FRAMEBUFFER_SRGB);
    glDepthFunc(GL_LESS);
    glDepthMask(GL_TRUE);
    gl::check_errors("shading pass");
  }

  // --- PCSS requirement (adaptive, per pixel) ------------------------------------------------
  if (want_requirement) {
    ScopedPass pass(timer, "pcss_requirement", info.passes);
    const int slot = ad.frame % 2;
    if (!ad.requirement[slot].id()) ad.requirement[slot] = gl::Buffer(16 * sizeof(std::uint32_t), nullptr, 0);
    const std::uint32_t zero = 0;
    glClearNamedBufferData(ad.requirement[slot].id(), GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
    requirement_program_.use();
    targets_->requirement_tex.bind(0);
    glBindSampler(0, 0);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, ad.requirement[slot].id());
    set_float(requirement_program_, "u_limit_inverse_uv", static_cast<float>(ap.max_texels) / ap.c);
    glDispatchCompute(static_cast<GLuint>((width_px + 63) / 64), static_cast<GLuint>((height_px + 63) / 64), 1);  // 64^2 px per group
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    ad.requirement_pending[slot] = true;
    ad.requirement_cascades[slot] = count;
    ad.requirement_c[slot] = ap.c;
    gl::check_errors("pcss_requirement pass");
  }
  ++ad.frame;
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  if (timer) timer->poll(false);
  last_cascades_ = info.cascades;
  return info;
}

namespace {
template <class T>
void flip_rows(io::Image<T>& img) {
  const std::size_t row = static_cast<std::size_t>(img.width) * img.channels;
  for (int y = 0; y < img.height / 2; ++y)
    std::swap_ranges(img.pixels.begin() + static_cast<std::ptrdiff_t>(y * row),
                     img.pixels.begin() + static_cast<std::ptrdiff_t>((y + 1) * row),
                     img.pixels.begin() + static_cast<std::ptrdiff_t>((img.height - 1 - y) * row));
}

template <class T>
io::Image<T> read_texture(const gl::Texture& tex, GLenum format, GLenum type, int channels) {
  io::Image<T> img{tex.desc().width, tex.desc().height, channels, {}};
  img.pixels.resize(static_cast<std::size_t>(img.width) * img.height * channels);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glGetTextureImage(tex.id(), 0, format, type, static_cast<GLsizei>(img.pixels.size() * sizeof(T)), img.pixels.data());
  gl::check_errors("texture read-back");
  flip_rows(img);
  return img;
}
}  // namespace

void Renderer::present(GLuint target, int width_px, int height_px) const {
  if (!targets_) return;
  glNamedFramebufferReadBuffer(targets_->fbo.id(), GL_COLOR_ATTACHMENT0);
  glBlitNamedFramebuffer(targets_->fbo.id(), target, 0, 0, targets_->width, targets_->height, 0, 0, width_px, height_px,
                         GL_COLOR_BUFFER_BIT, GL_NEAREST);
}

GLuint Renderer::shadow_map_texture() const { return maps_ ? maps_->depth.id() : 0; }

io::Image8 Renderer::read_color() const {
  if (!targets_) throw std::logic_error("read_color before render");
  return read_texture<std::uint8_t>(targets_->color, GL_RGBA, GL_UNSIGNED_BYTE, 4);
}

io::ImageF Renderer::read_visibility() const {
  if (!targets_) throw std::logic_error("read_visibility before render");
  return read_texture<float>(targets_->visibility, GL_RED, GL_FLOAT, 1);
}

io::ImageF Renderer::read_pcss_requirement() const {
  if (!targets_ || !targets_->requirement) throw std::logic_error("read_pcss_requirement before a per-pixel PCSS frame");
  return read_texture<float>(targets_->requirement_tex, GL_RG, GL_FLOAT, 2);
}

io::ImageF Renderer::read_screen_space_input() const {
  if (!screen_space_ || !screen_space_->width()) throw std::logic_error("read_screen_space_input before a screen-space frame");
  const io::ImageF g = read_texture<float>(screen_space_->gbuffer_position(), GL_RGBA, GL_FLOAT, 4);
  io::ImageF vis{g.width, g.height, 1, std::vector<float>(static_cast<std::size_t>(g.width) * g.height)};
  for (int y = 0; y < g.height; ++y)
    for (int x = 0; x < g.width; ++x) vis.at(x, y) = g.at(x, y, 3) < 0 ? 0.0f : 1.0f;  // nothing drawn: lit
  return vis;
}

io::ImageF Renderer::read_shadow_depth(int cascade) const {
  if (!maps_) throw std::logic_error("read_shadow_depth before render");
  if (cascade < 0 || cascade >= static_cast<int>(last_cascades_.size()))
    throw std::out_of_range("read_shadow_depth: no cascade " + std::to_string(cascade));
  const CascadeInfo& c = last_cascades_[static_cast<std::size_t>(cascade)];
  const int r = c.resolution_texels;
  io::ImageF img{r, r, 1, std::vector<float>(static_cast<std::size_t>(r) * r)};
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glGetTextureSubImage(maps_->depth.id(), 0, c.atlas_x, c.atlas_y, 0, r, r, 1, GL_DEPTH_COMPONENT, GL_FLOAT,
                       static_cast<GLsizei>(img.pixels.size() * sizeof(float)), img.pixels.data());
  gl::check_errors("shadow map read-back");
  flip_rows(img);
  return img;
}

}  // namespace penumbra::shadows
