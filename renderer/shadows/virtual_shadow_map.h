#pragma once
// The physical side of a virtual shadow map for the sun (issue 31's second part): one pool of
// page slots (a 32-bit depth atlas), a page table per clipmap level, each page drawn with its own
// caster culling, kept across frames until the light, or a caster over them, moves. Which pages a
// frame needs comes from adaptive/virtual_pages.h (by the rule or by the footprint); which slot
// holds which page, what a frame keeps, draws and evicts, and the tables, from the GL-free
// adaptive/page_cache.h (the floor first, coarse levels and near pages first, least recently asked
// for evicted: its comment); this class draws the pages it is told into their slots and uploads the
// tables. Shaders read depths through the tables with shaders/virtual_pages.glsl; a pixel whose page
// is missing reads a coarser resident level (virtual_resident_level), never none. The light view is a
// rotation only (pages are places in light space); its depth range is the sun's bounded region
// (sun_virtual_view).
#include <cstdint>
#include <set>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include <penumbra/adaptive/page_cache.h>
#include <penumbra/adaptive/virtual_pages.h>
#include <penumbra/gl/objects.h>
#include <penumbra/scene/gpu_mesh.h>
#include <penumbra/scene/scene.h>
#include <penumbra/shaders/virtual_mark_contract.h>
#include <penumbra/shadows/scoped_pass.h>
#include <penumbra/shadows/settings.h>

namespace penumbra::gl {
class PassTimer;
}

namespace penumbra::shadows {

// Where the clipmap stands this frame.
struct VirtualMapView {
  glm::mat4 light_view{1};        // world -> light space: x, y across the light, -z along it
  float near_ws = 0, far_ws = 1;  // the light-space depth range every page holds (distances along -z)
  adaptive::LightXY camera_xy;    // the camera in light space: each level's window is centred on it
  // Across the light, the sun's bounded region (fitting.h's sun_shadow_region): what the view's
  // pixels can read (the floor of map.virtual_marks_late, adaptive::region_floor_pages).
  adaptive::LightXY region_lo, region_hi;
};

// A light view for a sun whose light travels along `direction`: light-space x and y span the plane
// across it (the same basis as the references' light samples), z points back toward the sun.
glm::mat4 sun_light_view(const glm::vec3& direction);
// World point `p` across the light of `light_view` (its light-space x and y): where a clipmap
// centred on a camera at `p` puts its windows (VirtualMapView::camera_xy).
adaptive::LightXY light_xy(const glm::mat4& light_view, const glm::vec3& p);
// The light-space depth range (distances along -z) that holds the world box `bounds`, widened by
// 1 % and at least 1 cm on each side.
void light_depth_range(const glm::mat4& light_view, const scene::Aabb& bounds, float& near_ws, float& far_ws);
// The sun's virtual map view of `scene`'s camera in an image of `camera_aspect` (width / height):
// sun_light_view, the depth range of the region the sun's maps hold (fitting.h's
// sun_shadow_region: the casters that can reach the receivers, within 1000 receiver sizes, the
// rest depth-clamped as on the maps) widened by 1 % and at least 1 cm on each side, and the camera
// across the light. Not the scene's bounds: one object at 1e20 made the range 1e20 deep, and
// float depths then shadowed nothing. The region follows the camera, and a new depth range drops
// every cached page: with `previous` (the last frame's view), its range is kept while it holds the
// region and is at most 4 times its depth; a range taken anew has a quarter of the region's depth
// to spare on each side, so a walking camera does not redraw every page each frame.
VirtualMapView sun_virtual_view(const scene::Scene& scene, float camera_aspect, const VirtualMapView* previous = nullptr);

// The page cache's counts of a frame (adaptive::PageCacheStats: requested, cached, drawn, missing,
// floor, floor_level, evicted, invalidated, resident), and the triangles drawn into the pages and
// the index ranges they were drawn as (a multi-draw's draws: what a GPU's front end pays per draw).
struct VirtualMapStats : adaptive::PageCacheStats {
  std::uint64_t triangles = 0;  // drawn into the pages
  std::uint64_t draws = 0;
};

// The warning line for a frame whose pool did not hold every page it asked for ("" when none was
// missing): how many, the coarser level their pixels read instead, and the pool side that holds
// them all. The apps print it; the main job and the bench refuse to time such a frame.
std::string missing_pages_warning(const VirtualMapStats& stats, int pool_pages_per_side);

// The frame a virtual shadow map's shaders read: the std140 VirtualFrame block of
// shaders/virtual_mark_contract.h (one uniform buffer, VirtualFrameBuffer), filled in parts below.
using VirtualFrame = virtual_mark::VirtualFrame;
// Writes the layout's and the view's part of `frame`: the light view, each level's window around
// the view's camera, the texel, page and window sizes, the level count and the depth range.
void set_virtual_view(VirtualFrame& frame, const adaptive::VirtualMapLayout& layout, const VirtualMapView& view);

// How `s` marks pages: by the rule (or map.virtual_pages = footprint: the footprint), with
// adaptive.c and the pages' pixel floor map.virtual_min_texel_px.
adaptive::MarkOptions virtual_mark_options(const ShadowSettings& s);

// Writes the marking's part of `frame`: which level a surface point asks for, seen by `camera` in an
// image `height_px` rows high, by `options`' rule (or footprint), c and pixel floor.
void set_virtual_marking(VirtualFrame& frame, const scene::Camera& camera, int height_px, const adaptive::MarkOptions& options);

// PCSS through the pages (virtual_pages.glsl's virtual_pcss_radius): a sun of angular radius
// atan(tan_half_angle), the blocker search's radius over its geometric bound, the smallest
// penumbra (world radius), the search's constant depth bias in texels of its level, and whether
// the search tests each texel against the receiver's plane (else against one depth).
struct VirtualPcss {
  float tan_half_angle = 0;
  float search_scale = 1;
  float min_penumbra_ws = 0;
  float search_bias_texels = 1;
  bool receiver_plane = true;
};
// Writes PCSS's part of `frame`.
void set_virtual_pcss(VirtualFrame& frame, const VirtualPcss& pcss);
// PCSS's parameters through the pages for settings `s` and a sun of angular diameter
// `light_size_deg` (scene::Light::size): the search reads the surface point itself, without the
// normal offset; with map.receiver_plane_bias each texel is tested against the receiver's plane
// less map.depth_bias_texels of the search's level (as the maps' search), else against the
// receiver's depth less 2 texels (a coarse level's texel spans a sloped receiver's depths).
VirtualPcss virtual_pcss(const ShadowSettings& s, float light_size_deg);

// A uniform buffer holding one VirtualFrame, bound at the contract's VIRTUAL_FRAME_BLOCK: where the
// shaders of virtual_pages.glsl find the frame (no uniform of the block is set by name).
class VirtualFrameBuffer {
 public:
  VirtualFrameBuffer();
  // Writes `frame` into the buffer, unless it holds that frame already, and binds the buffer.
  void bind(const VirtualFrame& frame) const;
  // How many times bind() wrote the buffer.
  int writes() const { return writes_; }

 private:
  gl::Buffer buffer_;
  mutable VirtualFrame held_{};
  mutable bool holds_ = false;
  mutable int writes_ = 0;
};

class VirtualShadowMap;

// A pool too small for even the coarsest level under a view's pixels (VirtualShadowMap::update).
using PoolTooSmall = adaptive::PoolTooSmall;

// Page marking on the GPU (shaders/virtual_mark.comp): the pages each pixel's surface asks for, by the
// rule or by the footprint, as adaptive::mark_pages finds them on the CPU (the same arithmetic in
// float: a pixel exactly on a level's or a page's boundary may land on the other side).
class PageMarker {
 public:
  explicit PageMarker(const adaptive::VirtualMapLayout& layout);
  // `surface`: RGBA32F, world xyz and w > 0 where a surface is (metrics::SurfaceProbe's image, or a
  // G-buffer's positions) of an image `height_px` rows high seen by `camera`; `radius_ws` the
  // filter's world radius (0: none).
  // With `levels` (R32F, the surface's size), each pixel's level is written there too: the debug
  // view of the marking (-1 where no surface is, layout.levels beyond the coarsest level).
  adaptive::MarkResult mark(const gl::Texture& surface, const scene::Camera& camera, int height_px, const VirtualMapView& view,
                            double radius_ws, const adaptive::MarkOptions& options, const gl::Texture* levels = nullptr) const;
  // PCSS in two passes: first the pages of each pixel's blocker search (its own level, coarser than
  // the filter's); then, with `map` holding those (after its update), the pages of the penumbra
  // each pixel's search finds, on the level the rule (or the footprint) gives that penumbra. A
  // pixel with nothing in front marks no filter pages (lit). pixels_per_level: the filter's levels.
  // With `radii` (R32F, the surface's size), each pixel's penumbra is written there (world radius;
  // 0 nothing in front; -1 no surface, or no level held its search): the shading filters with it.
  adaptive::MarkResult mark_pcss_search(const gl::Texture& surface, const scene::Camera& camera, int height_px, const VirtualMapView& view,
                                        const VirtualPcss& pcss, const adaptive::MarkOptions& options) const;
  adaptive::MarkResult mark_pcss_filter(const gl::Texture& surface, const scene::Camera& camera, int height_px, const VirtualShadowMap& map,
                                        const VirtualPcss& pcss, const adaptive::MarkOptions& options,
                                        const gl::Texture* levels = nullptr, const gl::Texture* radii = nullptr) const;

  // The same marking without a read (map.virtual_marks_late: no read-back waited for within a
  // frame): each dispatch writes into `marks` (a buffer from make_marks()), and read() takes it in a
  // later frame, when the GPU has long finished it.
  gl::Buffer make_marks() const;
  void dispatch(const gl::Texture& surface, const scene::Camera& camera, int height_px, const VirtualMapView& view, double radius_ws,
                const adaptive::MarkOptions& options, const gl::Buffer& marks, const gl::Texture* levels = nullptr) const;
  void dispatch_pcss_search(const gl::Texture& surface, const scene::Camera& camera, int height_px, const VirtualMapView& view,
                            const VirtualPcss& pcss, const adaptive::MarkOptions& options, const gl::Buffer& marks) const;
  void dispatch_pcss_filter(const gl::Texture& surface, const scene::Camera& camera, int height_px, const VirtualShadowMap& map,
                            const VirtualPcss& pcss, const adaptive::MarkOptions& options, const gl::Texture* radii,
                            const gl::Buffer& marks, const gl::Texture* levels = nullptr) const;
  adaptive::MarkResult read(const gl::Buffer& marks) const;

  // Renderer::count_shading_reads: PCSS's blocker search runs here, not in the shading, so its
  // reads are counted by dispatching mark_pcss_filter's pass again, compiled with
  // COUNT_SHADOW_READS: each pixel's texture reads (tables, depths, tile bounds) are added to the
  // ShadowReadsResult buffer bound at BUFFER_SHADOW_READS (its pixels are the shading's). It marks
  // into a scratch buffer and writes no image: nothing a later frame reads changes.
  void count_pcss_search_reads(const gl::Texture& surface, const scene::Camera& camera, int height_px, const VirtualShadowMap& map,
                               const VirtualPcss& pcss, const adaptive::MarkOptions& options) const;

 private:
  // The marking's three passes (virtual_mark.comp's VIRTUAL_MARK_PASS): a filter's pages, PCSS's searches',
  // PCSS's penumbrae'.
  enum class Pass { filter = 0, pcss_search = 1, pcss_penumbra = 2 };
  // `frame`: the layout's and view's part (and PCSS's); run() adds the marking's.
  // `counting`: a program to run instead of the pass's own (count_pcss_search_reads).
  void run(Pass pass, const gl::Texture& surface, const scene::Camera& camera, int height_px, VirtualFrame frame, double radius_ws,
           const adaptive::MarkOptions& options, const gl::Texture* levels, const gl::Texture* radii, const gl::Buffer& marks,
           const gl::Program* counting = nullptr) const;
  const gl::Program& program(Pass pass) const { return programs_[static_cast<int>(pass)]; }
  adaptive::VirtualMapLayout layout_;
  gl::Program programs_[3];  // one per Pass: a pass chosen by a uniform costs the others' code on llvmpipe
  mutable gl::Program count_program_;  // Pass::pcss_penumbra with COUNT_SHADOW_READS, made on first use
  VirtualFrameBuffer frame_buffer_;
  gl::Buffer marks_;
  std::size_t words_ = 0;  // the marks buffer, in 32-bit words (virtual_mark_buffer_words)
};

class VirtualShadowMap {
 public:
  // Which pools the pages are drawn into: depth (PCF, PCSS), or depth and the moments of variance
  // shadow maps (t, t² + the texel's variance, of the depth t as the pages hold it).
  enum class Content { depth, depth_and_moments };
  // pool_pages_per_side² slots of layout.page_texels² texels. Throws std::invalid_argument for a
  // layout with more than VIRTUAL_MAX_LEVELS levels or non-positive sizes, std::runtime_error (naming
  // the pool) when GL cannot allocate it.
  VirtualShadowMap(const adaptive::VirtualMapLayout& layout, int pool_pages_per_side, Content content = Content::depth);

  const adaptive::VirtualMapLayout& layout() const { return layout_; }
  int pool_pages_per_side() const { return pool_side_; }
  int pool_slots() const { return pool_side_ * pool_side_; }
  // Which slot holds which page (GL-free): what update() admitted, evicted and kept.
  const adaptive::PageCache& cache() const { return cache_; }
  Content content() const { return content_; }

  // Makes the `requested` pages (window-relative, as adaptive::mark_pages gives them for
  // view.camera_xy) resident, drawing those not cached, and writes the page tables. First a coarse
  // floor: the pages of the finest level whose pages under every requested one fit the pool (with
  // the requested pages coarser than it), so that a pixel whose page is missing reads that level
  // instead of being shaded lit; then the rest, coarse levels first, nearest the camera first.
  // Throws PoolTooSmall when even the coarsest level's pages under the requested ones do not fit.
  // A view whose light_view or depth range differs from the last one invalidates every page.
  // Leaves the pool's framebuffer unbound and the viewport and scissor test changed.
  //
  // `steps`, when given, reports update()'s steps as passes of the frame, each timed by its timer
  // and counted by its work counter (either may be null): virtual_admit (the page cache: admit, evict, the view's invalidation),
  // virtual_draw (the casters into the admitted pages), virtual_bounds (when bounds() is on) and
  // virtual_table (the page tables written), each name followed by `suffix` (PCSS's first round:
  // "_search"). Every step is reported whether or not it has work this frame.
  //
  // `tiles` (PageMarker's MarkResult::tiles), when given: a page is drawn with the casters over the
  // rectangle of its marked tiles only (the rest of it holds what those casters leave there, which
  // no pixel that marked it reads); a resident page asked for tiles beyond it is drawn again
  // (adaptive::PageCache::update). Without it every page is drawn whole.
  struct StepReport {
    PassReport report;  // report.passes required
    std::string suffix;
  };
  VirtualMapStats update(const std::set<adaptive::Page>& requested, const VirtualMapView& view, const scene::Scene& scene,
                         const scene::GpuMeshes& meshes, const StepReport* steps = nullptr, const adaptive::PageTiles* tiles = nullptr);
  // The raster depth offset pages are drawn with (glPolygonOffset factor and units, as the maps'
  // map.slope_bias and map.offset_bias; none by default). A change drops every page.
  void set_raster_bias(float slope, float offset);
  // Whether update() also takes the depth bounds of each tile of the pages it draws
  // (virtual_bounds.comp) and bind() lets the filters use them (on by default; depth pools whose page
  // side VIRTUAL_BOUNDS_TILE divides). Turning them on drops every page, whose tiles have none.
  void set_bounds(bool on);
  bool bounds() const { return bounds_; }
  // Bytes one resident page holds: its depths (and moments), and its tiles' bounds when they are on.
  std::uint64_t page_bytes() const;
  // Drops every page (the light moved).
  void invalidate_all();
  // Drops every page but `kept` (window-relative for a camera at `camera_xy`): adaptive::PageCache::invalidate_all_but.
  void invalidate_all_but(const std::set<adaptive::Page>& kept, adaptive::LightXY camera_xy) { cache_.invalidate_all_but(kept, camera_xy); }
  // Drops the pages over the world box `bounds` (a caster moved: call with its old and its new
  // bounds): those whose light-space square meets the box's light-space footprint, at any depth.
  void invalidate(const scene::Aabb& bounds);
  // Drops the pages over every object of `scene` that moved (or changed its mesh) since the last
  // call, over its old and its new bounds; a scene with other objects than last time drops every
  // page. Returns the scene's world bounds (an object's taken again only when it moved: a mesh's
  // bounds walk its vertices). Call it with each frame's scene before its updates.
  scene::Aabb invalidate_moved_casters(const scene::Scene& scene);

  // Binds the pool to UNIT_VIRTUAL_POOL (raw depths) and UNIT_VIRTUAL_POOL_CMP (compared), the moments
  // pool (if any) to UNIT_VIRTUAL_MOMENTS, the tables to UNIT_VIRTUAL_TABLE, the tiles' bounds (if on) to
  // UNIT_VIRTUAL_BOUNDS, and frame() (the last update's view) to BLOCK_VIRTUAL_FRAME.
  void bind() const;
  // The VirtualFrame the map's readers see: its layout, pool and bounds, the last update's view,
  // and the marking and PCSS parts last set (a pixel samples the level it marked).
  const VirtualFrame& frame() const { return frame_; }
  void set_marking(const scene::Camera& camera, int height_px, const adaptive::MarkOptions& options) {
    set_virtual_marking(frame_, camera, height_px, options);
  }
  void set_pcss(const VirtualPcss& pcss) { set_virtual_pcss(frame_, pcss); }
  // The slot of window-relative `page` of the last update's view, or -1 when it is not resident.
  int slot_of(const adaptive::Page& page) const { return cache_.slot_of(page); }
  // The last update's view (has_view: there was one).
  const VirtualMapView& view() const { return view_; }
  bool has_view() const { return has_view_; }
  // Lower corner of level `level`'s window in light space, for the last update's view.
  adaptive::LightXY origin(int level) const { return cache_.origin(level); }

  // The debug view of the pool: each slot free, holding a page drawn by the last update, or one
  // kept from an earlier update (cached); the pool itself (32-bit depth, slot s at column
  // s % pool_pages_per_side, row s / pool_pages_per_side).
  using SlotState = adaptive::PageCache::SlotState;
  std::vector<SlotState> slot_states() const { return cache_.slot_states(); }
  const gl::Texture& pool() const { return pool_; }
  const gl::Texture& moments_pool() const { return moments_; }  // Content::depth_and_moments: RG32F, the pool's layout
  // The tiles' bounds when on: RGBA32F, a texel per VIRTUAL_BOUNDS_TILE² texels of the pool (virtual_bounds.comp).
  const gl::Texture& bounds_pool() const { return bounds_pool_; }

 private:
  // Clears the slots of the pages about to be drawn to the far plane (and the moments' to t = 1).
  void clear_slots(const std::vector<adaptive::PageCache::Admitted>& to_draw) const;
  // Draws page `key` into `slot` (cleared by clear_slots), each object's clusters kept by their
  // footprints across the light over the rectangle of `tiles`, adding the triangles and ranges drawn
  // to `stats`.
  void draw_page(int slot, const adaptive::PageKey& key, adaptive::TileMask tiles, const scene::Scene& scene, const scene::GpuMeshes& meshes,
                 const std::vector<scene::ClusterFootprints>& footprints, VirtualMapStats& stats) const;
  void write_tables();
  // Takes the bounds of every tile of the pages in `slots` (virtual_bounds.comp).
  void write_bounds(const std::vector<int>& slots);

  adaptive::VirtualMapLayout layout_;
  int pool_side_ = 0;
  Content content_ = Content::depth;
  gl::Texture pool_, moments_, table_;
  gl::Texture bounds_pool_;    // RGBA32F, a texel per tile of the pool (virtual_bounds.comp's planes)
  gl::Program bounds_program_;
  gl::Buffer bounds_slots_;    // the slots whose tiles virtual_bounds.comp takes
  bool bounds_ = false;
  gl::Sampler compare_;  // the pool's nearest LEQUAL comparison (virtual_pcf_box's gathers)
  gl::Framebuffer fbo_;
  gl::Program program_;
  VirtualFrame frame_{};
  VirtualFrameBuffer frame_buffer_;
  adaptive::PageCache cache_;
  VirtualMapView view_;
  bool has_view_ = false;
  float slope_bias_ = 0, offset_bias_ = 0;
  // Each object's mesh and placement at the last invalidate_moved_casters.
  struct Caster {
    const scene::MeshData* mesh = nullptr;  // compared, never read: it may be gone
    glm::mat4 model{1};
    scene::Aabb bounds;  // world
  };
  std::vector<Caster> casters_;
};

}  // namespace penumbra::shadows
