#include "shadows/renderer.h"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <utility>

#include "shaders/shadow_contract.h"
#include "shadows/passes.h"
#include "shadows/scoped_pass.h"
#include "shadows/screen_space.h"

namespace penumbra::shadows {

Renderer::Renderer() : res_(std::make_unique<FrameResources>(shaders_)), passes_(make_passes()) {}

Renderer::~Renderer() = default;

void Renderer::set_scene(const scene::Scene& s, std::uint32_t cluster_triangles) {
  scene_ = s;
  meshes_ = scene::GpuMeshes(scene_.objects, cluster_triangles);
  reset_adaptive();
  gl::check_errors("scene upload");
}

void Renderer::camera_cut() {
  if (res_->virtual_map) res_->virtual_map->late.pending = false;
}

void Renderer::reset_adaptive() {
  adaptive_.reset();
  res_->requirement.pending[0] = res_->requirement.pending[1] = false;
}

namespace {

// The PCSS requirement written by the previous frame (its GPU work is done by now on any
// pipelined GPU; reading it costs no stall) into `state`.
void read_back_requirement(FrameResources::Requirement& q, AdaptiveState& state) {
  const int other = 1 - q.frame % 2;
  if (!q.pending[other]) return;
  contract::PcssRequirementResult raw{};
  glGetNamedBufferSubData(q.buffer[other].id(), 0, sizeof raw, &raw);
  q.pending[other] = false;
  PcssRequirementInfo r;
  r.valid = true;
  double evaluated = 0, clamped = 0, above = 0;
  for (int i = 0; i < q.cascades[other]; ++i) {
    float max_inverse_uv = 0;
    std::memcpy(&max_inverse_uv, &raw.max_inverse_uv[i], sizeof max_inverse_uv);
    r.required_texels.push_back(static_cast<double>(q.c[other]) * max_inverse_uv);
    evaluated += raw.evaluated[i];
    clamped += raw.clamped[i];
    above += raw.above_max[i];
  }
  r.evaluated_pixels = evaluated;
  r.clamped_fraction = evaluated > 0 ? clamped / evaluated : 0;
  r.above_max_fraction = evaluated > 0 ? above / evaluated : 0;
  state.last = r;
  state.last_cascades = q.cascades[other];
  state.last_c = q.c[other];
}

}  // namespace

double shadow_memory_texels(const FrameInfo& info) {
  if (info.virtual_map) return static_cast<double>(info.virtual_map->resident_bytes + info.virtual_map->table_bytes) / 4;
  return static_cast<double>(info.atlas_width) * info.atlas_height;
}

FrameInfo Renderer::render(const ShadowSettings& s, int width_px, int height_px, gl::PassTimer* timer) {
  read_back_requirement(res_->requirement, adaptive_);
  const FramePlan plan = plan_frame(s, scene_, width_px, height_px, adaptive_);
  if (const std::string problem = plan_problem(plan); !problem.empty()) throw std::logic_error("frame plan: " + problem);

  FrameInfo info;
  info.width_px = width_px;
  info.height_px = height_px;
  info.adaptive = s.adaptive.enabled;
  info.cascades = plan.cascades;
  info.light = plan.light();
  info.resolution_texels = plan.cascades.front().resolution_texels;
  info.resolution_source = plan.resolution_source;
  info.pcss_requirement = plan.used_requirement;
  info.storage = plan.subrect ? "subrect" : "realloc";
  info.atlas_width = plan.atlas.width;
  info.atlas_height = plan.atlas.height;
  info.filter_radius_texels = plan.filter_radius_texels;
  info.reallocated = res_->prepare(plan);
  for (std::size_t i = 0; i < meshes_.size(); ++i) info.scene_triangles += meshes_[i].index_count() / 3;  // instances each count

  glDisable(GL_CULL_FACE);  // thin planes and open meshes cast from both sides
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDepthMask(GL_TRUE);
  FrameContext frame{s, plan, scene_, meshes_, *res_, info, timer, count_work_ ? &work_ : nullptr, show_cascades_};
  frame.upload_shadow_frame();
  for (const auto& pass : passes_) {
    if (!pass->needed(plan)) continue;
    if (pass->reports_subpasses()) {
      pass->execute(frame);  // its steps report themselves (frame.report())
    } else {
      ScopedPass scope(frame.report(), pass->name());
      pass->execute(frame);
    }
  }
  if (count_work_) info.work = work_.collect();
  last_settings_ = std::make_unique<ShadowSettings>(s);
  last_plan_ = std::make_unique<FramePlan>(plan);
  ++res_->requirement.frame;
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  if (timer) timer->poll(false);
  last_cascades_ = info.cascades;
  return info;
}

ShadowReads Renderer::count_shading_reads() {
  if (!last_plan_) throw std::logic_error("count_shading_reads: no frame rendered yet");
  FrameInfo scratch;
  FrameContext frame{*last_settings_, *last_plan_, scene_, meshes_, *res_, scratch, nullptr, nullptr, show_cascades_};
  frame.upload_shadow_frame();  // as the frame had it (a later edit of the scene's camera aside)
  return shadows::count_shading_reads(frame);
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
  if (!res_->targets) return;
  glNamedFramebufferReadBuffer(res_->targets->fbo.id(), GL_COLOR_ATTACHMENT0);
  glBlitNamedFramebuffer(res_->targets->fbo.id(), target, 0, 0, res_->targets->width, res_->targets->height, 0, 0, width_px, height_px,
                         GL_COLOR_BUFFER_BIT, GL_NEAREST);
}

GLuint Renderer::shadow_map_texture() const { return res_->maps ? res_->maps->depth.id() : 0; }
GLuint Renderer::depth_minmax_texture() const { return res_->maps ? res_->maps->depth_minmax.id() : 0; }

io::Image8 Renderer::read_color() const {
  if (!res_->targets) throw std::logic_error("read_color before render");
  return read_texture<std::uint8_t>(res_->targets->color, GL_RGBA, GL_UNSIGNED_BYTE, 4);
}

io::ImageF Renderer::read_visibility() const {
  if (!res_->targets) throw std::logic_error("read_visibility before render");
  return read_texture<float>(res_->targets->visibility, GL_RED, GL_FLOAT, 1);
}

io::ImageF Renderer::read_pcss_requirement() const {
  if (!res_->targets || !res_->targets->requirement) throw std::logic_error("read_pcss_requirement before a per-pixel PCSS frame");
  return read_texture<float>(res_->targets->requirement_tex, GL_RG, GL_FLOAT, 2);
}

io::ImageF Renderer::read_screen_space_input() const {
  if (!res_->screen_space || !res_->screen_space->width()) throw std::logic_error("read_screen_space_input before a screen-space frame");
  const io::ImageF g = read_texture<float>(res_->screen_space->gbuffer_position(), GL_RGBA, GL_FLOAT, 4);
  io::ImageF vis{g.width, g.height, 1, std::vector<float>(static_cast<std::size_t>(g.width) * g.height)};
  for (int y = 0; y < g.height; ++y)
    for (int x = 0; x < g.width; ++x) vis.at(x, y) = g.at(x, y, 3) < 0 ? 0.0f : 1.0f;  // nothing drawn: lit
  return vis;
}

io::ImageF Renderer::read_shadow_depth(int cascade) const {
  if (!res_->maps) throw std::logic_error("read_shadow_depth before render");
  if (cascade < 0 || cascade >= static_cast<int>(last_cascades_.size()))
    throw std::out_of_range("read_shadow_depth: no cascade " + std::to_string(cascade));
  const CascadeInfo& c = last_cascades_[static_cast<std::size_t>(cascade)];
  const int r = c.resolution_texels;
  io::ImageF img{r, r, 1, std::vector<float>(static_cast<std::size_t>(r) * r)};
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glGetTextureSubImage(res_->maps->depth.id(), 0, c.atlas_x, c.atlas_y, 0, r, r, 1, GL_DEPTH_COMPONENT, GL_FLOAT,
                       static_cast<GLsizei>(img.pixels.size() * sizeof(float)), img.pixels.data());
  gl::check_errors("shadow map read-back");
  flip_rows(img);
  return img;
}

}  // namespace penumbra::shadows
