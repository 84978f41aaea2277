// MSM moments pass: (z, z^2, z^3, z^4) of the light-view depth mapped linearly to z in [-1, 1].
#include "common.glsl"
#include "shadow_msm.glsl"

in float v_light_depth_ws;

layout(location = 0) out vec4 o_moments;

void main() {
  float t = clamp((v_light_depth_ws - u_light_near_ws) / (u_light_far_ws - u_light_near_ws), 0.0, 1.0);
  o_moments = msm_moments(2.0 * t - 1.0);
}
