#include "shadows/screen_space.h"

#include <algorithm>
#include <bit>
#include <stdexcept>

#include "gl/context.h"
#include "shadows/contract.h"
#include "shadows/scoped_pass.h"

namespace penumbra::shadows {

ScreenSpace::ScreenSpace(const gl::ShaderLibrary& shaders) : shaders_(shaders), edt_(shaders) {
  gl::SamplerDesc d;
  d.min_filter = d.mag_filter = GL_NEAREST;
  d.wrap = GL_CLAMP_TO_EDGE;
  nearest_ = gl::Sampler(d);
}
ScreenSpace::~ScreenSpace() = default;

void ScreenSpace::resize(const gl::Texture& camera_depth) {
  const int w = camera_depth.desc().width, h = camera_depth.desc().height;
  if (w == width_ && h == height_ && depth_id_ == camera_depth.id()) return;
  position_ = gl::Texture({GL_RGBA32F, w, h, 1}, "G-buffer position and signed eye depth");
  light_ = gl::Texture({GL_RGBA32F, w, h, 1}, "G-buffer shadow-map coordinates");
  const gl::Framebuffer::Attachment att[] = {{&position_, GL_COLOR_ATTACHMENT0},
                                             {&light_, GL_COLOR_ATTACHMENT1},
                                             {&camera_depth, GL_DEPTH_ATTACHMENT}};
  gbuffer_fbo_ = gl::Framebuffer(att, "G-buffer framebuffer");
  sites_ = gl::Texture({GL_R8UI, w, h, 1}, "screen-space sites");
  site_width_ = gl::Texture({GL_R32F, w, h, 1}, "screen-space site penumbra width");
  scratch_[0] = gl::Texture({GL_RG32F, w, h, 1}, "screen-space scratch 0");
  scratch_[1] = gl::Texture({GL_RG32F, w, h, 1}, "screen-space scratch 1");
  filtered_ = gl::Texture({GL_RG32F, w, h, 1}, "screen-space filtered visibility");
  edges_ = gl::Texture();
  width_ = w;
  height_ = h;
  depth_id_ = camera_depth.id();
}

gl::Texture& ScreenSpace::edges_mip() {
  if (!edges_.id()) {
    const int levels = std::bit_width(static_cast<unsigned>(std::max(width_, height_)));
    edges_ = gl::Texture({GL_RG32F, width_, height_, levels}, "erosion min-max mip-map");
  }
  return edges_;
}

const gl::Program& ScreenSpace::program(const std::string& file, const std::vector<gl::ShaderDefine>& defines) {
  std::string key = file;
  for (const auto& d : defines) key += ";" + d.name + "=" + d.value;
  auto it = programs_.find(key);
  if (it == programs_.end()) {
    gl::Program p = shaders_.program({{GL_COMPUTE_SHADER, file}}, defines);
    check_shadow_frame_block(p, key);
    it = programs_.emplace(key, std::move(p)).first;
  }
  return it->second;
}

void ScreenSpace::bind_gbuffer(const gl::Program& p, const ScreenView& view, float depth_threshold) const {
  // Integer textures with the default (linear, mip-mapped) filter are incomplete even for
  // texelFetch: every post-pass input is read through a nearest sampler.
  for (GLuint unit = contract::UNIT_GBUFFER_POSITION; unit <= contract::UNIT_POST_INPUT_2; ++unit) nearest_.bind(unit);
  position_.bind(contract::UNIT_GBUFFER_POSITION);
  light_.bind(contract::UNIT_GBUFFER_LIGHT);
  glProgramUniform1i(p.id(), p.location("u_camera_perspective"), view.perspective ? 1 : 0);
  glProgramUniform1f(p.id(), p.location("u_px_scale"), view.px_scale);
  glProgramUniform1f(p.id(), p.location("u_depth_threshold"), depth_threshold);
}

void ScreenSpace::detect_sites(const SiteSearch& search, float depth_threshold, const PostPassContext& ctx) {
  ScopedPass pass(ctx.report, search.laplacian ? "edges" : "sites");
  std::vector<gl::ShaderDefine> defines;
  if (search.laplacian) defines.push_back({"LAPLACIAN", "1"});
  if (search.blocker_search) defines.push_back({"BLOCKER_SEARCH", "1"});
  const gl::Program& p = program("ss_sites.comp", defines);
  p.use();
  ctx.set_technique_uniforms(p);
  bind_gbuffer(p, ctx.view, depth_threshold);
  glProgramUniform1i(p.id(), p.location("u_blocker_taps"), search.blocker_taps);
  glProgramUniform1f(p.id(), p.location("u_pcss_search_scale"), search.search_scale);
  glBindImageTexture(p.binding("u_sites"), sites_.id(), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_R8UI);
  glBindImageTexture(p.binding("u_site_width"), site_width_.id(), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_R32F);
  p.dispatch_covering(width_, height_);
  glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT);
  gl::check_errors("screen-space sites");
}

const gl::Texture& ScreenSpace::edt_penumbra(bool propagated_width, bool edge_between_pixels, float depth_threshold,
                                             const std::function<void(const gl::Program&)>& set_uniforms,
                                             const PostPassContext& ctx) {
  {
    ScopedPass pass(ctx.report, "edt");
    edt_.compute(sites_);
  }
  ScopedPass pass(ctx.report, "edt_penumbra");
  std::vector<gl::ShaderDefine> defines;
  if (propagated_width) defines.push_back({"PROPAGATED_WIDTH", "1"});
  const gl::Program& p = program("edt_penumbra.comp", defines);
  p.use();
  bind_gbuffer(p, ctx.view, depth_threshold);
  edt_.nearest().bind(contract::UNIT_POST_INPUT);
  if (propagated_width) site_width_.bind(contract::UNIT_POST_INPUT_2);
  p.set("u_edge_between_pixels", edge_between_pixels);
  set_uniforms(p);
  glBindImageTexture(p.binding("u_penumbra"), scratch_[0].id(), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RG32F);
  p.dispatch_covering(width_, height_);
  glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT);
  gl::check_errors("edt_penumbra pass");
  return scratch_[0];
}

const gl::Texture& ScreenSpace::mean_filter(const gl::Texture& source, float filter_ws, int max_width_px,
                                            float depth_threshold, const PostPassContext& ctx) {
  ScopedPass pass(ctx.report, "mean_filter");
  const gl::Program& p = program("ss_mean_filter.comp");
  p.use();
  bind_gbuffer(p, ctx.view, depth_threshold);
  glProgramUniform1f(p.id(), p.location("u_filter_ws"), filter_ws);
  glProgramUniform1f(p.id(), p.location("u_max_width_px"), static_cast<float>(max_width_px));
  // Ping-pong through a scratch image that is not `source`.
  gl::Texture& tmp = &source == &scratch_[0] ? scratch_[1] : scratch_[0];
  const gl::Texture* in[2] = {&source, &tmp};
  const gl::Texture* out[2] = {&tmp, &filtered_};
  for (int axis = 0; axis < 2; ++axis) {
    glProgramUniform1i(p.id(), p.location("u_axis"), axis);
    in[axis]->bind(contract::UNIT_POST_INPUT);
    glBindImageTexture(p.binding("u_target"), out[axis]->id(), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RG32F);
    p.dispatch_covering(width_, height_);
    glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT);
  }
  gl::check_errors("screen-space mean filter");
  return filtered_;
}

}  // namespace penumbra::shadows
