// Moments pass of a filtered-moments technique (VSM, MSM, EVSM, ...): writes the moments its
// shadow_<name>.glsl defines (technique_moments) of the normalized linear light depth t.
#include "common.glsl"
#include "techniques.glsl"

in float v_light_depth_ws;

layout(location = 0) out vec4 o_moments;

void main() {
  float t = clamp((v_light_depth_ws - u_light_near_ws) / (u_light_far_ws - u_light_near_ws), 0.0, 1.0);
  o_moments = technique_moments(t);
}
