// VSM moments of normalized linear light depth t: (t, t^2 + the variance of t over the texel,
// estimated from its screen derivatives as Donnelly & Lauritzen suggest).
in float v_light_depth_ws;

uniform float u_light_near_ws;
uniform float u_light_far_ws;

layout(location = 0) out vec2 o_moments;

void main() {
  float t = clamp((v_light_depth_ws - u_light_near_ws) / (u_light_far_ws - u_light_near_ws), 0.0, 1.0);
  float dx = dFdx(t), dy = dFdy(t);
  o_moments = vec2(t, t * t + 0.25 * (dx * dx + dy * dy));
}
