// Shared state of the screen-space post passes (EDTSM, EDTSSM, erosion): the G-buffer written by
// the first camera pass and the camera's metric. Pixel coordinates are GL's (row 0 at the bottom).
//
// G-buffer texel g = (world xyz, signed eye depth): |g.w| is the distance along the viewing
// direction, positive where the input shadow test says lit, negative where shadowed, and 0 where
// nothing was drawn. One fetch gives every post pass the position, the depth and the input.

#include "shadow_contract.h"

layout(binding = UNIT_GBUFFER_POSITION) uniform sampler2D u_gbuffer_position;  // world xyz, signed eye depth
layout(binding = UNIT_GBUFFER_LIGHT) uniform sampler2D u_gbuffer_light;          // shadow-map uv, biased reference depth, light-view depth (world)

uniform bool u_camera_perspective;
uniform float u_px_scale;          // perspective: z_screen * height_px; orthographic: height_px / view height
uniform float u_depth_threshold;   // largest relative eye-depth difference within one surface

vec4 gbuffer(ivec2 p) {
  return texelFetch(u_gbuffer_position, p, 0);
}

bool covered(vec4 g) {
  return g.w != 0.0;
}

// Distance along the viewing direction (world units).
float eye_depth(vec4 g) {
  return abs(g.w);
}

// The input (hard) visibility, 0 or 1.
float input_visibility(vec4 g) {
  return g.w > 0.0 ? 1.0 : 0.0;
}

// Screen pixels per world unit at eye depth z (Macedo & Apolinario eq. 2-3: w z_screen / z_eye).
float px_per_ws(float z_eye) {
  return u_camera_perspective ? u_px_scale / max(z_eye, 1e-6) : u_px_scale;
}

// Whether two eye depths belong to one surface (the edge-aware test of every pass).
bool same_surface(float z_a, float z_b) {
  return abs(z_a - z_b) <= u_depth_threshold * max(min(z_a, z_b), 1e-6);
}
