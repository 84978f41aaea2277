#include "shadows/virtual_shadow_map.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>

#include <glm/gtc/matrix_transform.hpp>

#include "gl/shader_library.h"
#include "scene/culling.h"
#include "shadows/contract.h"
#include "shadows/fitting.h"
#include "shaders/shadow_contract.h"
#include "shadows/scoped_pass.h"

namespace penumbra::shadows {

static_assert(contract::BLOCK_VIRTUAL_FRAME == virtual_mark::VIRTUAL_FRAME_BLOCK && contract::BLOCK_VIRTUAL_FRAME != contract::BLOCK_SHADOW_FRAME,
              "the VirtualFrame block's binding: shadow_contract.h and virtual_mark_contract.h");
static_assert(contract::VIRTUAL_MAX_LEVELS == virtual_mark::VIRTUAL_MARK_MAX_LEVELS, "the block's origins: one per level");
static_assert(adaptive::kTilesPerSide == virtual_mark::VIRTUAL_MARK_TILES_PER_SIDE, "a tile mask is the marking's");

glm::mat4 sun_light_view(const glm::vec3& direction) {
  const glm::vec3 d = glm::normalize(direction);
  glm::vec3 e1, e2;
  scene::light_basis(d, e1, e2);  // the references' basis
  glm::mat4 v(1);  // rows e1, e2, -d (column-major: element [column][row])
  for (int c = 0; c < 3; ++c) v[c][0] = e1[c], v[c][1] = e2[c], v[c][2] = -d[c];
  return v;
}

adaptive::LightXY light_xy(const glm::mat4& light_view, const glm::vec3& p) {
  const glm::vec4 l = light_view * glm::vec4(p, 1.0f);
  return {l.x, l.y};
}

void light_depth_range(const glm::mat4& light_view, const scene::Aabb& bounds, float& near_ws, float& far_ws) {
  if (bounds.empty()) {
    near_ws = 0, far_ws = 1;
    return;
  }
  const scene::Aabb l = bounds.transformed(light_view);
  const float margin = std::max(0.01f, 0.01f * (l.hi.z - l.lo.z));
  near_ws = -l.hi.z - margin;  // distances along -z
  far_ws = -l.lo.z + margin;
}

VirtualMapView sun_virtual_view(const scene::Scene& scene, float camera_aspect, const VirtualMapView* previous) {
  VirtualMapView view;
  view.light_view = sun_light_view(scene.light.direction);
  // Rows x, y, -d of the light view: the region's depth (its z) is d · p, the distance along -z.
  const SunRegion region = sun_shadow_region(scene, camera_aspect, glm::dmat3(glm::dmat4(view.light_view)));
  const double depth = region.hi.z - region.lo.z;
  const double margin = std::max(0.01, 0.01 * depth);
  // Compared as the floats the view holds: the range taken last frame must hold this one exactly.
  const auto near_ws = static_cast<float>(region.lo.z - margin), far_ws = static_cast<float>(region.hi.z + margin);
  if (previous && previous->light_view == view.light_view && previous->near_ws <= near_ws && previous->far_ws >= far_ws &&
      previous->far_ws - previous->near_ws <= 4 * (far_ws - near_ws)) {
    view.near_ws = previous->near_ws, view.far_ws = previous->far_ws;
  } else {
    const double spare = previous ? 0.25 * depth : 0.0;
    view.near_ws = static_cast<float>(region.lo.z - margin - spare);
    view.far_ws = static_cast<float>(region.hi.z + margin + spare);
  }
  if (!(std::isfinite(view.near_ws) && std::isfinite(view.far_ws) && view.far_ws > view.near_ws))
    throw std::runtime_error("virtual shadow map: the light's depth range is not finite (near " + std::to_string(view.near_ws) + ", far " +
                             std::to_string(view.far_ws) + ")");
  view.camera_xy = light_xy(view.light_view, scene.camera.position);
  view.region_lo = {region.lo.x, region.lo.y};
  view.region_hi = {region.hi.x, region.hi.y};
  return view;
}

namespace {

const adaptive::VirtualMapLayout& checked_layout(const adaptive::VirtualMapLayout& layout, int pool_pages_per_side) {
  if (layout.levels < 1 || layout.levels > contract::VIRTUAL_MAX_LEVELS || layout.page_texels < 1 || layout.pages_per_side < 1 ||
      !(layout.texel0_ws > 0) || pool_pages_per_side < 1)
    throw std::invalid_argument("virtual shadow map: levels must be 1.." + std::to_string(contract::VIRTUAL_MAX_LEVELS) +
                                ", page_texels, pages_per_side, texel0_ws and the pool's pages per side positive");
  return layout;
}

}  // namespace

VirtualShadowMap::VirtualShadowMap(const adaptive::VirtualMapLayout& layout, int pool_pages_per_side, Content content)
    : layout_(checked_layout(layout, pool_pages_per_side)),
      pool_side_(pool_pages_per_side),
      content_(content),
      cache_(layout, pool_pages_per_side * pool_pages_per_side) {
  set_virtual_view(frame_, layout, view_);
  frame_.u_virtual_pool_pages = pool_side_;
  const int side = pool_side_ * layout.page_texels;
  pool_ = gl::Texture({GL_DEPTH_COMPONENT32F, side, side, 1}, "virtual shadow map page pool");
  glTextureParameteri(pool_.id(), GL_TEXTURE_MIN_FILTER, GL_NEAREST);  // complete with one level: textureGather reads it
  glTextureParameteri(pool_.id(), GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  gl::SamplerDesc compare;
  compare.min_filter = compare.mag_filter = GL_NEAREST;
  compare.depth_compare = true;
  compare_ = gl::Sampler(compare);
  table_ = gl::Texture({GL_R32I, layout.pages_per_side, layout.pages_per_side * layout.levels, 1}, "virtual shadow map page tables");
  glTextureParameteri(table_.id(), GL_TEXTURE_MIN_FILTER, GL_NEAREST);  // an integer texture is complete only so
  glTextureParameteri(table_.id(), GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  std::vector<gl::Framebuffer::Attachment> attachments = {{&pool_, GL_DEPTH_ATTACHMENT}};
  if (content == Content::depth_and_moments) {
    moments_ = gl::Texture({GL_RG32F, side, side, 1}, "virtual shadow map moments pool");
    glTextureParameteri(moments_.id(), GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTextureParameteri(moments_.id(), GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    attachments.push_back({&moments_, GL_COLOR_ATTACHMENT0});
  }
  fbo_ = gl::Framebuffer(attachments, "virtual shadow map page pool");
  program_ = gl::ShaderLibrary().program(
      {{GL_VERTEX_SHADER, "virtual_page.vert"},
       {GL_FRAGMENT_SHADER, content == Content::depth_and_moments ? "virtual_page_moments.frag" : "shadow_depth.frag"}});
  if (content == Content::depth && layout.page_texels % contract::VIRTUAL_BOUNDS_TILE == 0) {
    const int tiles = side / contract::VIRTUAL_BOUNDS_TILE;
    bounds_pool_ = gl::Texture({GL_RGBA32F, tiles, tiles, 1}, "virtual shadow map tile bounds");
    glTextureParameteri(bounds_pool_.id(), GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTextureParameteri(bounds_pool_.id(), GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    bounds_program_ = gl::ShaderLibrary().program({{GL_COMPUTE_SHADER, "virtual_bounds.comp"}});
    check_virtual_frame_block(bounds_program_, "virtual_bounds.comp");
    bounds_slots_ = gl::Buffer(static_cast<std::size_t>(pool_slots()) * sizeof(std::int32_t), nullptr, GL_DYNAMIC_STORAGE_BIT);
    bounds_ = true;
  }
  frame_.u_virtual_bounds = bounds_;
  write_tables();
}

void VirtualShadowMap::set_raster_bias(float slope, float offset) {
  if (slope == slope_bias_ && offset == offset_bias_) return;
  slope_bias_ = slope, offset_bias_ = offset;
  invalidate_all();  // pages drawn with the old offsets would disagree with new ones
}

void VirtualShadowMap::set_bounds(bool on) {
  const bool now = on && bounds_pool_.id() != 0;
  if (now == bounds_) return;
  bounds_ = now;
  frame_.u_virtual_bounds = bounds_;
  if (now) invalidate_all();  // the pages drawn without bounds have none
}

std::uint64_t VirtualShadowMap::page_bytes() const {
  const auto texels = static_cast<std::uint64_t>(layout_.page_texels) * static_cast<std::uint64_t>(layout_.page_texels);
  const std::uint64_t tiles = texels / (contract::VIRTUAL_BOUNDS_TILE * contract::VIRTUAL_BOUNDS_TILE);
  return texels * (content_ == Content::depth_and_moments ? 4 + 8 : 4) + (bounds_ ? tiles * 16 : 0);
}

void VirtualShadowMap::write_bounds(const std::vector<int>& slots) {
  if (slots.empty()) return;
  glNamedBufferSubData(bounds_slots_.id(), 0, static_cast<GLsizeiptr>(slots.size() * sizeof(int)), slots.data());
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, contract::BUFFER_VIRTUAL_BOUNDS_SLOTS, bounds_slots_.id());
  pool_.bind(contract::UNIT_VIRTUAL_POOL);
  glBindSampler(contract::UNIT_VIRTUAL_POOL, 0);
  glBindImageTexture(contract::IMAGE_VIRTUAL_BOUNDS, bounds_pool_.id(), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
  frame_buffer_.bind(frame_);  // the pool's layout
  bounds_program_.use();
  const int groups = (layout_.page_texels / contract::VIRTUAL_BOUNDS_TILE + contract::VIRTUAL_BOUNDS_GROUP - 1) / contract::VIRTUAL_BOUNDS_GROUP;
  glDispatchCompute(static_cast<GLuint>(groups), static_cast<GLuint>(groups), static_cast<GLuint>(slots.size()));
  glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT);
}

void VirtualShadowMap::invalidate_all() { cache_.invalidate_all(); }

void VirtualShadowMap::invalidate(const scene::Aabb& bounds) {
  if (bounds.empty() || !has_view_) return;
  const scene::Aabb l = bounds.transformed(view_.light_view);
  cache_.invalidate({l.lo.x, l.lo.y}, {l.hi.x, l.hi.y});
}

scene::Aabb VirtualShadowMap::invalidate_moved_casters(const scene::Scene& scene) {
  const std::vector<scene::Object>& objects = scene.objects;
  const bool same_objects = casters_.size() == objects.size();
  if (!same_objects && !casters_.empty()) invalidate_all();
  std::vector<Caster> now;
  scene::Aabb all;
  for (std::size_t i = 0; i < objects.size(); ++i) {
    const scene::Object& o = objects[i];
    const bool kept = same_objects && casters_[i].mesh == o.mesh.get() && casters_[i].model == o.model;
    now.push_back({o.mesh.get(), o.model, kept ? casters_[i].bounds : o.mesh->bounds().transformed(o.model)});
    if (same_objects && !kept) {
      invalidate(casters_[i].bounds);
      invalidate(now.back().bounds);
    }
    all.extend(now.back().bounds);
  }
  casters_ = std::move(now);
  return all;
}

void VirtualShadowMap::clear_slots(const std::vector<adaptive::PageCache::Admitted>& to_draw) const {
  // Every slot before any page is drawn, as texture clears rather than a scissored framebuffer
  // clear between the pages' draws (on llvmpipe a scissored clear is a quad through the pipeline).
  const int n = layout_.page_texels;
  const float far_depth = 1.0f;
  const float far_moments[2] = {1, 1};  // the far plane, t = 1: nothing in front
  for (const adaptive::PageCache::Admitted& a : to_draw) {
    const int sx = a.slot % pool_side_, sy = a.slot / pool_side_;
    glClearTexSubImage(pool_.id(), 0, sx * n, sy * n, 0, n, n, 1, GL_DEPTH_COMPONENT, GL_FLOAT, &far_depth);
    if (content_ == Content::depth_and_moments)
      glClearTexSubImage(moments_.id(), 0, sx * n, sy * n, 0, n, n, 1, GL_RG, GL_FLOAT, far_moments);
  }
}

void VirtualShadowMap::draw_page(int slot, const adaptive::PageKey& key, adaptive::TileMask tiles, const scene::Scene& scene,
                                 const scene::GpuMeshes& meshes,
                                 const std::vector<scene::ClusterFootprints>& footprints, VirtualMapStats& stats) const {
  const int n = layout_.page_texels;
  const int sx = slot % pool_side_, sy = slot / pool_side_;
  glViewport(sx * n, sy * n, n, n);
  const double w = cache_.page_ws(key.level);
  const auto x0 = static_cast<float>(static_cast<double>(key.x) * w), y0 = static_cast<float>(static_cast<double>(key.y) * w);
  const auto wf = static_cast<float>(w);
  program_.set("u_clip_from_world", glm::ortho(x0, x0 + wf, y0, y0 + wf, view_.near_ws, view_.far_ws) * view_.light_view);
  // The texels of the page's tiles to draw (the whole page unless the marking said which; they hold
  // the squares the shading reads, its normal offset included), a texel wider for the marking's and
  // the shading's float arithmetic; the casters kept over them a texel wider still: the raster's
  // float matrix may reach a texel into a caster the exact rectangle just misses.
  const adaptive::TexelRect r = adaptive::tiles_rect(tiles, n, 1);
  glScissor(sx * n + r.x0, sy * n + r.y0, r.x1 - r.x0, r.y1 - r.y0);
  const float texel = wf / static_cast<float>(n);
  const scene::Footprint window{{x0 + static_cast<float>(r.x0 - 1) * texel, y0 + static_cast<float>(r.y0 - 1) * texel},
                                {x0 + static_cast<float>(r.x1 + 1) * texel, y0 + static_cast<float>(r.y1 + 1) * texel}};
  for (std::size_t i = 0; i < meshes.size(); ++i) {
    const scene::DrawRanges kept = scene::cull_clusters(meshes[i].clustered(), footprints[i], window);
    if (kept.first_index.empty()) continue;
    program_.set("u_model", scene.objects[i].model);
    meshes[i].draw(kept);
    stats.triangles += kept.triangles;
    stats.draws += kept.first_index.size();
  }
}

VirtualMapStats VirtualShadowMap::update(const std::set<adaptive::Page>& requested, const VirtualMapView& view, const scene::Scene& scene,
                                         const scene::GpuMeshes& meshes, const StepReport* steps, const adaptive::PageTiles* tiles) {
  if (meshes.size() != scene.objects.size()) throw std::invalid_argument("virtual shadow map: the meshes are not the scene's");
  for (const adaptive::Page& page : requested)  // before anything changes (the cache checks too, after a new view)
    if (page.level < 0 || page.level >= layout_.levels || page.x < 0 || page.y < 0 || page.x >= layout_.pages_per_side ||
        page.y >= layout_.pages_per_side)
      throw std::invalid_argument("virtual shadow map: page outside the layout (level " + std::to_string(page.level) + ", " +
                                  std::to_string(page.x) + ", " + std::to_string(page.y) + ")");
  std::optional<ScopedPass> scope;
  const auto step = [&](const char* name) {
    scope.reset();
    if (steps) scope.emplace(steps->report, name + steps->suffix);
  };

  step("virtual_admit");
  if (has_view_ && (view.light_view != view_.light_view || view.near_ws != view_.near_ws || view.far_ws != view_.far_ws)) invalidate_all();
  view_ = view;
  has_view_ = true;
  set_virtual_view(frame_, layout_, view_);
  const adaptive::PageCache::Update admitted = cache_.update(requested, view.camera_xy, tiles);
  VirtualMapStats stats;
  static_cast<adaptive::PageCacheStats&>(stats) = admitted.stats;
  const std::vector<adaptive::PageCache::Admitted>& to_draw = admitted.to_draw;

  step("virtual_draw");
  if (!to_draw.empty()) {
    fbo_.bind();
    program_.use();
    glEnable(GL_SCISSOR_TEST);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDepthMask(GL_TRUE);
    glDisable(GL_CULL_FACE);  // thin planes and open meshes cast from both sides
    glEnable(GL_DEPTH_CLAMP);  // casters nearer the sun than the depth range still occlude (as on the maps)
    glClearDepth(1.0);
    if (slope_bias_ != 0 || offset_bias_ != 0) {
      glEnable(GL_POLYGON_OFFSET_FILL);
      glPolygonOffset(slope_bias_, offset_bias_);
    }
    // Each cluster's footprint across the light once; each page then keeps the clusters over its
    // square (a unit over a page would send all its triangles, the clusters far from it too).
    std::vector<scene::ClusterFootprints> footprints;
    for (std::size_t i = 0; i < meshes.size(); ++i)
      footprints.push_back(scene::cluster_footprints(meshes[i].clustered(), view_.light_view * scene.objects[i].model));
    clear_slots(to_draw);
    for (const adaptive::PageCache::Admitted& a : to_draw) draw_page(a.slot, a.key, a.tiles, scene, meshes, footprints, stats);
    glDisable(GL_POLYGON_OFFSET_FILL);
    glDisable(GL_DEPTH_CLAMP);
    glDisable(GL_SCISSOR_TEST);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
  }
  if (bounds_) {
    step("virtual_bounds");
    if (!to_draw.empty()) {
      std::vector<int> drawn;
      for (const adaptive::PageCache::Admitted& a : to_draw) drawn.push_back(a.slot);
      write_bounds(drawn);
    }
  }
  step("virtual_table");
  write_tables();
  return stats;
}

void VirtualShadowMap::write_tables() {
  const std::vector<std::int32_t> table = cache_.table();
  glTextureSubImage2D(table_.id(), 0, 0, 0, layout_.pages_per_side, layout_.pages_per_side * layout_.levels, GL_RED_INTEGER, GL_INT, table.data());
}

std::string missing_pages_warning(const VirtualMapStats& stats, int pool_pages_per_side) {
  if (stats.missing <= 0) return "";
  const int slots = pool_pages_per_side * pool_pages_per_side;
  const auto side = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(stats.requested))));
  return "warning: virtual shadow map: " + std::to_string(stats.missing) + " of the " + std::to_string(stats.requested) +
         " pages the frame asked for did not fit a pool of " + std::to_string(slots) + (slots == 1 ? " slot" : " slots") +
         " (--map.virtual_pool_pages " + std::to_string(pool_pages_per_side) + "); their pixels read level " +
         std::to_string(stats.floor_level) + " or coarser instead of their own; --map.virtual_pool_pages " + std::to_string(side) +
         " holds them all";
}

namespace {

virtual_mark::vec3 block_vec3(const glm::vec3& v) { return {v.x, v.y, v.z}; }

}  // namespace

void set_virtual_view(VirtualFrame& frame, const adaptive::VirtualMapLayout& layout, const VirtualMapView& view) {
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) frame.u_virtual_light_view.columns[c][r] = view.light_view[c][r];  // column-major, as glm
  for (int k = 0; k < virtual_mark::VIRTUAL_MARK_MAX_LEVELS; ++k) {
    const adaptive::LightXY o = k < layout.levels ? adaptive::level_origin(k, view.camera_xy, layout) : adaptive::LightXY{};
    frame.u_virtual_origin[k] = {static_cast<float>(o.x), static_cast<float>(o.y), 0, 0};
  }
  frame.u_virtual_texel0_ws = static_cast<float>(layout.texel0_ws);
  frame.u_virtual_page_texels = layout.page_texels;
  frame.u_virtual_pages_per_side = layout.pages_per_side;
  frame.u_virtual_levels = layout.levels;
  frame.u_virtual_near_ws = view.near_ws;
  frame.u_virtual_far_ws = view.far_ws;
}

VirtualFrameBuffer::VirtualFrameBuffer() : buffer_(sizeof(VirtualFrame), nullptr, GL_DYNAMIC_STORAGE_BIT) {}

void VirtualFrameBuffer::bind(const VirtualFrame& frame) const {
  if (!holds_ || std::memcmp(&held_, &frame, sizeof frame) != 0) {  // std140 as laid out: no padding to differ in
    glNamedBufferSubData(buffer_.id(), 0, sizeof frame, &frame);
    held_ = frame;
    holds_ = true;
    ++writes_;
  }
  glBindBufferBase(GL_UNIFORM_BUFFER, contract::BLOCK_VIRTUAL_FRAME, buffer_.id());
}

adaptive::MarkOptions virtual_mark_options(const ShadowSettings& s) {
  adaptive::MarkOptions o;
  o.marking = s.map.virtual_pages == VirtualPages::footprint ? adaptive::Marking::footprint : adaptive::Marking::rule;
  o.c_texels = s.adaptive.c;
  o.min_texel_px = s.map.virtual_min_texel_px;
  o.reach_texels = s.map.normal_offset_texels;
  return o;
}

void set_virtual_marking(VirtualFrame& frame, const scene::Camera& camera, int height_px, const adaptive::MarkOptions& options) {
  const bool perspective = camera.projection == scene::Camera::Projection::perspective;
  frame.u_mark_camera_position = block_vec3(camera.position);
  frame.u_mark_camera_forward = block_vec3(glm::normalize(camera.target - camera.position));
  frame.u_mark_perspective = perspective;
  frame.u_mark_footprint_per_depth = perspective ? 2 * std::tan(glm::radians(camera.fov_y_deg) / 2) / static_cast<float>(height_px)
                                                 : camera.ortho_height_ws / static_cast<float>(height_px);
  frame.u_mark_c_texels = static_cast<float>(options.c_texels);
  frame.u_mark_min_texel_px = static_cast<float>(options.min_texel_px);
  frame.u_mark_reach_texels = static_cast<float>(options.reach_texels);
  frame.u_mark_footprint_only = options.marking == adaptive::Marking::footprint;
}

void set_virtual_pcss(VirtualFrame& frame, const VirtualPcss& pcss) {
  frame.u_virtual_tan_half_angle = pcss.tan_half_angle;
  frame.u_virtual_search_scale = pcss.search_scale;
  frame.u_virtual_min_penumbra_ws = pcss.min_penumbra_ws;
  frame.u_virtual_search_bias_texels = pcss.search_bias_texels;
  frame.u_virtual_search_receiver_plane = pcss.receiver_plane;
}

VirtualPcss virtual_pcss(const ShadowSettings& s, float light_size_deg) {
  const bool plane = s.map.receiver_plane_bias;
  return {std::tan(glm::radians(std::max(light_size_deg, 0.0f)) / 2), s.pcss.search_scale, s.pcss.min_penumbra_ws,
          plane ? s.map.depth_bias_texels : 2.0f, plane};
}

void VirtualShadowMap::bind() const {
  pool_.bind(contract::UNIT_VIRTUAL_POOL);
  glBindSampler(contract::UNIT_VIRTUAL_POOL, 0);  // texelFetch: no sampler state needed
  table_.bind(contract::UNIT_VIRTUAL_TABLE);
  glBindSampler(contract::UNIT_VIRTUAL_TABLE, 0);
  pool_.bind(contract::UNIT_VIRTUAL_POOL_CMP);
  compare_.bind(contract::UNIT_VIRTUAL_POOL_CMP);
  if (content_ == Content::depth_and_moments) {
    moments_.bind(contract::UNIT_VIRTUAL_MOMENTS);
    glBindSampler(contract::UNIT_VIRTUAL_MOMENTS, 0);
  }
  if (bounds_) {
    bounds_pool_.bind(contract::UNIT_VIRTUAL_BOUNDS);
    glBindSampler(contract::UNIT_VIRTUAL_BOUNDS, 0);
  }
  frame_buffer_.bind(frame_);
}

PageMarker::PageMarker(const adaptive::VirtualMapLayout& layout) : layout_(layout) {
  if (layout.levels < 1 || layout.levels > contract::VIRTUAL_MAX_LEVELS || layout.page_texels < 1 || layout.pages_per_side < 1 ||
      !(layout.texel0_ws > 0))
    throw std::invalid_argument("page marker: levels must be 1.." + std::to_string(contract::VIRTUAL_MAX_LEVELS) +
                                ", page_texels, pages_per_side and texel0_ws positive");
  const gl::ShaderLibrary shaders;
  for (int pass = 0; pass < 3; ++pass) {
    programs_[pass] = shaders.program({{GL_COMPUTE_SHADER, "virtual_mark.comp"}}, {{"VIRTUAL_MARK_PASS", std::to_string(pass)}});
    check_virtual_frame_block(programs_[pass], "virtual_mark.comp");
  }
  words_ = virtual_mark::virtual_mark_buffer_words(layout.levels, layout.pages_per_side);
  marks_ = make_marks();
}

adaptive::MarkResult PageMarker::mark(const gl::Texture& surface, const scene::Camera& camera, int height_px, const VirtualMapView& view,
                                      double radius_ws, const adaptive::MarkOptions& options, const gl::Texture* levels) const {
  dispatch(surface, camera, height_px, view, radius_ws, options, marks_, levels);
  return read(marks_);
}

adaptive::MarkResult PageMarker::mark_pcss_search(const gl::Texture& surface, const scene::Camera& camera, int height_px,
                                                  const VirtualMapView& view, const VirtualPcss& pcss, const adaptive::MarkOptions& options) const {
  dispatch_pcss_search(surface, camera, height_px, view, pcss, options, marks_);
  return read(marks_);
}

adaptive::MarkResult PageMarker::mark_pcss_filter(const gl::Texture& surface, const scene::Camera& camera, int height_px,
                                                  const VirtualShadowMap& map, const VirtualPcss& pcss, const adaptive::MarkOptions& options,
                                                  const gl::Texture* levels, const gl::Texture* radii) const {
  dispatch_pcss_filter(surface, camera, height_px, map, pcss, options, radii, marks_, levels);
  return read(marks_);
}

gl::Buffer PageMarker::make_marks() const {
  return gl::Buffer(words_ * sizeof(std::uint32_t), nullptr, GL_DYNAMIC_STORAGE_BIT);
}

void PageMarker::dispatch(const gl::Texture& surface, const scene::Camera& camera, int height_px, const VirtualMapView& view,
                          double radius_ws, const adaptive::MarkOptions& options, const gl::Buffer& marks, const gl::Texture* levels) const {
  VirtualFrame frame{};
  set_virtual_view(frame, layout_, view);
  run(Pass::filter, surface, camera, height_px, frame, radius_ws, options, levels, nullptr, marks);
}

void PageMarker::dispatch_pcss_search(const gl::Texture& surface, const scene::Camera& camera, int height_px, const VirtualMapView& view,
                                      const VirtualPcss& pcss, const adaptive::MarkOptions& options, const gl::Buffer& marks) const {
  VirtualFrame frame{};
  set_virtual_view(frame, layout_, view);
  set_virtual_pcss(frame, pcss);
  run(Pass::pcss_search, surface, camera, height_px, frame, 0, options, nullptr, nullptr, marks);
}

void PageMarker::dispatch_pcss_filter(const gl::Texture& surface, const scene::Camera& camera, int height_px, const VirtualShadowMap& map,
                                      const VirtualPcss& pcss, const adaptive::MarkOptions& options, const gl::Texture* radii,
                                      const gl::Buffer& marks, const gl::Texture* levels) const {
  map.bind();  // the search reads the pages resident now
  VirtualFrame frame = map.frame();  // its pool, bounds and view
  set_virtual_pcss(frame, pcss);
  run(Pass::pcss_penumbra, surface, camera, height_px, frame, 0, options, levels, radii, marks);
}

void PageMarker::count_pcss_search_reads(const gl::Texture& surface, const scene::Camera& camera, int height_px, const VirtualShadowMap& map,
                                         const VirtualPcss& pcss, const adaptive::MarkOptions& options) const {
  if (!count_program_.id()) {
    count_program_ = gl::ShaderLibrary().program({{GL_COMPUTE_SHADER, "virtual_mark.comp"}},
                                                 {{"VIRTUAL_MARK_PASS", std::to_string(static_cast<int>(Pass::pcss_penumbra))},
                                                  {"COUNT_SHADOW_READS", "1"}});
    check_virtual_frame_block(count_program_, "virtual_mark.comp (counting)");
  }
  map.bind();
  VirtualFrame frame = map.frame();
  set_virtual_pcss(frame, pcss);
  run(Pass::pcss_penumbra, surface, camera, height_px, frame, 0, options, nullptr, nullptr, marks_, &count_program_);
  glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
}

void PageMarker::run(Pass pass, const gl::Texture& surface, const scene::Camera& camera, int height_px, VirtualFrame frame,
                     double radius_ws, const adaptive::MarkOptions& options, const gl::Texture* levels, const gl::Texture* radii,
                     const gl::Buffer& marks, const gl::Program* counting) const {
  const gl::Program& prog = counting ? *counting : program(pass);
  if (height_px < 1) throw std::invalid_argument("page marker: the image needs at least one row");
  const auto same_size_r32f = [&](const gl::Texture* t) {
    return !t || (t->desc().width == surface.desc().width && t->desc().height == surface.desc().height && t->desc().format == GL_R32F);
  };
  if (!same_size_r32f(levels)) throw std::invalid_argument("page marker: the levels image must be R32F of the surface's size");
  if (!same_size_r32f(radii)) throw std::invalid_argument("page marker: the radii image must be R32F of the surface's size");
  prog.set("u_write_levels", levels != nullptr);
  if (levels) glBindImageTexture(virtual_mark::VIRTUAL_MARK_IMAGE_LEVELS, levels->id(), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_R32F);
  prog.set("u_write_radii", radii != nullptr);
  if (radii) glBindImageTexture(virtual_mark::VIRTUAL_MARK_IMAGE_RADII, radii->id(), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_R32F);
  set_virtual_marking(frame, camera, height_px, options);
  frame_buffer_.bind(frame);
  prog.set("u_radius_ws", static_cast<float>(radius_ws));
  const std::uint32_t zero = 0;
  glClearNamedBufferData(marks.id(), GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, virtual_mark::VIRTUAL_MARK_BUFFER, marks.id());
  glBindImageTexture(virtual_mark::VIRTUAL_MARK_IMAGE_SURFACE, surface.id(), 0, GL_FALSE, 0, GL_READ_ONLY, GL_RGBA32F);
  prog.dispatch_covering(surface.desc().width, surface.desc().height);
  glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT | GL_TEXTURE_UPDATE_BARRIER_BIT);
}

adaptive::MarkResult PageMarker::read(const gl::Buffer& marks) const {
  namespace vm = virtual_mark;
  std::vector<std::uint32_t> m(words_);
  glGetNamedBufferSubData(marks.id(), 0, static_cast<GLsizeiptr>(m.size() * sizeof(std::uint32_t)), m.data());
  adaptive::MarkResult out;
  for (int k = 0; k < layout_.levels; ++k) out.pixels_per_level.push_back(m[static_cast<std::size_t>(vm::VIRTUAL_MARK_WORD_PIXELS_PER_LEVEL + k)]);
  out.unmarked = m[vm::VIRTUAL_MARK_WORD_UNMARKED];
  const std::size_t page_bits_end = vm::VIRTUAL_MARK_WORD_PAGE_BITS + vm::virtual_mark_page_bit_words(layout_.levels, layout_.pages_per_side);
  for (std::size_t w = vm::VIRTUAL_MARK_WORD_PAGE_BITS; w < page_bits_end; ++w)
    for (std::uint32_t word = m[w]; word != 0; word &= word - 1) {
      const auto bit = static_cast<vm::uint>((w - vm::VIRTUAL_MARK_WORD_PAGE_BITS) * 32 + static_cast<std::size_t>(std::countr_zero(word)));
      const vm::Page page = vm::virtual_mark_page_of_bit(bit, layout_.pages_per_side);
      out.pages.insert({page.level, page.x, page.y});
    }
  for (const adaptive::Page& page : out.pages) {
    const vm::uint bit = vm::virtual_mark_page_bit(page.level, page.x, page.y, layout_.pages_per_side);
    const auto word = [&](int row) {
      return m[vm::VIRTUAL_MARK_WORD_PAGE_BITS + vm::virtual_mark_tile_word(bit, row, layout_.levels, layout_.pages_per_side)];
    };
    out.tiles[page] = word(0) | static_cast<adaptive::TileMask>(word(4)) << 32;
  }
  return out;
}

}  // namespace penumbra::shadows
