// The contract of the virtual shadow map's page marking (shaders/virtual_mark.comp), read by C++ and
// by GLSL: what an engine binds before it dispatches the marking and how it reads the marks back.
// Installed for engines as <penumbra/shaders/virtual_mark_contract.h> (C++17; no GL, no GLM), beside
// share/penumbra/shaders/virtual_mark.comp, the marking shader with its includes inlined (this file
// among them); docs/virtual-pages-in-your-engine.md walks through it. The renderer's PageMarker and
// its shading through the pages (shadows/virtual_shadow_map.h, shaders/virtual_pages.glsl) read the
// same block; tests/install/test_virtual_mark_gl.cpp checks every number here against the driver's
// view of the installed shader and against shaders/shadow_contract.h, test_shader_contract_gl the
// block's std140 offsets against the C++ struct's.
//
// Dispatch: ceil(width / VIRTUAL_MARK_GROUP_SIZE) × ceil(height / VIRTUAL_MARK_GROUP_SIZE) work
// groups over the surface image, one invocation per pixel. Compile with `#version 450 core` and
// `#define VIRTUAL_MARK_PASS 0` (1, 2: PCSS's two passes) before the shader's text.
//
// The frame: a std140 uniform block VirtualFrame at uniform-buffer binding VIRTUAL_FRAME_BLOCK
// (below), one buffer of sizeof(VirtualFrame) bytes written once a frame: the map's layout and
// light view, the camera the marking measures footprints with, the rule's constants, PCSS's
// search constants. What differs between dispatches of a frame stays a plain uniform of the
// marking shader: u_radius_ws (pass 0: the filter's world radius), u_write_levels, u_write_radii.
//
// Images (glBindImageTexture unit = the constant):
//   VIRTUAL_MARK_IMAGE_SURFACE  rgba32f, read: each pixel's surface point, world xyz; w > 0 where a
//                               surface is (w <= 0: sky, not marked, not counted)
//   VIRTUAL_MARK_IMAGE_LEVELS   r32f, written where u_write_levels: the level each pixel samples (-1:
//                               no surface; u_virtual_levels: beyond the coarsest level's window)
//   VIRTUAL_MARK_IMAGE_RADII    r32f, written in pass 2 where u_write_radii: each pixel's penumbra,
//                               world radius (0: nothing in front; -1: no surface or no search)
//
// The marks buffer: std430, shader storage binding VIRTUAL_MARK_BUFFER, 32-bit unsigned words,
// cleared to zero before each dispatch (the shader only adds and ORs), of at least
// virtual_mark_buffer_words(levels, pages_per_side) words:
//   word VIRTUAL_MARK_WORD_PIXELS_PER_LEVEL + k  pixels that sample level k (k < VIRTUAL_MARK_MAX_LEVELS)
//   word VIRTUAL_MARK_WORD_UNMARKED              pixels beyond the coarsest level's window
//   words VIRTUAL_MARK_WORD_PAGE_BITS + ...      one bit per page: page (level, x, y) of a level's
//                                                pages_per_side² window is bit
//                                                b = virtual_mark_page_bit(level, x, y, pages_per_side),
//                                                bit (b % 32) of page-bit word b / 32
//   then, from word VIRTUAL_MARK_WORD_PAGE_BITS + virtual_mark_page_bit_words(levels, pages_per_side),
//   two words per page (page bit b: words 2b and 2b + 1 of them): the page's marked tiles, the page
//   cut into VIRTUAL_MARK_TILES_PER_SIDE² tiles (16² texels of a 128² page), tile (tx, ty) (ty from
//   the page's lower edge) bit (ty % 4) · 8 + tx of word 2b + ty / 4 (virtual_mark_tile_word): the
//   tiles the squares that marked the page reach, a texel wider (the filters gather 2 × 2 blocks
//   from even texels). A renderer may draw into a page only the casters over its marked tiles.
// Page (x, y) of level k covers light-space [u_virtual_origin[k].xy + (x, y) · page_ws, + page_ws)
// with page_ws = u_virtual_page_texels · u_virtual_texel0_ws · 2^k.
//
// The level a pixel asks for (virtual_pages.glsl: virtual_requested_texel_ws, virtual_level_for_texel; on
// the CPU adaptive::requested_texel_ws and adaptive::level_for_texel):
//   texel_ws = max(r / c, s · min_texel_px)      (the rule; u_mark_footprint_only: s · min_texel_px)
//   level    = clamp(floor(log2(texel_ws / u_virtual_texel0_ws)), 0, u_virtual_levels - 1)
// r the filter's world radius (u_radius_ws), c u_mark_c_texels, s the pixel's world footprint (its
// view depth · u_mark_footprint_per_depth), min_texel_px u_mark_min_texel_px. The pixel marks the
// pages of that level under the square of half-side r + u_mark_reach_texels texels of the level
// around its light-space point (the shading reads the square around the point moved along the
// surface normal: the reach is that offset, 0 where it reads none); a level whose window does not
// hold the point gives way to the next coarser one. PCSS's search square (pass 1) is marked as it is
// read: half-side the search radius, no reach.
//
// Texture units of the pages PCSS's second pass (VIRTUAL_MARK_PASS 2) searches for blockers through
// (virtual_pages.glsl; passes 0 and 1 read no texture): VIRTUAL_UNIT_POOL (the depth pool, r32f or
// a depth format, gathered and fetched without a comparison), VIRTUAL_UNIT_TABLE (the page tables,
// r32i: the pool slot of each page, -1 where not resident), VIRTUAL_UNIT_BOUNDS (each pool tile's
// depth bounds, read only where u_virtual_bounds).
#ifndef PENUMBRA_VIRTUAL_MARK_CONTRACT_H
#define PENUMBRA_VIRTUAL_MARK_CONTRACT_H

#ifdef __cplusplus
#include <cstddef>
#include <cstdint>

namespace penumbra::shadows::virtual_mark {
using uint = std::uint32_t;
// The block's GLSL types as plain floats (no GLM): a vec3 member is followed by a scalar, which
// std140 packs into its fourth component; mat4 is column-major, columns[c][r] (as GLSL and glm).
struct vec3 {
  float x = 0, y = 0, z = 0;
};
struct vec4 {
  float x = 0, y = 0, z = 0, w = 0;
};
struct mat4 {
  float columns[4][4] = {};
};
using bool32 = std::uint32_t;  // a GLSL bool in a block: 4 bytes, 0 or 1
#define PENUMBRA_VIRTUAL_CONSTANT(name, value) inline constexpr int name = value;
#define PENUMBRA_VIRTUAL_FUNCTION inline constexpr
#define PENUMBRA_VIRTUAL_ALIGN16 alignas(16)
#define PENUMBRA_VIRTUAL_UNIFORM_BLOCK(name, binding_point) struct alignas(16) name
#else
#define PENUMBRA_VIRTUAL_CONSTANT(name, value) const int name = value;
#define PENUMBRA_VIRTUAL_FUNCTION
#define PENUMBRA_VIRTUAL_ALIGN16
#define PENUMBRA_VIRTUAL_UNIFORM_BLOCK(name, binding_point) layout(std140, binding = binding_point) uniform name
#define bool32 bool
#endif

PENUMBRA_VIRTUAL_CONSTANT(VIRTUAL_MARK_MAX_LEVELS, 16)  // levels the buffer counts (the renderer's VIRTUAL_MAX_LEVELS)
PENUMBRA_VIRTUAL_CONSTANT(VIRTUAL_MARK_GROUP_SIZE, 8)   // a work group: 8 × 8 pixels
PENUMBRA_VIRTUAL_CONSTANT(VIRTUAL_MARK_BUFFER, 0)       // shader storage binding of the marks buffer
PENUMBRA_VIRTUAL_CONSTANT(VIRTUAL_MARK_IMAGE_SURFACE, 0)
PENUMBRA_VIRTUAL_CONSTANT(VIRTUAL_MARK_IMAGE_LEVELS, 1)
PENUMBRA_VIRTUAL_CONSTANT(VIRTUAL_MARK_IMAGE_RADII, 2)
// The marks buffer, in 32-bit words from its start.
PENUMBRA_VIRTUAL_CONSTANT(VIRTUAL_MARK_WORD_PIXELS_PER_LEVEL, 0)
PENUMBRA_VIRTUAL_CONSTANT(VIRTUAL_MARK_WORD_UNMARKED, 16)   // VIRTUAL_MARK_MAX_LEVELS
PENUMBRA_VIRTUAL_CONSTANT(VIRTUAL_MARK_WORD_PAGE_BITS, 17)  // VIRTUAL_MARK_MAX_LEVELS + 1
PENUMBRA_VIRTUAL_CONSTANT(VIRTUAL_MARK_TILES_PER_SIDE, 8)   // a page's marked tiles: 8 × 8, a 64-bit mask
// Texture units (the renderer's UNIT_VIRTUAL_* of shaders/shadow_contract.h).
PENUMBRA_VIRTUAL_CONSTANT(VIRTUAL_UNIT_POOL, 9)
PENUMBRA_VIRTUAL_CONSTANT(VIRTUAL_UNIT_TABLE, 10)
PENUMBRA_VIRTUAL_CONSTANT(VIRTUAL_UNIT_BOUNDS, 14)
// Uniform-buffer binding of the VirtualFrame block (the renderer's BLOCK_VIRTUAL_FRAME; its
// ShadowFrame block takes binding 0).
PENUMBRA_VIRTUAL_CONSTANT(VIRTUAL_FRAME_BLOCK, 1)

// One frame of the virtual shadow map, as every shader that reads its pages or marks them sees it.
// Layout rules: mat4 and vec4 (and arrays of them) start on 16 bytes, a vec3 is followed by a
// scalar, booleans are 4 bytes; the C++ offsets are checked against the driver's std140 offsets.
PENUMBRA_VIRTUAL_UNIFORM_BLOCK(VirtualFrame, VIRTUAL_FRAME_BLOCK) {
  PENUMBRA_VIRTUAL_ALIGN16 mat4 u_virtual_light_view;  // world → light space: rigid, the light along -z
  // xy: level k's window's lower corner in light space; zw: 0. A vec4 per level: std140 strides an
  // array of vec2 by 16 bytes anyway.
  PENUMBRA_VIRTUAL_ALIGN16 vec4 u_virtual_origin[VIRTUAL_MARK_MAX_LEVELS];
  PENUMBRA_VIRTUAL_ALIGN16 vec3 u_mark_camera_position;  // the camera the marking measures footprints from
  float u_mark_footprint_per_depth;  // perspective: a pixel's world size per unit of view depth; orthographic: its size
  PENUMBRA_VIRTUAL_ALIGN16 vec3 u_mark_camera_forward;   // unit view direction
  float u_mark_c_texels;             // c: texels under the filter's radius
  float u_mark_min_texel_px;         // the pixel floor: no texel finer than this many footprints
  float u_mark_reach_texels;         // a filter's square is marked this many texels of its level wider (the shading's normal offset)
  float u_virtual_texel0_ws;         // level 0's texel; level k's is u_virtual_texel0_ws · 2^k
  int u_virtual_page_texels;         // texels per page side
  int u_virtual_pages_per_side;      // pages per level window side
  int u_virtual_levels;              // clipmap levels, at most VIRTUAL_MARK_MAX_LEVELS
  int u_virtual_pool_pages;          // pool slots per side (slot s at (s % n, s / n)); pass 2 and the shading
  float u_virtual_near_ws;           // the light-space depth range the pages hold: depth = (-z - near) / (far - near)
  float u_virtual_far_ws;
  float u_virtual_tan_half_angle;    // PCSS: the sun's angular radius, as a tangent
  float u_virtual_search_scale;      // PCSS: the blocker search's radius over its geometric bound
  float u_virtual_min_penumbra_ws;   // PCSS: the smallest penumbra (world radius)
  float u_virtual_search_bias_texels;  // PCSS: the search's depth bias, texels of its level
  bool32 u_virtual_bounds;           // the tiles' depth bounds at VIRTUAL_UNIT_BOUNDS may be read
  bool32 u_virtual_search_receiver_plane;  // PCSS: the search tests each texel against the receiver's plane
  bool32 u_mark_perspective;         // perspective (else orthographic) camera
  bool32 u_mark_footprint_only;      // mark by the footprint alone (what engines' virtual maps do)
};

// The bit of page (x, y) of `level` among the page bits, for windows of pages_per_side² pages.
PENUMBRA_VIRTUAL_FUNCTION uint virtual_mark_page_bit(int level, int x, int y, int pages_per_side) {
  return uint((level * pages_per_side + y) * pages_per_side + x);
}

// The words of the page bits for `levels` levels of pages_per_side² pages; the tile words follow them.
PENUMBRA_VIRTUAL_FUNCTION uint virtual_mark_page_bit_words(int levels, int pages_per_side) {
  return (uint(levels) * uint(pages_per_side) * uint(pages_per_side) + 31u) / 32u;
}

// The word (from VIRTUAL_MARK_WORD_PAGE_BITS) holding tile row `tile_row` of the page of bit `bit`.
PENUMBRA_VIRTUAL_FUNCTION uint virtual_mark_tile_word(uint bit, int tile_row, int levels, int pages_per_side) {
  return virtual_mark_page_bit_words(levels, pages_per_side) + 2u * bit + uint(tile_row / 4);
}

#ifdef __cplusplus
// The words a marks buffer needs for `levels` levels of pages_per_side² pages: the counts, the page
// bits and two tile words per page.
inline constexpr std::size_t virtual_mark_buffer_words(int levels, int pages_per_side) {
  const std::size_t pages = static_cast<std::size_t>(levels) * static_cast<std::size_t>(pages_per_side) * static_cast<std::size_t>(pages_per_side);
  return static_cast<std::size_t>(VIRTUAL_MARK_WORD_PAGE_BITS) + virtual_mark_page_bit_words(levels, pages_per_side) + 2 * pages;
}
// The page of bit `bit` among the page bits: the inverse of virtual_mark_page_bit.
struct Page {
  int level = 0, x = 0, y = 0;
};
inline constexpr Page virtual_mark_page_of_bit(uint bit, int pages_per_side) {
  const auto n = static_cast<uint>(pages_per_side);
  return {static_cast<int>(bit / (n * n)), static_cast<int>(bit % n), static_cast<int>(bit / n % n)};
}
static_assert(VIRTUAL_MARK_WORD_UNMARKED == VIRTUAL_MARK_WORD_PIXELS_PER_LEVEL + VIRTUAL_MARK_MAX_LEVELS, "std430: a uint array, no padding");
static_assert(VIRTUAL_MARK_WORD_PAGE_BITS == VIRTUAL_MARK_WORD_UNMARKED + 1, "std430: a uint, then the page bits");
static_assert(sizeof(vec3) == 12 && sizeof(vec4) == 16 && sizeof(mat4) == 64, "the block's GLSL types");
static_assert(offsetof(VirtualFrame, u_virtual_origin) == 64 && offsetof(VirtualFrame, u_mark_camera_position) == 64 + 16 * VIRTUAL_MARK_MAX_LEVELS &&
                  offsetof(VirtualFrame, u_mark_footprint_per_depth) == offsetof(VirtualFrame, u_mark_camera_position) + 12,
              "std140: a vec4 array after the mat4, a vec3 followed by a scalar in its fourth component");
static_assert(offsetof(VirtualFrame, u_mark_footprint_only) == 64 + 16 * VIRTUAL_MARK_MAX_LEVELS + 2 * 16 + 16 * 4,
              "std140: the scalars packed, no padding between members");
static_assert(sizeof(VirtualFrame) == offsetof(VirtualFrame, u_mark_footprint_only) + 4 + 12, "the block's end padded to 16 bytes");
}  // namespace penumbra::shadows::virtual_mark
#else
#undef bool32
#endif
#undef PENUMBRA_VIRTUAL_CONSTANT
#undef PENUMBRA_VIRTUAL_FUNCTION
#undef PENUMBRA_VIRTUAL_ALIGN16
#undef PENUMBRA_VIRTUAL_UNIFORM_BLOCK

#endif  // PENUMBRA_VIRTUAL_MARK_CONTRACT_H
