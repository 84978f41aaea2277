#include "shadows/virtual_shadow_map.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <utility>

#include <glm/gtc/matrix_transform.hpp>

#include "gl/shader_library.h"
#include "scene/culling.h"
#include "shadows/fitting.h"
#include "shaders/shadow_contract.h"
#include "shadows/scoped_pass.h"

namespace penumbra::shadows {

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
    bounds_slots_ = gl::Buffer(static_cast<std::size_t>(pool_slots()) * sizeof(std::int32_t), nullptr, GL_DYNAMIC_STORAGE_BIT);
    bounds_ = true;
  }
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
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, bounds_slots_.id());
  pool_.bind(contract::UNIT_VIRTUAL_POOL);
  glBindSampler(contract::UNIT_VIRTUAL_POOL, 0);
  glBindImageTexture(0, bounds_pool_.id(), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
  bounds_program_.use();
  bounds_program_.set("u_virtual_pool_pages", pool_side_);
  bounds_program_.set("u_virtual_page_texels", layout_.page_texels);
  const int groups = (layout_.page_texels / contract::VIRTUAL_BOUNDS_TILE + 7) / 8;  // 8 × 8 tiles a workgroup
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

std::uint64_t VirtualShadowMap::draw_page(int slot, const adaptive::PageKey& key, const scene::Scene& scene, const scene::GpuMeshes& meshes,
                                         const std::vector<std::vector<scene::Footprint>>& footprints) const {
  const int n = layout_.page_texels;
  const int sx = slot % pool_side_, sy = slot / pool_side_;
  glViewport(sx * n, sy * n, n, n);
  glScissor(sx * n, sy * n, n, n);
  glClear(GL_DEPTH_BUFFER_BIT);  // the scissor keeps the other slots
  if (content_ == Content::depth_and_moments) {
    const float far_moments[4] = {1, 1, 0, 0};  // the far plane, t = 1: nothing in front
    glClearBufferfv(GL_COLOR, 0, far_moments);
  }
  const double w = cache_.page_ws(key.level);
  const auto x0 = static_cast<float>(static_cast<double>(key.x) * w), y0 = static_cast<float>(static_cast<double>(key.y) * w);
  const auto wf = static_cast<float>(w);
  program_.set("u_clip_from_world", glm::ortho(x0, x0 + wf, y0, y0 + wf, view_.near_ws, view_.far_ws) * view_.light_view);
  // The square widened by a texel: the raster's float matrix may reach a texel into a caster the
  // exact square just misses.
  const float texel = wf / static_cast<float>(n);
  const scene::Footprint window{{x0 - texel, y0 - texel}, {x0 + wf + texel, y0 + wf + texel}};
  std::uint64_t triangles = 0;
  for (std::size_t i = 0; i < meshes.size(); ++i) {
    const scene::DrawRanges kept = scene::cull_units(meshes[i].units(), footprints[i], window);
    if (kept.first_index.empty()) continue;
    program_.set("u_model", scene.objects[i].model);
    meshes[i].draw(kept);
    triangles += kept.triangles;
  }
  return triangles;
}

VirtualMapStats VirtualShadowMap::update(const std::set<adaptive::Page>& requested, const VirtualMapView& view, const scene::Scene& scene,
                                         const scene::GpuMeshes& meshes, const StepReport* steps) {
  if (meshes.size() != scene.objects.size()) throw std::invalid_argument("virtual shadow map: the meshes are not the scene's");
  for (const adaptive::Page& page : requested)  // before anything changes (the cache checks too, after a new view)
    if (page.level < 0 || page.level >= layout_.levels || page.x < 0 || page.y < 0 || page.x >= layout_.pages_per_side ||
        page.y >= layout_.pages_per_side)
      throw std::invalid_argument("virtual shadow map: page outside the layout (level " + std::to_string(page.level) + ", " +
                                  std::to_string(page.x) + ", " + std::to_string(page.y) + ")");
  std::optional<ScopedPass> scope;
  const auto step = [&](const char* name) {
    scope.reset();
    if (steps) scope.emplace(steps->timer, (name + steps->suffix).c_str(), *steps->passes);
  };

  step("virtual_admit");
  if (has_view_ && (view.light_view != view_.light_view || view.near_ws != view_.near_ws || view.far_ws != view_.far_ws)) invalidate_all();
  view_ = view;
  has_view_ = true;
  const adaptive::PageCache::Update admitted = cache_.update(requested, view.camera_xy);
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
    // Each unit's footprint across the light once; each page then keeps the units over its square.
    std::vector<std::vector<scene::Footprint>> footprints;
    for (std::size_t i = 0; i < meshes.size(); ++i)
      footprints.push_back(scene::unit_footprints(meshes[i].units(), view_.light_view * scene.objects[i].model));
    for (const auto& [slot, key] : to_draw) stats.triangles += draw_page(slot, key, scene, meshes, footprints);
    glDisable(GL_POLYGON_OFFSET_FILL);
    glDisable(GL_DEPTH_CLAMP);
    glDisable(GL_SCISSOR_TEST);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
  }
  if (bounds_) {
    step("virtual_bounds");
    if (!to_draw.empty()) {
      std::vector<int> drawn;
      for (const auto& [slot, key] : to_draw) drawn.push_back(slot);
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

void set_virtual_page_uniforms(const gl::Program& program, const adaptive::VirtualMapLayout& layout, const VirtualMapView& view) {
  program.set("u_virtual_light_view", view.light_view);
  std::vector<glm::vec2> origins;
  for (int k = 0; k < layout.levels; ++k) {
    const adaptive::LightXY o = adaptive::level_origin(k, view.camera_xy, layout);
    origins.emplace_back(static_cast<float>(o.x), static_cast<float>(o.y));
  }
  program.set("u_virtual_origin", std::span<const glm::vec2>(origins));
  program.set("u_virtual_texel0_ws", static_cast<float>(layout.texel0_ws));
  program.set("u_virtual_page_texels", layout.page_texels);
  program.set("u_virtual_pages_per_side", layout.pages_per_side);
  program.set("u_virtual_levels", layout.levels);
  program.set("u_virtual_near_ws", view.near_ws);
  program.set("u_virtual_far_ws", view.far_ws);
}

adaptive::MarkOptions virtual_mark_options(const ShadowSettings& s) {
  adaptive::MarkOptions o;
  o.marking = s.map.virtual_pages == VirtualPages::footprint ? adaptive::Marking::footprint : adaptive::Marking::rule;
  o.c_texels = s.adaptive.c;
  o.min_texel_px = s.adaptive.min_texel_px > 0 ? s.adaptive.min_texel_px : 1.0;
  return o;
}

void set_virtual_mark_uniforms(const gl::Program& program, const scene::Camera& camera, int height_px, const adaptive::MarkOptions& options) {
  const bool perspective = camera.projection == scene::Camera::Projection::perspective;
  program.set("u_mark_camera_position", camera.position);
  program.set("u_mark_camera_forward", glm::normalize(camera.target - camera.position));
  program.set("u_mark_perspective", perspective);
  program.set("u_mark_footprint_per_depth", perspective ? 2 * std::tan(glm::radians(camera.fov_y_deg) / 2) / static_cast<float>(height_px)
                                                        : camera.ortho_height_ws / static_cast<float>(height_px));
  program.set("u_mark_c_texels", static_cast<float>(options.c_texels));
  program.set("u_mark_min_texel_px", static_cast<float>(options.min_texel_px));
  program.set("u_mark_footprint_only", options.marking == adaptive::Marking::footprint);
}

void set_virtual_pcss_uniforms(const gl::Program& program, const VirtualPcss& pcss) {
  program.set("u_virtual_tan_half_angle", pcss.tan_half_angle);
  program.set("u_virtual_search_scale", pcss.search_scale);
  program.set("u_virtual_min_penumbra_ws", pcss.min_penumbra_ws);
  program.set("u_virtual_search_bias_texels", pcss.search_bias_texels);
  program.set("u_search_receiver_plane", pcss.receiver_plane);
}

VirtualPcss virtual_pcss(const ShadowSettings& s, float light_size_deg) {
  const bool plane = s.map.receiver_plane_bias;
  return {std::tan(glm::radians(std::max(light_size_deg, 0.0f)) / 2), s.pcss.search_scale, s.pcss.min_penumbra_ws,
          plane ? s.map.depth_bias_texels : 2.0f, plane};
}

void VirtualShadowMap::bind(const gl::Program& program) const {
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
  program.set("u_virtual_bounds", bounds_);
  set_virtual_page_uniforms(program, layout_, view_);
  program.set("u_virtual_pool_pages", pool_side_);
}

PageMarker::PageMarker(const adaptive::VirtualMapLayout& layout) : layout_(layout) {
  if (layout.levels < 1 || layout.levels > contract::VIRTUAL_MAX_LEVELS || layout.page_texels < 1 || layout.pages_per_side < 1 ||
      !(layout.texel0_ws > 0))
    throw std::invalid_argument("page marker: levels must be 1.." + std::to_string(contract::VIRTUAL_MAX_LEVELS) +
                                ", page_texels, pages_per_side and texel0_ws positive");
  const gl::ShaderLibrary shaders;
  for (int pass = 0; pass < 3; ++pass)
    programs_[pass] = shaders.program({{GL_COMPUTE_SHADER, "virtual_mark.comp"}}, {{"VIRTUAL_MARK_PASS", std::to_string(pass)}});
  const std::size_t bits = static_cast<std::size_t>(layout.levels) * layout.pages_per_side * layout.pages_per_side;
  words_ = (bits + 31) / 32;
  marks_ = make_marks();
}

adaptive::MarkResult PageMarker::mark(const gl::Texture& surface, const scene::Camera& camera, int height_px, const VirtualMapView& view,
                                      double radius_ws, const adaptive::MarkOptions& options, const gl::Texture* levels) const {
  run(Pass::filter, surface, camera, height_px, view, radius_ws, options, levels, nullptr, marks_);
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
  set_virtual_pcss_uniforms(program(Pass::pcss_penumbra), pcss);
  map.bind(program(Pass::pcss_penumbra));  // the search reads the pages the first pass marked
  run(Pass::pcss_penumbra, surface, camera, height_px, map.view(), 0, options, levels, radii, marks_);
  return read(marks_);
}

gl::Buffer PageMarker::make_marks() const {
  return gl::Buffer((contract::VIRTUAL_MAX_LEVELS + 1 + words_) * sizeof(std::uint32_t), nullptr, GL_DYNAMIC_STORAGE_BIT);
}

void PageMarker::dispatch(const gl::Texture& surface, const scene::Camera& camera, int height_px, const VirtualMapView& view,
                          double radius_ws, const adaptive::MarkOptions& options, const gl::Buffer& marks) const {
  run(Pass::filter, surface, camera, height_px, view, radius_ws, options, nullptr, nullptr, marks);
}

void PageMarker::dispatch_pcss_search(const gl::Texture& surface, const scene::Camera& camera, int height_px, const VirtualMapView& view,
                                      const VirtualPcss& pcss, const adaptive::MarkOptions& options, const gl::Buffer& marks) const {
  set_virtual_pcss_uniforms(program(Pass::pcss_search), pcss);
  run(Pass::pcss_search, surface, camera, height_px, view, 0, options, nullptr, nullptr, marks);
}

void PageMarker::dispatch_pcss_filter(const gl::Texture& surface, const scene::Camera& camera, int height_px, const VirtualShadowMap& map,
                                      const VirtualPcss& pcss, const adaptive::MarkOptions& options, const gl::Texture* radii,
                                      const gl::Buffer& marks) const {
  set_virtual_pcss_uniforms(program(Pass::pcss_penumbra), pcss);
  map.bind(program(Pass::pcss_penumbra));  // the search reads the pages resident now
  run(Pass::pcss_penumbra, surface, camera, height_px, map.view(), 0, options, nullptr, radii, marks);
}

void PageMarker::run(Pass pass, const gl::Texture& surface, const scene::Camera& camera, int height_px, const VirtualMapView& view,
                     double radius_ws, const adaptive::MarkOptions& options, const gl::Texture* levels, const gl::Texture* radii,
                     const gl::Buffer& marks) const {
  const gl::Program& prog = program(pass);
  if (height_px < 1) throw std::invalid_argument("page marker: the image needs at least one row");
  const auto same_size_r32f = [&](const gl::Texture* t) {
    return !t || (t->desc().width == surface.desc().width && t->desc().height == surface.desc().height && t->desc().format == GL_R32F);
  };
  if (!same_size_r32f(levels)) throw std::invalid_argument("page marker: the levels image must be R32F of the surface's size");
  if (!same_size_r32f(radii)) throw std::invalid_argument("page marker: the radii image must be R32F of the surface's size");
  prog.set("u_write_levels", levels != nullptr);
  if (levels) glBindImageTexture(1, levels->id(), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_R32F);
  prog.set("u_write_radii", radii != nullptr);
  if (radii) glBindImageTexture(2, radii->id(), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_R32F);
  set_virtual_page_uniforms(prog, layout_, view);
  set_virtual_mark_uniforms(prog, camera, height_px, options);
  prog.set("u_radius_ws", static_cast<float>(radius_ws));
  const std::uint32_t zero = 0;
  glClearNamedBufferData(marks.id(), GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, marks.id());
  glBindImageTexture(0, surface.id(), 0, GL_FALSE, 0, GL_READ_ONLY, GL_RGBA32F);
  prog.dispatch_covering(surface.desc().width, surface.desc().height);
  glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT | GL_TEXTURE_UPDATE_BARRIER_BIT);
}

adaptive::MarkResult PageMarker::read(const gl::Buffer& marks) const {
  std::vector<std::uint32_t> m(contract::VIRTUAL_MAX_LEVELS + 1 + words_);
  glGetNamedBufferSubData(marks.id(), 0, static_cast<GLsizeiptr>(m.size() * sizeof(std::uint32_t)), m.data());
  adaptive::MarkResult out;
  for (int k = 0; k < layout_.levels; ++k) out.pixels_per_level.push_back(m[static_cast<std::size_t>(k)]);
  out.unmarked = m[contract::VIRTUAL_MAX_LEVELS];
  const int n = layout_.pages_per_side;
  for (std::size_t w = 0; w < words_; ++w)
    for (std::uint32_t word = m[contract::VIRTUAL_MAX_LEVELS + 1 + w]; word != 0; word &= word - 1) {
      const auto bit = static_cast<int>(w * 32 + static_cast<std::size_t>(std::countr_zero(word)));
      out.pages.insert({bit / (n * n), bit % n, (bit / n) % n});
    }
  return out;
}

}  // namespace penumbra::shadows
