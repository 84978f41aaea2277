// The contract between the renderer's C++ and its GLSL, read by both compilers: C++ includes it as
// "shaders/shadow_contract.h" (namespace penumbra::shadows::contract), GLSL through common.glsl
// and shading.vert. It names the texture units, the uniform-block binding, MAX_CASCADES, and the
// per-frame shadow data as one std140 uniform block that the renderer uploads once per frame
// (FrameResources::upload_frame). Uniforms not listed here belong to one technique or pass and are
// set per program, by locations resolved once at link (gl::Program).
//
// Layout rules kept by hand, checked by test_shader_contract against the driver's std140 offsets
// and by the renderer against GL_UNIFORM_BLOCK_DATA_SIZE when it links a program with the block:
// - mat4, vec4 and vec3 members start on 16 bytes (PENUMBRA_ALIGN16); a vec3 is followed by a
//   scalar, which std140 packs into its fourth component;
// - per-cascade scalars are one vec4 (component i = cascade i), not float[MAX_CASCADES], whose
//   std140 stride would be 16 bytes; GLSL reads them as u_cascade_res[i] all the same;
// - booleans are 4 bytes (bool32: bool in GLSL, std::uint32_t in C++).
#ifndef PENUMBRA_SHADOW_CONTRACT_H
#define PENUMBRA_SHADOW_CONTRACT_H

#ifdef __cplusplus
#include <cstdint>

#include <glm/glm.hpp>

namespace penumbra::shadows::contract {
using vec3 = glm::vec3;
using vec4 = glm::vec4;
using mat4 = glm::mat4;
using bool32 = std::uint32_t;
#define PENUMBRA_CONSTANT(name, value) inline constexpr int name = value;
#define PENUMBRA_ALIGN16 alignas(16)
#define PENUMBRA_UNIFORM_BLOCK(name, binding_point) struct alignas(16) name
#define PENUMBRA_STORAGE_BUFFER(name, binding_point) struct name
using uint = std::uint32_t;
#else
#define PENUMBRA_CONSTANT(name, value) const int name = value;
#define PENUMBRA_ALIGN16
#define PENUMBRA_UNIFORM_BLOCK(name, binding_point) layout(std140, binding = binding_point) uniform name
#define PENUMBRA_STORAGE_BUFFER(name, binding_point) layout(std430, binding = binding_point) buffer name
#define bool32 bool
#endif

// Cascades of one frame (one map per cascade in the shadow atlas).
PENUMBRA_CONSTANT(MAX_CASCADES, 4)

// Texture units.
PENUMBRA_CONSTANT(UNIT_SHADOW_CMP, 0)          // depth atlas, linear comparison (hardware 2x2 PCF)
PENUMBRA_CONSTANT(UNIT_SHADOW_CMP_NEAREST, 1)  // depth atlas, nearest comparison / gather
PENUMBRA_CONSTANT(UNIT_SHADOW_DEPTH, 2)        // depth atlas, raw depth (blocker search)
PENUMBRA_CONSTANT(UNIT_MOMENTS, 3)             // filtered moments (VSM, MSM, EVSM, ESM)
PENUMBRA_CONSTANT(UNIT_SCREEN_VISIBILITY, 4)   // shading pass: the screen-space post passes' result
PENUMBRA_CONSTANT(UNIT_GBUFFER_POSITION, 4)    // post passes: world xyz, signed eye depth
PENUMBRA_CONSTANT(UNIT_GBUFFER_LIGHT, 5)       // post passes: map uv, reference depth, light depth
PENUMBRA_CONSTANT(UNIT_DEPTH_MINMAX, 6)        // min-max depth pyramid of the atlas (PCSS bounds)
PENUMBRA_CONSTANT(UNIT_POST_INPUT, 7)          // post passes: the previous post pass's output
PENUMBRA_CONSTANT(UNIT_POST_INPUT_2, 8)        // post passes: a second input (site widths)
PENUMBRA_CONSTANT(UNIT_VIRTUAL_POOL, 9)            // virtual shadow map: the page pool (raw depth, texelFetch)
PENUMBRA_CONSTANT(UNIT_VIRTUAL_TABLE, 10)          // virtual shadow map: the page tables (slot per page, -1: none)
PENUMBRA_CONSTANT(UNIT_VIRTUAL_POOL_CMP, 11)       // virtual shadow map: the page pool, nearest depth comparison (gathers)
PENUMBRA_CONSTANT(UNIT_VIRTUAL_PCSS_RADII, 12)     // virtual shadow map, PCSS: each pixel's penumbra as the marking found it
PENUMBRA_CONSTANT(UNIT_VIRTUAL_MOMENTS, 13)        // virtual shadow map, VSM: the moments pool (t, t² + texel variance)
PENUMBRA_CONSTANT(VIRTUAL_MAX_LEVELS, 16)          // virtual shadow map: clipmap levels at most
PENUMBRA_CONSTANT(UNIT_VIRTUAL_BOUNDS, 14)         // virtual shadow map: each pool tile's depth bounds (virtual_bounds.comp)
PENUMBRA_CONSTANT(VIRTUAL_BOUNDS_TILE, 16)         // virtual shadow map: texels per side of a bounds tile (divides a page's side)

// Uniform-block binding points.
PENUMBRA_CONSTANT(BLOCK_SHADOW_FRAME, 0)
PENUMBRA_CONSTANT(BLOCK_VIRTUAL_FRAME, 1)  // the virtual shadow map's VirtualFrame (virtual_mark_contract.h's VIRTUAL_FRAME_BLOCK)

// What every shadow lookup of a frame needs: cameras, the light frame, the cascades, biases and the
// fixed filter radius. Members keep their uniform names, so GLSL reads them as before.
PENUMBRA_UNIFORM_BLOCK(ShadowFrame, BLOCK_SHADOW_FRAME) {
  PENUMBRA_ALIGN16 mat4 u_view_projection;   // camera
  PENUMBRA_ALIGN16 mat4 u_camera_view;
  PENUMBRA_ALIGN16 mat4 u_light_view;
  PENUMBRA_ALIGN16 mat4 u_cascade_view_projection[MAX_CASCADES];
  PENUMBRA_ALIGN16 vec4 u_cascade_region[MAX_CASCADES];  // atlas uv of the map's corner (xy), per-map uv (zw)
  PENUMBRA_ALIGN16 vec4 u_cascade_res;        // texels per side, component i = cascade i
  PENUMBRA_ALIGN16 vec4 u_cascade_extent_ws;  // directional: side of the map; spot: unfitted near-plane width
  PENUMBRA_ALIGN16 vec4 u_cascade_far_ws;     // camera view depth where cascade i ends
  PENUMBRA_ALIGN16 vec3 u_light_direction;    // direction light travels
  float u_light_near_ws;
  PENUMBRA_ALIGN16 vec3 u_light_position;     // spot
  float u_light_far_ws;
  PENUMBRA_ALIGN16 vec3 u_light_color;
  float u_light_s_xy;                         // fitting scale
  PENUMBRA_ALIGN16 vec3 u_camera_position;
  float u_light_tan_half_fov;                 // spot
  PENUMBRA_ALIGN16 vec3 u_camera_forward;
  float u_rpdb_max;                           // largest |d depth / d uv| trusted by the receiver-plane bias
  float u_spot_cos_outer;                     // spot cone
  float u_spot_cos_inner;
  float u_ambient;
  float u_normal_offset_texels;
  float u_depth_bias_texels;
  float u_cascade_blend;                      // blend band, fraction of a cascade's depth range
  float u_filter_radius;                      // the technique's fixed filter radius (filter_radius_uv)
  int u_cascade_count;
  bool32 u_light_perspective;
  bool32 u_receiver_plane_bias;
  bool32 u_filter_radius_world;               // u_filter_radius in world units (else texels)
  bool32 u_show_cascades;                     // tint by cascade (debug overlay)
};

// The PCSS requirement pass (pcss_requirement.comp) reduces the shading pass's per-pixel
// requirement into this std430 buffer, read back a frame later (Renderer::render): per cascade the
// largest 1 / r_uv (float bits: positive floats order like their bits) and pixel counts. One work
// group covers PCSS_REQUIREMENT_GROUP_PIXELS² pixels (16 × 16 invocations of 4 × 4 pixels each).
PENUMBRA_CONSTANT(BUFFER_PCSS_REQUIREMENT, 0)
PENUMBRA_CONSTANT(PCSS_REQUIREMENT_GROUP_PIXELS, 64)
// (GLSL declares the buffer only where PENUMBRA_PCSS_REQUIREMENT_RESULT is defined: a vertex
// stage may have no storage blocks at all.)
#if defined(__cplusplus) || defined(PENUMBRA_PCSS_REQUIREMENT_RESULT)
PENUMBRA_STORAGE_BUFFER(PcssRequirementResult, BUFFER_PCSS_REQUIREMENT) {
  uint max_inverse_uv[MAX_CASCADES];
  uint evaluated[MAX_CASCADES];
  uint clamped[MAX_CASCADES];
  uint above_max[MAX_CASCADES];
};
#endif

// A counting run of the shading pass (Renderer::count_shading_reads, read_count.glsl): each pixel
// shaded adds itself and its shadow lookup's texture instructions, texels and bytes to this std430
// buffer, spread over SHADOW_READ_SLOTS slots by pixel so that no 32-bit slot overflows; the CPU
// sums the slots.
PENUMBRA_CONSTANT(BUFFER_SHADOW_READS, 3)
PENUMBRA_CONSTANT(SHADOW_READ_SLOTS, 256)
#if defined(__cplusplus) || defined(COUNT_SHADOW_READS)
PENUMBRA_STORAGE_BUFFER(ShadowReadsResult, BUFFER_SHADOW_READS) {
  uint read_pixels[SHADOW_READ_SLOTS];
  uint read_instructions[SHADOW_READ_SLOTS];
  uint read_texels[SHADOW_READ_SLOTS];
  uint read_bytes[SHADOW_READ_SLOTS];
};
#endif

// The shading pass through a virtual shadow map (VIRTUAL_SHADOW_MAP) marks each pixel by where it
// found its pages: on the level it marked, on a coarser resident one (the pool could not hold
// its), or nowhere (lit); virtual_status.comp counts them into this buffer, read back after the pass
// (FrameInfo::virtual_map). A work group covers VIRTUAL_STATUS_GROUP_PIXELS² pixels.
PENUMBRA_CONSTANT(BUFFER_VIRTUAL_SHADING, 1)
PENUMBRA_CONSTANT(VIRTUAL_STATUS_GROUP_PIXELS, 64)
#if defined(__cplusplus) || defined(PENUMBRA_VIRTUAL_SHADING_RESULT)
PENUMBRA_STORAGE_BUFFER(VirtualShadingResult, BUFFER_VIRTUAL_SHADING) {
  uint at_level;
  uint coarser;
  uint none;
};
#endif

// virtual_bounds.comp: the tiles' bounds of the pages a virtual shadow map drew, written to image
// unit IMAGE_VIRTUAL_BOUNDS from the pool slots listed in storage buffer BUFFER_VIRTUAL_BOUNDS_SLOTS
// (ints); a work group covers VIRTUAL_BOUNDS_GROUP² tiles of one page.
PENUMBRA_CONSTANT(BUFFER_VIRTUAL_BOUNDS_SLOTS, 2)
PENUMBRA_CONSTANT(IMAGE_VIRTUAL_BOUNDS, 0)
PENUMBRA_CONSTANT(VIRTUAL_BOUNDS_GROUP, 8)

#ifdef __cplusplus
static_assert(sizeof(PcssRequirementResult) == 4 * MAX_CASCADES * sizeof(std::uint32_t), "std430: four uint arrays, no padding");
static_assert(sizeof(VirtualShadingResult) == 3 * sizeof(std::uint32_t), "std430: three uints");
static_assert(sizeof(ShadowReadsResult) == 4 * SHADOW_READ_SLOTS * sizeof(std::uint32_t), "std430: four uint arrays, no padding");
static_assert(MAX_CASCADES == 4, "per-cascade scalars are one vec4 each (u_cascade_res, ...)");
}  // namespace penumbra::shadows::contract
#else
#undef bool32
#endif
#undef PENUMBRA_CONSTANT
#undef PENUMBRA_ALIGN16
#undef PENUMBRA_UNIFORM_BLOCK
#undef PENUMBRA_STORAGE_BUFFER

#endif  // PENUMBRA_SHADOW_CONTRACT_H
