// Occluder pass: the occluder polygon (stimulus px, canonical frame) into the shadow map's clip
// space; depth 0 (the light sees the occluder in front of the receiver at depth 0.5).
layout(location = 0) in vec2 a_position_px;

uniform vec2 u_map_origin_px;  // canonical position of the shadow map's lower-left corner
uniform float u_map_extent_px; // side of the shadow map in stimulus px (texels * artifact_px)

void main() {
  vec2 ndc = (a_position_px - u_map_origin_px) / u_map_extent_px * 2.0 - 1.0;
  gl_Position = vec4(ndc, -1.0, 1.0);
}
