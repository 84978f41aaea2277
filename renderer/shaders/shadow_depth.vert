// Shadow-map pass: positions into the light's clip space (one cascade's); light-view depth for the
// moments. The light view, shared by every cascade, comes from the ShadowFrame block.
#include "shadow_contract.h"

layout(location = 0) in vec3 a_position;

uniform mat4 u_model;
uniform mat4 u_light_view_projection;

out float v_light_depth_ws;  // distance along the light's viewing axis

void main() {
  vec4 world = u_model * vec4(a_position, 1.0);
  v_light_depth_ws = -(u_light_view * world).z;
  gl_Position = u_light_view_projection * world;
}
