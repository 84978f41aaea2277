// Shared shadow-map state: samplers, light description, bias helpers.
// Spaces: `sc` = shadow-map coordinates (uv in [0,1]^2, depth in [0,1] window depth);
// `*_ws` = world units; light-view depth = distance along the light's viewing axis.

// The light frame, cascades, biases and the fixed filter radius of the frame come from the
// ShadowFrame uniform block (shadow_contract.h, shared with the C++ side).
#include "shadow_contract.h"
#include "read_count.glsl"

const float PI = 3.14159265358979;

layout(binding = UNIT_SHADOW_CMP) uniform sampler2DShadow u_shadow_cmp;                  // linear: hardware 2x2 comparison
layout(binding = UNIT_SHADOW_CMP_NEAREST) uniform sampler2DShadow u_shadow_cmp_nearest;  // nearest comparison / gather
layout(binding = UNIT_SHADOW_DEPTH) uniform sampler2D u_shadow_depth;                    // raw depth (blocker search)
layout(binding = UNIT_MOMENTS) uniform sampler2D u_moments;                              // filtered moments (linear depth)

uniform vec2 u_poisson[64];         // unit-disk taps, the outermost at radius 1

#if !defined(PENUMBRA_COMPUTE)
// The screen-space techniques' per-pixel result, read by the shading pass.
layout(binding = UNIT_SCREEN_VISIBILITY) uniform sampler2D u_screen_visibility;
#endif

// The map being sampled (one cascade, or the only map), set by the shading pass before a
// technique runs. Maps live in an atlas: a region of g_shadow_res^2 texels surrounded by a guard
// band of at least two texels cleared to the far depth (lit), so that every lookup clamped into
// the band behaves like a lit border, whatever the neighbouring regions hold.
float g_shadow_res = 1.0;       // texels per side of the map
float g_light_extent_ws = 1.0;  // directional: side of the map; spot: unfitted near-plane width
vec4 g_region = vec4(0.0, 0.0, 1.0, 1.0);  // atlas uv of the map's corner (xy) and per map uv (zw)

// The maps of this frame (u_cascade_* in ShadowFrame): one per cascade (a spot light or an
// uncascaded frame has one). All cascades share the light view and its depth range; they differ in
// the xy window, the resolution and the atlas region. use_cascade(i) points the globals above at
// cascade i.
void use_cascade(int i) {
  g_shadow_res = u_cascade_res[i];
  g_region = u_cascade_region[i];
  g_light_extent_ws = u_cascade_extent_ws[i];
}

// Atlas uv of map uv `uv`; lookups beyond the map are clamped into its guard band.
vec2 atlas_uv(vec2 uv) {
  float band = 1.0 / g_shadow_res;
  return g_region.xy + clamp(uv, vec2(-band), vec2(1.0 + band)) * g_region.zw;
}

// Shadow-map uv per world unit at light-view depth `depth_ws`.
float uv_per_ws(float depth_ws) {
  if (!u_light_perspective) return 1.0 / g_light_extent_ws;
  return u_light_s_xy / (2.0 * max(depth_ws, 1e-6) * u_light_tan_half_fov);
}

// Light-view depth (world units) of a stored window depth `d`.
float linear_depth_ws(float d) {
  if (!u_light_perspective) return mix(u_light_near_ws, u_light_far_ws, d);
  float n = u_light_near_ws, f = u_light_far_ws;
  float z_ndc = 2.0 * d - 1.0;
  return 2.0 * n * f / (f + n - z_ndc * (f - n));
}

#if !defined(PENUMBRA_COMPUTE)  // screen-space derivatives exist only in fragment shaders
// d(depth)/d(uv) of the receiver plane, from screen-space derivatives; zero where undefined.
vec2 receiver_plane_gradient(vec3 sc) {
  if (!u_receiver_plane_bias) return vec2(0.0);
  vec3 dx = dFdx(sc);
  vec3 dy = dFdy(sc);
  float det = dx.x * dy.y - dx.y * dy.x;
  if (abs(det) < 1e-20) return vec2(0.0);
  vec2 g = vec2(dy.y * dx.z - dx.y * dy.z, dx.x * dy.z - dy.x * dx.z) / det;
  float len = length(g);
  return len > u_rpdb_max ? g * (u_rpdb_max / len) : g;
}
#endif

// The technique's fixed filter radius (PCF, RPCF; TechniqueEntry::filter_radius), as the user
// gave it (u_filter_radius, u_filter_radius_world): in texels of the map being sampled, or in
// world units at the receiver.
// The filter radius in uv and in texels of the current map, at light-view depth `depth_ws`.
float filter_radius_uv(float depth_ws) {
  return u_filter_radius_world ? u_filter_radius * uv_per_ws(depth_ws) : u_filter_radius / g_shadow_res;
}
float filter_radius_texels(float depth_ws) {
  return u_filter_radius_world ? u_filter_radius * uv_per_ws(depth_ws) * g_shadow_res : u_filter_radius;
}

// Normalized linear light depth in [0, 1] of light-view depth `depth_ws` (the moments' depth).
float normalized_light_depth(float depth_ws) {
  return clamp((depth_ws - u_light_near_ws) / (u_light_far_ws - u_light_near_ws), 0.0, 1.0);
}

// Window-depth change per world unit of light-view depth at `depth_ws`.
float depth_per_ws(float depth_ws) {
  float n = u_light_near_ws, f = u_light_far_ws;
  if (!u_light_perspective) return 1.0 / (f - n);
  return f * n / ((f - n) * depth_ws * depth_ws);
}

// Constant receiver offset in window depth, set once per fragment by the shading pass: covers
// the rounding between the map's rasterized depth and the receiver's recomputed depth.
float g_constant_bias = 0.0;

// Receiver depth to compare against at `sc.xy + offset_uv`, clamped into the map's depth range.
float reference_depth(vec3 sc, vec2 offset_uv, vec2 gradient) {
  return clamp(sc.z + dot(offset_uv, gradient) - g_constant_bias, 0.0, 1.0);
}

// Interleaved gradient noise (Jimenez 2014): a per-pixel value in [0, 1).
float interleaved_gradient_noise(vec2 pixel) {
  return fract(52.9829189 * fract(dot(pixel, vec2(0.06711056, 0.00583715))));
}

#if !defined(PENUMBRA_COMPUTE)
// Rotation of the Poisson disk for this pixel (identity when rotation is off).
mat2 poisson_rotation(bool rotate) {
  if (!rotate) return mat2(1.0);
  float a = 2.0 * PI * interleaved_gradient_noise(gl_FragCoord.xy);
  float c = cos(a), s = sin(a);
  return mat2(c, s, -s, c);
}
#endif
