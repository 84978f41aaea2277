// A virtual shadow map's page: positions into the page's orthographic light clip space
// (shadows/virtual_shadow_map.cpp); the fragment shader is shadow_depth.frag's (depth only) or
// virtual_page_moments.frag's (depth and moments).
layout(location = 0) in vec3 a_position;

uniform mat4 u_model;
uniform mat4 u_clip_from_world;

out float v_page_depth;  // the depth t as the pages hold it, without the raster depth offset

void main() {
  gl_Position = u_clip_from_world * (u_model * vec4(a_position, 1.0));
  v_page_depth = gl_Position.z * 0.5 + 0.5;  // orthographic: w = 1
}
