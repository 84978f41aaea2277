#include "shadows/passes.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <optional>
#include <set>
#include <span>
#include <stdexcept>
#include <string>

#include "gl/context.h"
#include "sampling/poisson_disk.h"
#include "shadows/contract.h"
#include "shadows/moments_blur.h"
#include "shadows/renderer.h"
#include "shadows/scoped_pass.h"

namespace penumbra::shadows {

const gl::Program& ProgramCache::get(const gl::ShaderLibrary& shaders, const std::string& key, const std::vector<gl::ShaderStage>& stages,
                                     const std::vector<gl::ShaderDefine>& defines) {
  auto it = programs_.find(key);
  if (it == programs_.end()) {
    gl::Program program = shaders.program(stages, defines);
    check_shadow_frame_block(program, key);
    check_virtual_frame_block(program, key);
    it = programs_.emplace(key, std::move(program)).first;
  }
  return it->second;
}

FrameResources::FrameResources(const gl::ShaderLibrary& library) : shaders(library) {
  depth_program = shaders.program({{GL_VERTEX_SHADER, "shadow_depth.vert"}, {GL_FRAGMENT_SHADER, "shadow_depth.frag"}});
  requirement_program = shaders.program({{GL_COMPUTE_SHADER, "pcss_requirement.comp"}});
  minmax_program = shaders.program({{GL_COMPUTE_SHADER, "depth_minmax.comp"}});
  gl::SamplerDesc d;
  d.depth_compare = true;
  cmp_linear = gl::Sampler(d);
  d.min_filter = d.mag_filter = GL_NEAREST;
  cmp_nearest = gl::Sampler(d);
  d.depth_compare = false;
  raw_nearest = gl::Sampler(d);
  // Beyond the map the border reads as the far depth: lit, like the depth samplers' border and the
  // guard band of an atlas region. Each frame sets the border to its technique's far moments.
  moments_linear = gl::Sampler(gl::SamplerDesc{});
  shadow_frame = gl::Buffer(sizeof(contract::ShadowFrame), nullptr, GL_DYNAMIC_STORAGE_BIT);
  gl::check_errors("renderer setup");
}

bool FrameResources::prepare(const FramePlan& plan) {
  bool reallocated = false;
  const AtlasLayout& layout = plan.atlas;
  const GLenum moments_format = plan.moments ? moments_gl_format(plan.moments->format) : 0;
  if (!maps || maps->width != layout.width || maps->height != layout.height || maps->moments_format != moments_format) {
    GLint max_size = 0;
    glGetIntegerv(GL_MAX_TEXTURE_SIZE, &max_size);
    if (layout.width > max_size || layout.height > max_size)
      throw std::runtime_error("render: shadow atlas " + std::to_string(layout.width) + "x" + std::to_string(layout.height) +
                               " exceeds GL_MAX_TEXTURE_SIZE " + std::to_string(max_size) +
                               " (lower map.resolution_texels, adaptive.max_texels or map.cascades)");
    maps.reset();
    // Out of memory is one line naming the map and what to lower, never an abort later on: a
    // 16384² VSM (5 GiB) under `ulimit -v 6 GiB` aborted in a thread start, or printed a GL debug
    // line before its error line. Software GL maps textures in this process, so its address-space
    // limit is checked first, with room left for the rest of the frame (and the image writers).
    const std::uint64_t texels = static_cast<std::uint64_t>(layout.width) * static_cast<std::uint64_t>(layout.height);
    const std::uint64_t needed = texels * (4 + (plan.moments ? 2 * bytes_per_texel(plan.moments->format) : 0));
    const auto out_of_memory = [&](const std::string& why) {
      char line[400];
      std::snprintf(line, sizeof line,
                    "render: the shadow atlas %dx%d (%s%.0f MiB) does not fit in memory: %s (lower map.resolution_texels, "
                    "adaptive.max_texels or map.cascades)",
                    layout.width, layout.height, plan.moments ? "depth and two moment maps, " : "depth, ",
                    static_cast<double>(needed) / (1 << 20), why.c_str());
      return gl::OutOfMemory(line);
    };
    constexpr std::uint64_t kRoomAfterMapsBytes = 1ull << 30;
    if (const auto left = gl::address_space_left_bytes(); left && needed + kRoomAfterMapsBytes > *left) {
      char why[160];
      std::snprintf(why, sizeof why, "this process's address-space limit (ulimit -v) leaves %.0f MiB", static_cast<double>(*left) / (1 << 20));
      throw out_of_memory(why);
    }
    try {
      auto m = std::make_unique<Maps>();
      m->width = layout.width;
      m->height = layout.height;
      m->moments_format = moments_format;
      m->depth = gl::Texture({GL_DEPTH_COMPONENT32F, layout.width, layout.height, 1}, "shadow depth atlas");
      const GLint grey[4] = {GL_RED, GL_RED, GL_RED, GL_ONE};  // debug views show depth as grey
      glTextureParameteriv(m->depth.id(), GL_TEXTURE_SWIZZLE_RGBA, grey);
      const gl::Framebuffer::Attachment depth_only[] = {{&m->depth, GL_DEPTH_ATTACHMENT}};
      m->depth_fbo = gl::Framebuffer(depth_only, "shadow depth framebuffer");
      if (plan.moments) {
        m->moments_tex = gl::Texture({moments_format, layout.width, layout.height, 1}, "shadow moments");
        m->moments_tmp = gl::Texture({moments_format, layout.width, layout.height, 1}, "moments blur temporary");
        const gl::Framebuffer::Attachment att[] = {{&m->moments_tex, GL_COLOR_ATTACHMENT0}, {&m->depth, GL_DEPTH_ATTACHMENT}};
        m->moments_fbo = gl::Framebuffer(att, "moments framebuffer");
      }
      maps = std::move(m);
    } catch (const gl::OutOfMemory& e) {
      throw out_of_memory(e.what());
    }
    reallocated = true;
  }
  if (plan.runs(PassId::depth_minmax) && !maps->depth_minmax.id()) {
    const int w = (maps->width + 1) / 2, h = (maps->height + 1) / 2;
    int levels = 1;
    while ((std::max(w, h) >> levels) > 0) ++levels;
    maps->depth_minmax = gl::Texture({GL_RG32F, w, h, levels}, "min-max depth pyramid");
  }
  const int w = plan.width_px, h = plan.height_px;
  const bool virtual_status = plan.virtual_pages != VirtualPages::off;
  if (!targets || targets->width != w || targets->height != h || targets->requirement != plan.pcss_requirement ||
      targets->virtual_status != virtual_status) {
    targets.reset();
    auto t = std::make_unique<Targets>();
    t->width = w;
    t->height = h;
    t->requirement = plan.pcss_requirement;
    t->virtual_status = virtual_status;
    t->color = gl::Texture({GL_SRGB8_ALPHA8, w, h, 1}, "lit colour");
    t->visibility = gl::Texture({GL_R32F, w, h, 1}, "visibility");
    t->depth = gl::Texture({GL_DEPTH_COMPONENT32F, w, h, 1}, "camera depth");
    std::vector<gl::Framebuffer::Attachment> att = {{&t->color, GL_COLOR_ATTACHMENT0}, {&t->visibility, GL_COLOR_ATTACHMENT1}};
    if (plan.pcss_requirement) {
      t->requirement_tex = gl::Texture({GL_RG32F, w, h, 1}, "PCSS requirement");
      att.push_back({&t->requirement_tex, GL_COLOR_ATTACHMENT2});
    }
    if (virtual_status) {  // a plan has one or the other: both are fragment output 2
      t->virtual_status_tex = gl::Texture({GL_R8UI, w, h, 1}, "virtual map page status");
      att.push_back({&t->virtual_status_tex, GL_COLOR_ATTACHMENT2});
    }
    att.push_back({&t->depth, GL_DEPTH_ATTACHMENT});
    t->fbo = gl::Framebuffer(att, "camera framebuffer");
    targets = std::move(t);
    ++targets_generation;
  }
  screen_result = nullptr;
  return reallocated;
}

std::uint64_t FrameContext::draw_scene(const gl::Program& program, bool shading, const glm::mat4& clip_from_world,
                                       scene::CullVolume volume) const {
  std::uint64_t triangles = 0;
  for (std::size_t i = 0; i < meshes.size(); ++i) {
    const auto& o = scene.objects[i];
    std::optional<scene::DrawRanges> kept;
    if (settings.map.culling) {
      const glm::mat4 clip_from_mesh = clip_from_world * o.model;
      kept = volume == scene::CullVolume::caster ? scene::cull_clusters(meshes[i].clustered(), clip_from_mesh, volume)
                                                 : scene::cull_units(meshes[i].units(), clip_from_mesh, volume);
      if (kept->first_index.empty()) continue;
    }
    program.set("u_model", o.model);
    if (shading) {
      program.set("u_normal_matrix", glm::transpose(glm::inverse(glm::mat3(o.model))));
      program.set("u_albedo", o.albedo);
    }
    if (kept) {
      meshes[i].draw(*kept);
      triangles += kept->triangles;
    } else {
      meshes[i].draw();
      triangles += meshes[i].index_count() / 3;
    }
  }
  return triangles;
}

PassReport FrameContext::report() const { return {timer, work, &info.passes}; }

glm::mat4 FrameContext::camera_view_projection() const { return scene.camera.projection_matrix(plan.aspect) * scene.camera.view(); }

const gl::Program& FrameContext::shading_program(bool gbuffer, bool count_reads) const {
  const TechniqueEntry& entry = *plan.technique;
  std::vector<gl::ShaderDefine> defines;
  if (gbuffer) {
    // The first pass of a screen-space technique: its input shadows, revectorized or hard.
    const bool rbsm = entry.rbsm_input && entry.rbsm_input(settings);
    defines.push_back({std::string(technique_entry(rbsm ? Technique::rbsm : Technique::hard).define), "1"});
    defines.push_back({"SCREEN_SPACE_GBUFFER", "1"});
  } else {
    defines.push_back({std::string(entry.define), "1"});
    if (entry.variant_defines) entry.variant_defines(settings, defines);
  }
  if (plan.pcss_requirement) defines.push_back({"PCSS_REQUIREMENT", "1"});
  if (plan.virtual_pages != VirtualPages::off && !gbuffer) defines.push_back({"VIRTUAL_SHADOW_MAP", "1"});
  if (count_reads) defines.push_back({"COUNT_SHADOW_READS", "1"});
  std::string key = "shading:";
  for (const auto& d : defines) key += d.name + ";";
  return res.programs.get(res.shaders, key, {{GL_VERTEX_SHADER, "shading.vert"}, {GL_FRAGMENT_SHADER, "shading.frag"}}, defines);
}

void FrameContext::bind_shadow_maps() const {
  using namespace contract;
  res.maps->depth.bind(UNIT_SHADOW_CMP);
  res.maps->depth.bind(UNIT_SHADOW_CMP_NEAREST);
  res.maps->depth.bind(UNIT_SHADOW_DEPTH);
  res.cmp_linear.bind(UNIT_SHADOW_CMP);
  res.cmp_nearest.bind(UNIT_SHADOW_CMP_NEAREST);
  res.raw_nearest.bind(UNIT_SHADOW_DEPTH);
  if (plan.runs(PassId::depth_minmax)) {
    res.maps->depth_minmax.bind(UNIT_DEPTH_MINMAX);
    glBindSampler(UNIT_DEPTH_MINMAX, 0);  // texelFetch per level
  }
  if (plan.moments) {
    glSamplerParameterfv(res.moments_linear.id(), GL_TEXTURE_BORDER_COLOR, plan.moments->far_moments.data());
    res.maps->moments_tex.bind(UNIT_MOMENTS);
    res.moments_linear.bind(UNIT_MOMENTS);
  }
}

void FrameContext::upload_shadow_frame() const {
  const ShadowSettings& s = settings;
  const scene::Camera& cam = scene.camera;
  const scene::Light& light = scene.light;
  const LightFrame& lf = plan.light();
  const int count = static_cast<int>(plan.cascades.size());
  const int res0 = plan.cascades.front().resolution_texels;
  const float texel_mid_ws = lf.texel_ws(0.5f * (lf.near_ws + lf.far_ws), res0);
  contract::ShadowFrame b{};
  b.u_view_projection = camera_view_projection();
  b.u_camera_view = cam.view();
  b.u_light_view = lf.view;
  const float w = static_cast<float>(plan.atlas.width), h = static_cast<float>(plan.atlas.height);
  for (int i = 0; i < count; ++i) {
    const CascadeInfo& c = plan.cascades[static_cast<std::size_t>(i)];
    b.u_cascade_view_projection[i] = c.light.view_projection();
    b.u_cascade_region[i] = glm::vec4(static_cast<float>(c.atlas_x) / w, static_cast<float>(c.atlas_y) / h,
                                      static_cast<float>(c.resolution_texels) / w, static_cast<float>(c.resolution_texels) / h);
    b.u_cascade_res[i] = static_cast<float>(c.resolution_texels);
    b.u_cascade_extent_ws[i] = c.light.extent_ws;
    b.u_cascade_far_ws[i] = c.split_far_ws;
  }
  b.u_light_direction = glm::normalize(light.direction);
  b.u_light_near_ws = lf.near_ws;
  b.u_light_position = light.position;
  b.u_light_far_ws = lf.far_ws;
  b.u_light_color = light.color;
  b.u_light_s_xy = lf.s_xy;
  b.u_camera_position = cam.position;
  b.u_light_tan_half_fov = std::tan(glm::radians(lf.fov_deg) / 2);
  b.u_camera_forward = glm::normalize(cam.target - cam.position);
  // Trust receiver slopes up to 85° from the light: |d depth/d uv| ≤ tan 85° · extent / depth range.
  b.u_rpdb_max = std::tan(glm::radians(85.0f)) * texel_mid_ws * static_cast<float>(res0) / std::max(lf.far_ws - lf.near_ws, 1e-6f);
  const float half_cone = glm::radians(light.spot_fov_deg) / 2;
  b.u_spot_cos_outer = std::cos(half_cone);
  b.u_spot_cos_inner = std::cos(half_cone * 0.9f);
  b.u_ambient = light.ambient;
  b.u_normal_offset_texels = s.map.normal_offset_texels;
  b.u_depth_bias_texels = s.map.depth_bias_texels;
  b.u_cascade_blend = count > 1 ? s.map.cascade_blend : 0.0f;
  b.u_cascade_count = count;
  b.u_light_perspective = lf.perspective;
  b.u_receiver_plane_bias = s.map.receiver_plane_bias;
  b.u_show_cascades = show_cascades;
  if (plan.filter_radius) {
    b.u_filter_radius = plan.filter_radius->radius;
    b.u_filter_radius_world = plan.filter_radius->unit == RadiusUnit::world;
  }
  glNamedBufferSubData(res.shadow_frame.id(), 0, sizeof b, &b);
  glBindBufferBase(GL_UNIFORM_BUFFER, contract::BLOCK_SHADOW_FRAME, res.shadow_frame.id());
}

void FrameContext::set_technique_uniforms(const gl::Program& prog) const {
  const ShadowSettings& s = settings;
  const TechniqueEntry& entry = *plan.technique;
  const scene::Light& light = scene.light;
  const LightFrame& lf = plan.light();
  if (entry.set_uniforms) entry.set_uniforms(prog, s);
  if (entry.rbsm_input && entry.rbsm_input(s)) set_rbsm_uniforms(prog, s.rbsm);  // the G-buffer's revectorized input
  if (entry.uses_light_size()) {
    prog.set("u_pcss_light_radius_uv", light.size / 2 * lf.s_xy / std::max(lf.extent_ws, 1e-9f));
    prog.set("u_pcss_tan_half_angle", plan.tan_half_angle);
    prog.set("u_pcss_min_penumbra_ws", s.pcss.min_penumbra_ws);
  }
  if (const int taps = entry.poisson_taps ? entry.poisson_taps(s) : 0; taps > 0) {
    auto it = res.poisson.find(taps);
    if (it == res.poisson.end()) it = res.poisson.emplace(taps, sampling::poisson_disk(taps)).first;
    prog.set("u_poisson", std::span<const glm::vec2>(it->second));
  }
}

namespace {

// The sun's virtual shadow map for this frame: the camera's world positions (into the camera
// targets' depth, which the shading pass reuses), the pages they mark by the rule or the footprint,
// and those not cached drawn into the pool with their own caster culling.
//
// Its steps are the frame's passes (each timed when a timer is given): virtual_positions,
// virtual_mark (the marking dispatch, and its read-back unless the marks are read late),
// virtual_read (the previous frame's marks, late), then VirtualShadowMap::update's virtual_admit,
// virtual_draw, virtual_bounds and virtual_table; PCSS marks and updates twice, its first round
// suffixed "_search".
class VirtualPagesPass final : public Pass {
 public:
  PassId id() const override { return PassId::virtual_pages; }
  bool reports_subpasses() const override { return true; }
  void execute(FrameContext& f) override {
    FrameResources& r = f.res;
    const ShadowSettings& s = f.settings;
    auto& v = r.virtual_map;
    std::optional<ScopedPass> scope;
    const auto step = [&](const char* name) {
      scope.reset();
      scope.emplace(f.report(), name);
    };
    const auto steps = [&](const char* suffix) {
      scope.reset();
      return VirtualShadowMap::StepReport{f.report(), suffix};
    };
    // How the technique reads pages (its registry entry): moments are drawn beside the depths, a
    // blocker search marks in two rounds.
    const PageReading reading = technique_entry(s.technique).pages;
    const auto content = reading == PageReading::moments ? VirtualShadowMap::Content::depth_and_moments : VirtualShadowMap::Content::depth;
    if (!v || v->pool_pages != s.map.virtual_pool_pages || v->map->content() != content) {
      v = std::make_unique<FrameResources::Virtual>();
      const adaptive::VirtualMapLayout layout;
      v->pool_pages = s.map.virtual_pool_pages;
      v->map = std::make_unique<VirtualShadowMap>(layout, s.map.virtual_pool_pages, content);
      v->marker = std::make_unique<PageMarker>(layout);
      v->shading_counts = gl::Buffer(sizeof(contract::VirtualShadingResult), nullptr, GL_DYNAMIC_STORAGE_BIT);
    }
    v->map->set_raster_bias(s.map.slope_bias, s.map.offset_bias);
    v->map->set_bounds(s.map.virtual_bounds);
    v->map->invalidate_moved_casters(f.scene);
    const int w = f.plan.width_px, h = f.plan.height_px;
    if (v->targets_generation != r.targets_generation) {  // new camera targets: their depth is attached anew
      v->targets_generation = r.targets_generation;
      v->positions = gl::Texture({GL_RGBA32F, w, h, 1}, "virtual map: camera world positions");
      v->pcss_radii = gl::Texture({GL_R32F, w, h, 1}, "virtual map: PCSS penumbra per pixel");
      const gl::Framebuffer::Attachment att[] = {{&v->positions, GL_COLOR_ATTACHMENT0}, {&r.targets->depth, GL_DEPTH_ATTACHMENT}};
      v->fbo = gl::Framebuffer(att, "virtual map: position pass");
    }
    // The camera's surfaces: world xyz, w = 1 (0 where nothing is).
    step("virtual_positions");
    const gl::Program& prog = r.programs.get(r.shaders, "virtual_positions",
                                             {{GL_VERTEX_SHADER, "shading.vert"}, {GL_FRAGMENT_SHADER, "virtual_positions.frag"}});
    v->fbo.bind();
    glViewport(0, 0, w, h);
    const float nothing[4] = {0, 0, 0, 0}, far_depth = 1;
    glClearBufferfv(GL_COLOR, 0, nothing);
    glClearBufferfv(GL_DEPTH, 0, &far_depth);
    prog.use();
    f.info.camera_triangles += f.draw_scene(prog, true, f.camera_view_projection(), scene::CullVolume::view);

    // Mark, then make the marked pages resident.
    const VirtualMapView view =
        sun_virtual_view(f.scene, static_cast<float>(w) / static_cast<float>(h), v->map->has_view() ? &v->map->view() : nullptr);
    v->options = virtual_mark_options(s);
    FrameInfo::Virtual out;
    out.page_texels = v->map->layout().page_texels;
    out.pool_pages_per_side = v->map->pool_pages_per_side();
    out.near_ws = view.near_ws, out.far_ws = view.far_ws;
    adaptive::MarkResult marked;
    const bool pcss = reading == PageReading::blocker_search;
    if (pcss) {
      v->radius_ws = 0;
      v->pcss = virtual_pcss(s, f.scene.light.size);
    } else {
      v->radius_ws = f.plan.filter_radius->radius;
      v->pcss.reset();
    }
    // Pages drawn by their marked tiles: frames drawn anew and marked this frame (ShadowMapParams::virtual_page_tiles).
    const bool tiles = s.map.virtual_page_tiles && !s.map.virtual_cache;
    if (s.map.virtual_marks_late) {
      // The previous frame's marks, read now that the GPU has long finished them, as pages of this
      // frame's windows; with the sun's region on a coarse level, so that a pixel whose marks are
      // not read yet finds a page. This frame's marks go to the next.
      auto& late = v->late;
      if (late.filter.id() == 0) late.filter = v->marker->make_marks(), late.search = v->marker->make_marks();
      const adaptive::VirtualMapLayout& layout = v->map->layout();
      std::set<adaptive::Page> requested;
      step("virtual_read");
      if (late.pending && late.light_view == view.light_view && late.pcss == pcss) {
        marked = v->marker->read(late.filter);
        requested = adaptive::rebase_pages(marked.pages, late.camera_xy, view.camera_xy, layout);
        if (pcss) {
          const std::set<adaptive::Page> search =
              adaptive::rebase_pages(v->marker->read(late.search).pages, late.camera_xy, view.camera_xy, layout);
          out.search_pages = static_cast<int>(search.size());
          requested.insert(search.begin(), search.end());
        }
      }
      // At most 16 pages (1 MiB of 128² depths; 8 coarse pages on the town's street), what the first
      // frame after a cut shows. 256 pages (a quarter of the default pool) took 234 pages beside the
      // 104 the street's marks asked for. Each floor page draws every caster over it, so the floor
      // stays resident even without map.virtual_cache (drawn again only where a caster moved or the
      // light did, like an engine's coarse levels): redrawn every frame it doubled the triangles of
      // an uncached frame on the street (docs/results/virtual-maps.md).
      constexpr int kRegionFloorPages = 16;
      const std::set<adaptive::Page> floor =
          adaptive::region_floor_pages(view.region_lo, view.region_hi, view.camera_xy, layout, std::min(kRegionFloorPages, v->map->pool_slots() / 4));
      out.region_floor = static_cast<int>(floor.size());
      requested.insert(floor.begin(), floor.end());
      if (!s.map.virtual_cache) v->map->invalidate_all_but(floor, view.camera_xy);
      const VirtualShadowMap::StepReport report = steps("");
      out.pages = v->map->update(requested, view, f.scene, f.meshes, &report);
      step("virtual_mark");
      if (pcss) {
        v->marker->dispatch_pcss_search(v->positions, f.scene.camera, h, view, *v->pcss, v->options, late.search);
        v->marker->dispatch_pcss_filter(v->positions, f.scene.camera, h, *v->map, *v->pcss, v->options, &v->pcss_radii, late.filter);
      } else {
        v->marker->dispatch(v->positions, f.scene.camera, h, view, v->radius_ws, v->options, late.filter);
      }
      late.pending = true;
      late.camera_xy = view.camera_xy;
      late.light_view = view.light_view;
      late.pcss = pcss;
      out.marks_late = true;
    } else if (pcss) {
      // Two rounds: the pages of each pixel's blocker search, then those of the penumbra it finds.
      v->late.pending = false;
      step("virtual_mark_search");
      const adaptive::MarkResult search = v->marker->mark_pcss_search(v->positions, f.scene.camera, h, view, *v->pcss, v->options);
      if (!s.map.virtual_cache) v->map->invalidate_all();
      const VirtualShadowMap::StepReport first_report = steps("_search");
      const VirtualMapStats first = v->map->update(search.pages, view, f.scene, f.meshes, &first_report, tiles ? &search.tiles : nullptr);
      step("virtual_mark");
      marked = v->marker->mark_pcss_filter(v->positions, f.scene.camera, h, *v->map, *v->pcss, v->options, nullptr, &v->pcss_radii);
      std::set<adaptive::Page> all = search.pages;
      all.insert(marked.pages.begin(), marked.pages.end());
      adaptive::PageTiles all_tiles = search.tiles;  // the second round keeps the search's tiles
      for (const auto& [page, t] : marked.tiles) all_tiles[page] |= t;
      const VirtualShadowMap::StepReport second_report = steps("");
      const VirtualMapStats second = v->map->update(all, view, f.scene, f.meshes, &second_report, tiles ? &all_tiles : nullptr);
      out.pages = second;
      out.pages.drawn = first.drawn + second.drawn;
      // The search's pages drawn this frame are not cached ones (those drawn again for the
      // penumbrae's tiles are counted drawn, not cached, by the second round already).
      out.pages.cached = second.cached - (first.drawn - second.widened);
      out.pages.widened = first.widened + second.widened;
      out.pages.evicted = first.evicted + second.evicted;
      out.pages.invalidated = first.invalidated + second.invalidated;
      out.pages.floor = std::max(first.floor, second.floor);
      out.pages.triangles = first.triangles + second.triangles;
      out.pages.draws = first.draws + second.draws;
      out.search_pages = static_cast<int>(search.pages.size());
      out.sync_reads = 2;
    } else {
      v->late.pending = false;
      step("virtual_mark");
      marked = v->marker->mark(v->positions, f.scene.camera, h, view, v->radius_ws, v->options);
      if (!s.map.virtual_cache) v->map->invalidate_all();
      const VirtualShadowMap::StepReport report = steps("");
      out.pages = v->map->update(marked.pages, view, f.scene, f.meshes, &report, tiles ? &marked.tiles : nullptr);
      out.sync_reads = 1;
    }
    out.pixels_per_level = marked.pixels_per_level;
    out.unmarked = marked.unmarked;
    out.resident_bytes = static_cast<std::uint64_t>(out.pages.resident) * v->map->page_bytes();
    out.pool_bytes = static_cast<std::uint64_t>(v->map->pool_slots()) * v->map->page_bytes();
    out.table_bytes = static_cast<std::uint64_t>(v->map->layout().pages_per_side) * v->map->layout().pages_per_side *
                      static_cast<std::uint64_t>(v->map->layout().levels) * 4;
    scope.reset();
    f.info.virtual_map = out;
    f.info.map_triangles.push_back(out.pages.triangles);
    gl::check_errors("virtual_pages pass");
  }
};

class ShadowMapPass final : public Pass {
 public:
  PassId id() const override { return PassId::shadow_map; }
  void execute(FrameContext& f) override {
    const auto& moments = f.plan.moments;
    FrameResources& r = f.res;
    const gl::Program& prog =
        moments ? r.programs.get(r.shaders, "moments:" + std::string(f.plan.technique->define),
                                 {{GL_VERTEX_SHADER, "shadow_depth.vert"}, {GL_FRAGMENT_SHADER, "shadow_moments.frag"}},
                                 {{std::string(f.plan.technique->define), "1"}})
                : r.depth_program;
    (moments ? r.maps->moments_fbo : r.maps->depth_fbo).bind();
    glEnable(GL_DEPTH_CLAMP);  // casters in front of the fitted near plane still occlude
    glEnable(GL_SCISSOR_TEST);
    prog.use();
    const int guard = f.plan.atlas.guard;
    for (const auto& c : f.plan.cascades) {
      // Clear the region and its guard band only: the rest of a sub-rectangle atlas is never read.
      const int res = c.resolution_texels;
      glScissor(c.atlas_x - guard, c.atlas_y - guard, res + 2 * guard, res + 2 * guard);
      if (moments) glClearBufferfv(GL_COLOR, 0, moments->far_moments.data());
      const float one = 1;
      glClearBufferfv(GL_DEPTH, 0, &one);
      glViewport(c.atlas_x, c.atlas_y, res, res);
      glScissor(c.atlas_x, c.atlas_y, res, res);
      if (!moments) {
        glEnable(GL_POLYGON_OFFSET_FILL);
        glPolygonOffset(f.settings.map.slope_bias, f.settings.map.offset_bias);
      }
      prog.set("u_light_view_projection", c.light.view_projection());
      // The light view and the moments' depth range are the frame's (ShadowFrame): cascades share them.
      if (moments && f.plan.technique->set_uniforms) f.plan.technique->set_uniforms(prog, f.settings);
      f.info.map_triangles.push_back(f.draw_scene(prog, false, c.light.view_projection(), scene::CullVolume::caster));
    }
    glDisable(GL_SCISSOR_TEST);
    glDisable(GL_POLYGON_OFFSET_FILL);
    glDisable(GL_DEPTH_CLAMP);
    gl::check_errors("shadow_map pass");
  }
};

class MomentsBlurPass final : public Pass {
 public:
  PassId id() const override { return PassId::moments_blur; }
  void execute(FrameContext& f) override {
    const MomentsLayout& moments = *f.plan.moments;
    const FilterRadius radius = *f.plan.filter_radius;
    FrameResources& r = f.res;
    const char* qualifier = image_format_qualifier(moments.format);
    const gl::Program& blur = r.programs.get(r.shaders, std::string("blur:") + qualifier + (moments.direct_sums ? ":direct" : ""),
                                             {{GL_COMPUTE_SHADER, "vsm_blur.comp"}}, moments_blur_defines(moments));
    const LightFrame& lf = f.plan.light();
    const float mid_depth = 0.5f * (lf.near_ws + lf.far_ws);
    for (const auto& c : f.plan.cascades) {
      // World-space radii span a different number of texels in each cascade.
      const float texel = c.light.texel_ws(mid_depth, c.resolution_texels);
      const float r_texels = radius.unit == RadiusUnit::texels ? radius.radius : radius.radius / texel;
      blur_moments_region(blur, moments, r.maps->moments_tex, r.maps->moments_tmp, glm::ivec2(c.atlas_x, c.atlas_y), c.resolution_texels,
                          moments_blur_radius_texels(r_texels, c.resolution_texels));
    }
    gl::check_errors("vsm_blur pass");
  }
};

// The min-max depth pyramid of the atlas, level by level over the frame's map regions: a block is
// known where it lies inside one map's region and guard band (drawn or cleared this frame), and
// (0, 1) elsewhere, so lookups that reach stale or unused atlas texels only lose the shortcut
// (depth_minmax.comp).
class DepthMinmaxPass final : public Pass {
 public:
  PassId id() const override { return PassId::depth_minmax; }
  void execute(FrameContext& f) override {
    FrameResources& r = f.res;
    const gl::Program& prog = r.minmax_program;
    prog.use();
    const int guard = f.plan.atlas.guard;
    std::vector<glm::ivec4> regions;
    glm::ivec2 lo(std::numeric_limits<int>::max()), hi(std::numeric_limits<int>::min());
    for (const auto& c : f.plan.cascades) {
      const glm::ivec4 region(c.atlas_x - guard, c.atlas_y - guard, c.atlas_x + c.resolution_texels + guard,
                              c.atlas_y + c.resolution_texels + guard);
      regions.push_back(region);
      lo = glm::min(lo, glm::ivec2(region.x, region.y));
      hi = glm::max(hi, glm::ivec2(region.z, region.w));
    }
    prog.set("u_regions", static_cast<int>(regions.size()));
    prog.set("u_region", std::span<const glm::ivec4>(regions));
    const GLuint depth_unit = prog.binding("u_depth"), minmax_unit = prog.binding("u_minmax"), out_unit = prog.binding("u_out");
    r.maps->depth.bind(depth_unit);
    glBindSampler(depth_unit, 0);
    r.maps->depth_minmax.bind(minmax_unit);
    glBindSampler(minmax_unit, 0);
    GLint levels = 0;
    glGetTextureParameteriv(r.maps->depth_minmax.id(), GL_TEXTURE_IMMUTABLE_LEVELS, &levels);
    for (int level = 1; level <= levels; ++level) {
      // This level's texels that overlap the regions' bounding box.
      const glm::ivec2 first = lo >> level, last = (hi - 1) >> level;
      const glm::ivec2 extent = last - first + 1;
      prog.set("u_level", level);
      prog.set("u_origin", first);
      prog.set("u_extent", extent);
      glBindImageTexture(out_unit, r.maps->depth_minmax.id(), level - 1, GL_FALSE, 0, GL_WRITE_ONLY, GL_RG32F);
      prog.dispatch_covering(extent.x, extent.y);
      glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
    }
    gl::check_errors("depth_minmax pass");
  }
};

class GbufferPass final : public Pass {
 public:
  PassId id() const override { return PassId::gbuffer; }
  void execute(FrameContext& f) override {
    FrameResources& r = f.res;
    if (!r.screen_space) r.screen_space = std::make_unique<ScreenSpace>(r.shaders);
    r.screen_space->resize(r.targets->depth);
    const gl::Program& prog = f.shading_program(true);
    r.screen_space->gbuffer_framebuffer().bind();
    glViewport(0, 0, f.plan.width_px, f.plan.height_px);
    const float nothing[4] = {0, 0, 0, 0}, far_depth = 1;
    glClearBufferfv(GL_COLOR, 0, nothing);
    glClearBufferfv(GL_COLOR, 1, nothing);
    glClearBufferfv(GL_DEPTH, 0, &far_depth);
    prog.use();
    f.bind_shadow_maps();
    f.set_technique_uniforms(prog);
    f.info.camera_triangles += f.draw_scene(prog, true, f.camera_view_projection(), scene::CullVolume::view);
    gl::check_errors("gbuffer pass");
  }
};

class PostPass final : public Pass {
 public:
  PassId id() const override { return PassId::post; }
  bool reports_subpasses() const override { return true; }
  void execute(FrameContext& f) override {
    const scene::Camera& cam = f.scene.camera;
    const float height = static_cast<float>(f.plan.height_px);
    PostPassContext ctx;
    ctx.view.perspective = cam.projection == scene::Camera::Projection::perspective;
    ctx.view.px_scale = ctx.view.perspective ? height / (2 * std::tan(glm::radians(cam.fov_y_deg) / 2)) : height / cam.ortho_height_ws;
    ctx.set_technique_uniforms = [&f](const gl::Program& p) { f.set_technique_uniforms(p); };
    ctx.report = f.report();
    f.bind_shadow_maps();
    f.res.screen_result = &f.plan.technique->post(*f.res.screen_space, f.settings, ctx);
  }
};

// The shading's pixels by where they found their virtual-map pages (virtual_status.comp), read at
// once (a wait for the pass): the counts belong to this frame's report. With
// map.virtual_marks_late the previous frame's counts are read first and reported instead, and
// this frame's are left for the next.
void count_virtual_status(FrameContext& f) {
  FrameResources& r = f.res;
  FrameResources::Virtual& v = *r.virtual_map;
  const gl::Buffer& counts = v.shading_counts;
  const bool late = f.settings.map.virtual_marks_late;
  const auto report = [&] {
    contract::VirtualShadingResult c{};
    glGetNamedBufferSubData(counts.id(), 0, sizeof c, &c);
    f.info.virtual_map->at_level = c.at_level;
    f.info.virtual_map->coarser = c.coarser;
    f.info.virtual_map->none = c.none;
  };
  if (late && v.shading_counts_pending) {
    report();  // written by the previous frame
    f.info.virtual_map->shaded_of_previous_frame = true;
  }
  const std::uint32_t zero = 0;
  glClearNamedBufferData(counts.id(), GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
  const gl::Program& prog = r.programs.get(r.shaders, "virtual_status", {{GL_COMPUTE_SHADER, "virtual_status.comp"}});
  prog.use();
  glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
  glBindImageTexture(prog.binding("u_status"), r.targets->virtual_status_tex.id(), 0, GL_FALSE, 0, GL_READ_ONLY, GL_R8UI);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, contract::BUFFER_VIRTUAL_SHADING, counts.id());
  constexpr int group = contract::VIRTUAL_STATUS_GROUP_PIXELS;
  glDispatchCompute(static_cast<GLuint>((f.plan.width_px + group - 1) / group), static_cast<GLuint>((f.plan.height_px + group - 1) / group), 1);
  glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
  v.shading_counts_pending = late;
  if (!late) {
    report();
    ++f.info.virtual_map->sync_reads;
  }
  gl::check_errors("virtual map status count");
}

// The shading pass's draw with `prog` (the frame's shading program, or its counting variant): the
// shadow maps and the technique's state bound, every object in view drawn. Returns the triangles
// drawn.
std::uint64_t draw_shading(FrameContext& f, const gl::Program& prog) {
  FrameResources& r = f.res;
  prog.use();
  f.bind_shadow_maps();
  f.set_technique_uniforms(prog);
  if (f.plan.virtual_pages != VirtualPages::off) {
    const FrameResources::Virtual& v = *r.virtual_map;
    v.map->set_marking(f.scene.camera, f.plan.height_px, v.options);
    v.map->bind();
    if (v.pcss) {
      v.pcss_radii.bind(contract::UNIT_VIRTUAL_PCSS_RADII);
      glBindSampler(contract::UNIT_VIRTUAL_PCSS_RADII, 0);
      glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT);  // the marker's image stores
    }
  }
  if (r.screen_result) {
    glBindSampler(contract::UNIT_SCREEN_VISIBILITY, 0);
    r.screen_result->bind(contract::UNIT_SCREEN_VISIBILITY);
  }
  return f.draw_scene(prog, true, f.camera_view_projection(), scene::CullVolume::view);
}

// The camera's depth alone (map.depth_prepass), into the camera targets' depth, which the shading
// pass then tests with LEQUAL: each pixel's visible surface is shaded once, its shadow looked up
// once, however many surfaces were drawn over it before. Its triangles are the camera's.
class DepthPrepassPass final : public Pass {
 public:
  PassId id() const override { return PassId::depth_prepass; }
  void execute(FrameContext& f) override {
    FrameResources& r = f.res;
    // shading.vert's invariant position: the shading pass's depths equal these exactly.
    const gl::Program& prog =
        r.programs.get(r.shaders, "depth_prepass", {{GL_VERTEX_SHADER, "shading.vert"}, {GL_FRAGMENT_SHADER, "shadow_depth.frag"}});
    r.targets->fbo.bind();
    glViewport(0, 0, f.plan.width_px, f.plan.height_px);
    const float far_depth = 1;
    glClearBufferfv(GL_DEPTH, 0, &far_depth);
    glColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDepthMask(GL_TRUE);
    prog.use();
    f.info.camera_triangles += f.draw_scene(prog, false, f.camera_view_projection(), scene::CullVolume::view);
    glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    gl::check_errors("depth_prepass pass");
  }
};

class ShadingPass final : public Pass {
 public:
  PassId id() const override { return PassId::shading; }
  void execute(FrameContext& f) override {
    FrameResources& r = f.res;
    const bool requirement = f.plan.pcss_requirement;
    const gl::Program& prog = f.shading_program(false);
    r.targets->fbo.bind();
    const bool virtual_pages = f.plan.virtual_pages != VirtualPages::off;
    if (requirement || virtual_pages) {
      const GLenum bufs[] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1, GL_COLOR_ATTACHMENT2};
      glNamedFramebufferDrawBuffers(r.targets->fbo.id(), 3, bufs);
    }
    glViewport(0, 0, f.plan.width_px, f.plan.height_px);
    glEnable(GL_FRAMEBUFFER_SRGB);
    const float sky[4] = {0.45f, 0.55f, 0.7f, 1};
    const float lit = 1, far_depth = 1;
    glClearBufferfv(GL_COLOR, 0, sky);
    glClearBufferfv(GL_COLOR, 1, &lit);
    if (requirement) {
      const float none[4] = {0, 0, 0, 0};
      glClearBufferfv(GL_COLOR, 2, none);
    }
    if (virtual_pages) {
      const GLuint none[4] = {0, 0, 0, 0};
      glClearBufferuiv(GL_COLOR, 2, none);
    }
    if (f.plan.camera_depth_first()) {
      // The G-buffer, the virtual map's position pass or the depth prepass left the depth: shade
      // exactly the fragments it kept.
      glDepthFunc(GL_LEQUAL);
      glDepthMask(GL_FALSE);
    } else {
      glClearBufferfv(GL_DEPTH, 0, &far_depth);
    }
    f.info.camera_triangles += draw_shading(f, prog);
    if (virtual_pages) count_virtual_status(f);
    glDisable(GL_FRAMEBUFFER_SRGB);
    glDepthFunc(GL_LESS);
    glDepthMask(GL_TRUE);
    gl::check_errors("shading pass");
  }
};

class PcssRequirementPass final : public Pass {
 public:
  PassId id() const override { return PassId::pcss_requirement; }
  void execute(FrameContext& f) override {
    FrameResources& r = f.res;
    FrameResources::Requirement& q = r.requirement;
    const AdaptiveParams& ap = f.settings.adaptive;
    const int slot = q.frame % 2;
    if (!q.buffer[slot].id()) q.buffer[slot] = gl::Buffer(sizeof(contract::PcssRequirementResult), nullptr, 0);
    const std::uint32_t zero = 0;
    glClearNamedBufferData(q.buffer[slot].id(), GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
    r.requirement_program.use();
    const GLuint requirement_unit = r.requirement_program.binding("u_requirement");
    r.targets->requirement_tex.bind(requirement_unit);
    glBindSampler(requirement_unit, 0);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, contract::BUFFER_PCSS_REQUIREMENT, q.buffer[slot].id());
    r.requirement_program.set("u_limit_inverse_uv", static_cast<float>(ap.max_texels) / ap.c);
    // A work group covers PCSS_REQUIREMENT_GROUP_PIXELS² pixels (its invocations reduce blocks of
    // pixels each), so the dispatch covers pixels / that, not pixels / the work-group size.
    constexpr int group = contract::PCSS_REQUIREMENT_GROUP_PIXELS;
    glDispatchCompute(static_cast<GLuint>((f.plan.width_px + group - 1) / group), static_cast<GLuint>((f.plan.height_px + group - 1) / group), 1);
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    q.pending[slot] = true;
    q.cascades[slot] = static_cast<int>(f.plan.cascades.size());
    q.c[slot] = ap.c;
    gl::check_errors("pcss_requirement pass");
  }
};

}  // namespace

ShadowReads count_shading_reads(FrameContext& f) {
  FrameResources& r = f.res;
  if (!r.shadow_reads.id()) r.shadow_reads = gl::Buffer(sizeof(contract::ShadowReadsResult), nullptr, GL_DYNAMIC_STORAGE_BIT);
  const std::uint32_t zero = 0;
  glClearNamedBufferData(r.shadow_reads.id(), GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, contract::BUFFER_SHADOW_READS, r.shadow_reads.id());
  r.targets->fbo.bind();
  glViewport(0, 0, f.plan.width_px, f.plan.height_px);
  // The frame's own depth, kept: each pixel's surface passes (LEQUAL), nothing behind it runs
  // (shading.frag declares early fragment tests when counting), nothing is written.
  glColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LEQUAL);
  glDepthMask(GL_FALSE);
  const gl::Program& prog = f.shading_program(false, true);
  const TechniqueEntry& entry = *f.plan.technique;
  const std::optional<MomentsLayout> moments = entry.moments ? entry.moments(f.settings) : std::nullopt;
  prog.set("u_count_moment_bytes", moments ? bytes_per_texel(moments->format) : 0);
  draw_shading(f, prog);  // its triangles are the frame's, counted when it was drawn
  // PCSS through the virtual map searches for blockers in its marking, not in the shading: that
  // pass again, counting (PageMarker::count_pcss_search_reads).
  if (f.plan.virtual_pages != VirtualPages::off && r.virtual_map && r.virtual_map->pcss)
    r.virtual_map->marker->count_pcss_search_reads(r.virtual_map->positions, f.scene.camera, f.plan.height_px, *r.virtual_map->map,
                                                   *r.virtual_map->pcss, r.virtual_map->options);
  glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
  glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  glDepthFunc(GL_LESS);
  glDepthMask(GL_TRUE);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  contract::ShadowReadsResult raw{};
  glGetNamedBufferSubData(r.shadow_reads.id(), 0, sizeof raw, &raw);
  ShadowReads reads;
  for (int i = 0; i < contract::SHADOW_READ_SLOTS; ++i) {
    reads.pixels += raw.read_pixels[i];
    reads.instructions += raw.read_instructions[i];
    reads.texels += raw.read_texels[i];
    reads.bytes += raw.read_bytes[i];
  }
  gl::check_errors("shadow read count");
  return reads;
}

std::vector<std::unique_ptr<Pass>> make_passes() {
  std::vector<std::unique_ptr<Pass>> passes;
  passes.push_back(std::make_unique<VirtualPagesPass>());
  passes.push_back(std::make_unique<ShadowMapPass>());
  passes.push_back(std::make_unique<MomentsBlurPass>());
  passes.push_back(std::make_unique<DepthMinmaxPass>());
  passes.push_back(std::make_unique<GbufferPass>());
  passes.push_back(std::make_unique<PostPass>());
  passes.push_back(std::make_unique<DepthPrepassPass>());
  passes.push_back(std::make_unique<ShadingPass>());
  passes.push_back(std::make_unique<PcssRequirementPass>());
  return passes;
}

}  // namespace penumbra::shadows
