// Camera pass: world position and normal for per-fragment shadow lookups.
// u_view_projection comes from the ShadowFrame block.
#include "shadow_contract.h"
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;

uniform mat4 u_model;
uniform mat3 u_normal_matrix;

out vec3 v_world;
// The screen-space techniques draw the scene twice and test depth for equality the second time.
invariant gl_Position;
out vec3 v_normal;

void main() {
  vec4 world = u_model * vec4(a_position, 1.0);
  v_world = world.xyz;
  v_normal = u_normal_matrix * a_normal;
  gl_Position = u_view_projection * world;
}
