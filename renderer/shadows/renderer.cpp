#include "shadows/renderer.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

#include <glm/gtc/type_ptr.hpp>

#include "shadows/scoped_pass.h"
#include "shadows/screen_space.h"

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

struct Renderer::Maps {
  int resolution = 0;
  bool moments = false;
  gl::Texture depth;
  gl::Framebuffer depth_fbo;
  gl::Texture moments_tex, moments_tmp;
  gl::Framebuffer moments_fbo;
};

struct Renderer::Targets {
  int width = 0, height = 0;
  gl::Texture color, visibility, depth;
  gl::Framebuffer fbo;
};

Renderer::Renderer() {
  depth_program_ = shaders_.program({{GL_VERTEX_SHADER, "shadow_depth.vert"}, {GL_FRAGMENT_SHADER, "shadow_depth.frag"}});
  moments_program_ = shaders_.program({{GL_VERTEX_SHADER, "shadow_depth.vert"}, {GL_FRAGMENT_SHADER, "shadow_moments.frag"}});
  blur_program_ = shaders_.program({{GL_COMPUTE_SHADER, "vsm_blur.comp"}});
  gl::SamplerDesc d;
  d.depth_compare = true;
  cmp_linear_ = gl::Sampler(d);
  d.min_filter = d.mag_filter = GL_NEAREST;
  cmp_nearest_ = gl::Sampler(d);
  d.depth_compare = false;
  raw_nearest_ = gl::Sampler(d);
  gl::SamplerDesc m;
  m.wrap = GL_CLAMP_TO_EDGE;
  moments_linear_ = gl::Sampler(m);
  gl::check_errors("renderer setup");
}

Renderer::~Renderer() = default;

void Renderer::set_scene(const scene::Scene& s) {
  scene_ = s;
  meshes_.clear();
  for (const auto& o : scene_.objects) meshes_.push_back(std::make_unique<scene::GpuMesh>(*o.mesh));
  gl::check_errors("scene upload");
}

const gl::Program& Renderer::shading_program(const ShadowSettings& s, bool gbuffer) {
  std::vector<gl::ShaderDefine> defines;
  if (is_screen_space(s.technique)) {
    // First pass: the input shadows (plain hard shadows; the revectorized ones once RBSM exists).
    if (gbuffer) defines.push_back({"TECHNIQUE_HARD", "1"}), defines.push_back({"SCREEN_SPACE_GBUFFER", "1"});
    else if (s.technique == Technique::erosion) defines.push_back({"TECHNIQUE_EROSION", "1"});
    else defines.push_back({"SCREEN_SPACE_VISIBILITY", "1"});
  } else {
    const char* names[] = {"TECHNIQUE_HARD", "TECHNIQUE_PCF", "TECHNIQUE_PCSS", "TECHNIQUE_VSM"};
    defines.push_back({names[static_cast<int>(s.technique)], "1"});
    const Kernel kernel = s.technique == Technique::pcss ? s.pcss.kernel : s.pcf.kernel;
    if (kernel == Kernel::grid) defines.push_back({"KERNEL_GRID", "1"});
  }
  std::string key;
  for (const auto& d : defines) key += d.name + ";";
  auto it = shading_programs_.find(key);
  if (it == shading_programs_.end())
    it = shading_programs_.emplace(key, shaders_.program({{GL_VERTEX_SHADER, "shading.vert"}, {GL_FRAGMENT_SHADER, "shading.frag"}}, defines)).first;
  return it->second;
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


}  // namespace

FrameInfo Renderer::render(const ShadowSettings& s, int width_px, int height_px, gl::PassTimer* timer) {
  if (width_px < 1 || height_px < 1) throw std::runtime_error("render: image size must be positive");
  const int res = s.map.resolution_texels;
  if (res < 1) throw std::runtime_error("render: shadow-map resolution must be at least 1 texel");
  FrameInfo info;
  info.resolution_texels = res;
  info.width_px = width_px;
  info.height_px = height_px;
  const bool vsm = s.technique == Technique::vsm;
  const scene::Light& light = scene_.light;
  const float aspect = static_cast<float>(width_px) / static_cast<float>(height_px);

  // Padding of the fitted frustum by the filter's reach.
  FitRequest fit{s.map.fit, aspect, res, 0, 0};
  const float tan_half_angle = std::tan(glm::radians(std::max(light.size, 0.0f)) / 2);
  if (s.technique == Technique::pcf) {
    (s.pcf.radius_unit == RadiusUnit::texels ? fit.pad_texels : fit.pad_ws) = s.pcf.radius;
  } else if (vsm) {
    (s.vsm.radius_unit == RadiusUnit::texels ? fit.pad_texels : fit.pad_ws) = s.vsm.radius;
  } else if (s.technique == Technique::pcss || s.technique == Technique::edtssm || s.technique == Technique::erosion) {
    const scene::Aabb b = scene_.bounds();
    const float depth_range = b.empty() ? 1.0f : glm::length(b.hi - b.lo);
    const float search_scale = s.technique == Technique::pcss     ? s.pcss.search_scale
                               : s.technique == Technique::edtssm ? s.edtssm.search_scale
                                                                  : s.erosion.search_scale;
    fit.pad_ws = search_scale * (light.type == scene::Light::Type::spot ? light.size / 2 : tan_half_angle * depth_range);
    fit.pad_texels = 1;
  } else if (s.technique == Technique::edtsm) {
    fit.pad_texels = 1;
  }
  info.light = compute_light_frame(scene_, fit);
  const LightFrame& lf = info.light;
  const glm::mat4 light_vp = lf.view_projection();
  const float mid_depth = 0.5f * (lf.near_ws + lf.far_ws);
  const float texel_mid_ws = lf.texel_ws(mid_depth, res);

  // (Re)allocate the maps for this resolution and technique.
  if (!maps_ || maps_->resolution != res || maps_->moments != vsm) {
    maps_.reset();
    auto m = std::make_unique<Maps>();
    m->resolution = res;
    m->moments = vsm;
    m->depth = gl::Texture({GL_DEPTH_COMPONENT32F, res, res, 1}, "shadow depth map");
    const GLint grey[4] = {GL_RED, GL_RED, GL_RED, GL_ONE};  // debug views show depth as grey
    glTextureParameteriv(m->depth.id(), GL_TEXTURE_SWIZZLE_RGBA, grey);
    const gl::Framebuffer::Attachment depth_only[] = {{&m->depth, GL_DEPTH_ATTACHMENT}};
    m->depth_fbo = gl::Framebuffer(depth_only, "shadow depth framebuffer");
    if (vsm) {
      m->moments_tex = gl::Texture({GL_RG32F, res, res, 1}, "VSM moments");
      m->moments_tmp = gl::Texture({GL_RG32F, res, res, 1}, "VSM blur temporary");
      const gl::Framebuffer::Attachment att[] = {{&m->moments_tex, GL_COLOR_ATTACHMENT0}, {&m->depth, GL_DEPTH_ATTACHMENT}};
      m->moments_fbo = gl::Framebuffer(att, "VSM moments framebuffer");
    }
    maps_ = std::move(m);
  }
  if (!targets_ || targets_->width != width_px || targets_->height != height_px) {
    targets_.reset();
    auto t = std::make_unique<Targets>();
    t->width = width_px;
    t->height = height_px;
    t->color = gl::Texture({GL_SRGB8_ALPHA8, width_px, height_px, 1}, "lit colour");
    t->visibility = gl::Texture({GL_R32F, width_px, height_px, 1}, "visibility");
    t->depth = gl::Texture({GL_DEPTH_COMPONENT32F, width_px, height_px, 1}, "camera depth");
    const gl::Framebuffer::Attachment att[] = {{&t->color, GL_COLOR_ATTACHMENT0}, {&t->visibility, GL_COLOR_ATTACHMENT1}, {&t->depth, GL_DEPTH_ATTACHMENT}};
    t->fbo = gl::Framebuffer(att, "camera framebuffer");
    targets_ = std::move(t);
  }

  glDisable(GL_CULL_FACE);  // thin planes and open meshes cast from both sides
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDepthMask(GL_TRUE);

  // --- shadow map ----------------------------------------------------------------------------
  {
    ScopedPass pass(timer, "shadow_map", info.passes);
    const gl::Program& prog = vsm ? moments_program_ : depth_program_;
    (vsm ? maps_->moments_fbo : maps_->depth_fbo).bind();
    glViewport(0, 0, res, res);
    glEnable(GL_DEPTH_CLAMP);  // casters in front of the fitted near plane still occlude
    if (vsm) {
      const float far_moments[4] = {1, 1, 0, 0};
      glClearBufferfv(GL_COLOR, 0, far_moments);
    } else {
      glEnable(GL_POLYGON_OFFSET_FILL);
      glPolygonOffset(s.map.slope_bias, s.map.offset_bias);
    }
    const float one = 1;
    glClearBufferfv(GL_DEPTH, 0, &one);
    prog.use();
    set_mat4(prog, "u_light_view_projection", light_vp);
    set_mat4(prog, "u_light_view", lf.view);
    if (vsm) {
      set_float(prog, "u_light_near_ws", lf.near_ws);
      set_float(prog, "u_light_far_ws", lf.far_ws);
    }
    draw_scene(prog, false);
    glDisable(GL_POLYGON_OFFSET_FILL);
    glDisable(GL_DEPTH_CLAMP);
    gl::check_errors("shadow_map pass");
  }

  // --- VSM blur ------------------------------------------------------------------------------
  if (vsm) {
    const float radius_texels = s.vsm.radius_unit == RadiusUnit::texels ? s.vsm.radius : s.vsm.radius / texel_mid_ws;
    info.filter_radius_texels = radius_texels;
    ScopedPass pass(timer, "vsm_blur", info.passes);
    blur_program_.use();
    set_float(blur_program_, "u_radius_texels", radius_texels);
    const GLuint groups = static_cast<GLuint>((res + 63) / 64);
    glBindSampler(0, 0);
    set_int(blur_program_, "u_axis", 0);
    maps_->moments_tex.bind(0);
    glBindImageTexture(0, maps_->moments_tmp.id(), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RG32F);
    glDispatchCompute(groups, 1, 1);
    glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
    set_int(blur_program_, "u_axis", 1);
    maps_->moments_tmp.bind(0);
    glBindImageTexture(0, maps_->moments_tex.id(), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RG32F);
    glDispatchCompute(groups, 1, 1);
    glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
    gl::check_errors("vsm_blur pass");
  } else if (s.technique == Technique::pcf) {
    info.filter_radius_texels = s.pcf.radius_unit == RadiusUnit::texels ? s.pcf.radius : s.pcf.radius / texel_mid_ws;
  }

  // --- shading (and, for screen-space techniques, the G-buffer and post passes) --------------
  const scene::Camera& cam = scene_.camera;
  const bool light_size_used = s.technique == Technique::pcss || s.technique == Technique::edtssm || s.technique == Technique::erosion;
  // Light frame, biases and the technique's uniforms: shared by both camera passes and the
  // screen-space compute passes (uniforms a program lacks are ignored).
  auto set_shading_uniforms = [&](const gl::Program& prog) {
    set_mat4(prog, "u_view_projection", cam.projection_matrix(aspect) * cam.view());
    set_mat4(prog, "u_light_view_projection", light_vp);
    set_mat4(prog, "u_light_view", lf.view);
    set_int(prog, "u_light_perspective", lf.perspective ? 1 : 0);
    set_float(prog, "u_light_near_ws", lf.near_ws);
    set_float(prog, "u_light_far_ws", lf.far_ws);
    set_float(prog, "u_light_extent_ws", lf.extent_ws);
    set_float(prog, "u_light_s_xy", lf.s_xy);
    set_float(prog, "u_light_tan_half_fov", std::tan(glm::radians(lf.fov_deg) / 2));
    set_float(prog, "u_shadow_res", static_cast<float>(res));
    // Trust receiver slopes up to 85° from the light: |d depth/d uv| ≤ tan 85° · extent / depth range.
    set_float(prog, "u_rpdb_max", std::tan(glm::radians(85.0f)) * texel_mid_ws * static_cast<float>(res) / std::max(lf.far_ws - lf.near_ws, 1e-6f));
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

    int taps = 0;
    if (s.technique == Technique::pcf) {
      taps = s.pcf.poisson_taps;
      set_float(prog, "u_pcf_radius_texels", s.pcf.radius_unit == RadiusUnit::texels ? s.pcf.radius : 0.0f);
      set_float(prog, "u_pcf_radius_ws", s.pcf.radius_unit == RadiusUnit::world ? s.pcf.radius : -1.0f);
      set_int(prog, "u_rotate", s.pcf.rotate ? 1 : 0);
      set_int(prog, "u_max_grid_taps", s.pcf.max_grid_taps);
      set_int(prog, "u_taps", taps);
    } else if (s.technique == Technique::pcss) {
      taps = std::max(s.pcss.filter_taps, s.pcss.blocker_taps);
      set_int(prog, "u_blocker_taps", s.pcss.blocker_taps);
      set_int(prog, "u_max_grid_taps", s.pcss.max_grid_taps);
      set_float(prog, "u_pcss_search_scale", s.pcss.search_scale);
      // One disk for both steps, sized for the larger tap count; the filter step takes its own
      // count from the front (the best-candidate order spreads any prefix).
      set_int(prog, "u_taps", s.pcss.filter_taps);
    } else if (vsm) {
      set_float(prog, "u_vsm_min_variance", s.vsm.min_variance);
      set_float(prog, "u_vsm_bleed_reduction", s.vsm.bleed_reduction);
    } else if (s.technique == Technique::edtssm) {
      taps = s.edtssm.blocker_taps;
    } else if (s.technique == Technique::erosion) {
      taps = std::max(s.erosion.taps, s.erosion.blocker_taps);
      set_int(prog, "u_taps", s.erosion.taps);
      set_int(prog, "u_rotate", s.erosion.rotate ? 1 : 0);
    }
    if (light_size_used) {
      set_float(prog, "u_pcss_light_radius_uv", light.size / 2 * lf.s_xy / std::max(lf.extent_ws, 1e-9f));
      set_float(prog, "u_pcss_tan_half_angle", tan_half_angle);
      set_float(prog, "u_pcss_min_penumbra_ws", s.pcss.min_penumbra_ws);
    }
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
    if (vsm) {
      maps_->moments_tex.bind(3);
      moments_linear_.bind(3);
    }
  };

  const gl::Texture* screen_result = nullptr;
  if (is_screen_space(s.technique)) {
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
    screen_result = &screen_space_->run(s, ctx);
  }
  {
    ScopedPass pass(timer, "shading", info.passes);
    const gl::Program& prog = shading_program(s);
    targets_->fbo.bind();
    glViewport(0, 0, width_px, height_px);
    glEnable(GL_FRAMEBUFFER_SRGB);
    const float sky[4] = {0.45f, 0.55f, 0.7f, 1};
    const float lit = 1, far_depth = 1;
    glClearBufferfv(GL_COLOR, 0, sky);
    glClearBufferfv(GL_COLOR, 1, &lit);
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
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  if (timer) timer->poll(false);
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

io::ImageF Renderer::read_screen_space_input() const {
  if (!screen_space_ || !screen_space_->width()) throw std::logic_error("read_screen_space_input before a screen-space frame");
  const io::ImageF g = read_texture<float>(screen_space_->gbuffer_position(), GL_RGBA, GL_FLOAT, 4);
  io::ImageF vis{g.width, g.height, 1, std::vector<float>(static_cast<std::size_t>(g.width) * g.height)};
  for (int y = 0; y < g.height; ++y)
    for (int x = 0; x < g.width; ++x) vis.at(x, y) = g.at(x, y, 3) < 0 ? 0.0f : 1.0f;  // nothing drawn: lit
  return vis;
}

io::ImageF Renderer::read_shadow_depth() const {
  if (!maps_) throw std::logic_error("read_shadow_depth before render");
  return read_texture<float>(maps_->depth, GL_DEPTH_COMPONENT, GL_FLOAT, 1);
}

}  // namespace penumbra::shadows
