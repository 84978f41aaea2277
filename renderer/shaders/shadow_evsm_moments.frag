// EVSM moments pass: both exponential warps of the light-view depth and their squares.
#define EVSM_MOMENTS_PASS 1
#include "common.glsl"
#include "shadow_evsm.glsl"

in float v_light_depth_ws;

layout(location = 0) out vec4 o_moments;

void main() {
  float t = clamp((v_light_depth_ws - u_light_near_ws) / (u_light_far_ws - u_light_near_ws), 0.0, 1.0);
  o_moments = evsm_moments(t);
}
