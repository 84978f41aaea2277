// A virtual shadow map's page with moments (shadows/virtual_shadow_map.h, Content::
// depth_and_moments): the rasterizer writes depth, and the fragment the variance shadow map's
// moments of the depth t as the pages hold it (linear from the view's near to its far depth: the
// page's projection is orthographic; without the raster depth offset, as the maps' moments),
// t and t² plus the variance of t over the texel from its screen derivatives, as the maps' moments
// pass does (shadow_vsm.glsl).
in float v_page_depth;

layout(location = 0) out vec4 o_moments;

void main() {
  const float t = clamp(v_page_depth, 0.0, 1.0);
  const float dx = dFdx(t), dy = dFdy(t);
  o_moments = vec4(t, t * t + 0.25 * (dx * dx + dy * dy), 0.0, 0.0);
}
