// Camera pass: Lambert shading with the technique's visibility. The renderer defines the
// technique's TECHNIQUE_* (and variant defines such as KERNEL_GRID); technique_visibility() comes
// from that technique's shadow_<name>.glsl. Writes linear radiance (encoded to sRGB by the
// framebuffer), the light visibility in [0, 1] (shadow test * spot cone) and, with
// PCSS_REQUIREMENT, the per-pixel resolution requirement the adaptive rule reduces on the GPU
// (pcss_requirement.comp).
// Screen-space techniques run it twice: with SCREEN_SPACE_GBUFFER it writes the G-buffer (world
// position and eye depth signed by the input test before the spot cone, shadow-map coordinates);
// the second time it takes the visibility the post passes left in u_screen_visibility
// (SCREEN_SPACE_VISIBILITY), or, for erosion, PCF over the eroded penumbra width found there.
// Screen-space techniques use one map (no cascades).
#include "common.glsl"
// Every technique's shadow_<name>.glsl (generated from renderer/shaders/ by CMake); the one whose
// TECHNIQUE_* is defined provides technique_visibility().
#include "techniques.glsl"

in vec3 v_world;
in vec3 v_normal;

#if defined(COUNT_SHADOW_READS)
// A counting run redraws the frame's surfaces over their own depth (Renderer::count_shading_reads):
// only the fragment each pixel kept runs, once, as on a GPU whose early depth test culls the rest.
layout(early_fragment_tests) in;
#endif

uniform vec3 u_albedo;  // per object; the frame's light, cameras and cascades are in ShadowFrame


#if defined(SCREEN_SPACE_GBUFFER)
layout(location = 0) out vec4 o_position;  // world xyz, eye depth signed by the input test (+ lit, - shadowed)
layout(location = 1) out vec4 o_light;     // shadow-map uv, biased reference depth, light-view depth (world)
#else
layout(location = 0) out vec4 o_color;
layout(location = 1) out float o_visibility;
#endif
#if defined(PCSS_REQUIREMENT)
layout(location = 2) out vec2 o_requirement;  // (1 / filter radius in map uv, cascade + 0.5 if clamped)
#endif
#if defined(VIRTUAL_SHADOW_MAP)
// Where the pixel found its pages (virtual_status.comp counts them): 1 on the level it marked, 2 on a
// coarser resident one, 3 none (lit); 0 (the clear) where no surface is.
layout(location = 2) out uint o_virtual_status;
#endif

vec3 g_sc = vec3(0.0);  // map coordinates of the last cascade_visibility call (G-buffer pass)

#if defined(VIRTUAL_SHADOW_MAP)
#include "virtual_pages.glsl"

// Box PCF of world radius `radius_ws` through the sun's virtual shadow map: on the level this
// pixel's pages were marked on (the request of virtual_mark.comp, the first level at or above it whose
// window holds the point), with the normal offset and constant bias in that level's texels and the
// receiver plane `gradient` (normalized depth per world unit across the light). Where the pool
// could not hold a page, the next coarser resident level answers; where none does, the pixel is
// lit (o_virtual_status says which). VSM: the box-filtered moments of the same square and
// Chebyshev's bound for the receiver's own depth (as the maps' VSM: no bias, the normal offset
// moves the lookup only).
float virtual_filter(vec3 n, float sin_angle, vec2 gradient, float radius_ws) {
  const vec3 receiver = virtual_light_point(v_world);
  const vec2 xy = receiver.xy;
  int marked = virtual_level_for_texel(virtual_requested_texel_ws(v_world, radius_ws));
  while (marked < u_virtual_levels - 1 && !virtual_in_window(marked, xy)) ++marked;
  for (int k = marked; k < u_virtual_levels; ++k) {
    const float texel = virtual_texel_ws(k);
    const vec3 lp = virtual_light_point(v_world + n * (u_normal_offset_texels * texel * sin_angle));
    const float bias = u_depth_bias_texels * texel / (u_virtual_far_ws - u_virtual_near_ws);
    bool found;
#if defined(TECHNIQUE_VSM)
    const float v = vsm_visibility(virtual_moments_box(k, lp.xy, radius_ws, found), receiver.z);
#else
    const float v = virtual_pcf_box(k, lp.xy, lp.z - bias, gradient, radius_ws, found);
#endif
    if (found) {
      o_virtual_status = k == marked ? 1u : 2u;
      return v;
    }
  }
  o_virtual_status = 3u;
  return 1.0;
}

#if defined(TECHNIQUE_PCSS)
// PCSS: the penumbra of this pixel's surface as the marking's blocker search found it (virtual_mark.comp,
// the same pixel of the position pass whose depth this pass reuses), so the search runs once a
// frame and the filter reads the pages that penumbra marked. 0: nothing in front; -1: no level
// held the search.
layout(binding = UNIT_VIRTUAL_PCSS_RADII) uniform sampler2D u_virtual_pcss_radii;
#endif

// The technique's visibility through the pages: box PCF (or VSM's box-filtered moments) of the
// fixed world radius, or PCSS's box filter of the penumbra its blocker search found.
float virtual_visibility(vec3 n, float sin_angle, vec2 gradient) {
#if defined(TECHNIQUE_PCSS)
  const float radius_ws = COUNTED(1, 4, texelFetch(u_virtual_pcss_radii, ivec2(gl_FragCoord.xy), 0)).r;
  if (radius_ws < 0.0) {
    o_virtual_status = 3u;  // no level held the search
    return 1.0;
  }
  if (radius_ws == 0.0) {
    o_virtual_status = 1u;  // nothing in front: lit, as the search says
    return 1.0;
  }
  return virtual_filter(n, sin_angle, gradient, radius_ws);
#else
  return virtual_filter(n, sin_angle, gradient, u_filter_radius);  // world units: the plan refuses texels
#endif
}

// The receiver plane in the virtual map's light space (virtual_plane_gradient) from screen-space
// derivatives (uniform control flow).
vec2 virtual_receiver_gradient() {
  if (!u_receiver_plane_bias) return vec2(0.0);
  const vec3 l = virtual_light_point(v_world);
  return virtual_plane_gradient(dFdx(l), dFdy(l));
}
#endif

// Visibility from cascade i. `gradient0` is the receiver-plane gradient in cascade 0's uv; the
// cascades' uv differ by a scale only (same light view), so it carries over.
float cascade_visibility(int i, vec3 n, float sin_angle, float depth_ws, vec2 gradient0, out float filter_uv) {
  use_cascade(i);
  filter_uv = 0.0;
  float texel_ws = 1.0 / (uv_per_ws(depth_ws) * g_shadow_res);
  vec3 lookup = v_world + n * (u_normal_offset_texels * texel_ws * sin_angle);
  vec4 clip = u_cascade_view_projection[i] * vec4(lookup, 1.0);
  vec3 sc = clip.xyz / clip.w * 0.5 + 0.5;
  vec2 gradient = gradient0 * (g_light_extent_ws / u_cascade_extent_ws[0]);
  g_constant_bias = u_depth_bias_texels * texel_ws * depth_per_ws(depth_ws);
  g_sc = sc;

  float visibility;
#if defined(SCREEN_SPACE_VISIBILITY)
  visibility = COUNTED(1, 8, texelFetch(u_screen_visibility, ivec2(gl_FragCoord.xy), 0)).r;  // EDTSM, EDTSSM: the post passes' result
#else
  visibility = technique_visibility(sc, gradient, depth_ws, filter_uv);
#endif
  return clamp(visibility, 0.0, 1.0);  // sums of weights may overshoot by an ulp
}

void main() {
  vec3 n = normalize(v_normal);
  if (!gl_FrontFacing) n = -n;
  vec3 to_light = u_light_perspective ? normalize(u_light_position - v_world) : -u_light_direction;
  float n_dot_l = dot(n, to_light);
  float sin_angle = sqrt(clamp(1.0 - n_dot_l * n_dot_l, 0.0, 1.0));
  float depth_ws = -(u_light_view * vec4(v_world, 1.0)).z;

#if defined(VIRTUAL_SHADOW_MAP)
  float visibility = clamp(virtual_visibility(n, sin_angle, virtual_receiver_gradient()), 0.0, 1.0);
  const int cascade = 0;
#else
  // Receiver-plane gradient in cascade 0's uv, in uniform control flow (derivatives are valid).
  use_cascade(0);
  float texel0_ws = 1.0 / (uv_per_ws(depth_ws) * g_shadow_res);
  vec4 clip0 = u_cascade_view_projection[0] * vec4(v_world + n * (u_normal_offset_texels * texel0_ws * sin_angle), 1.0);
  vec2 gradient0 = receiver_plane_gradient(clip0.xyz / clip0.w * 0.5 + 0.5);

  // Cascade by camera depth; inside the blend band at a cascade's far end, mix with the next.
  float view_depth = -(u_camera_view * vec4(v_world, 1.0)).z;
  int cascade = 0;
  while (cascade < u_cascade_count - 1 && view_depth > u_cascade_far_ws[cascade]) ++cascade;
  float filter_uv;
  float visibility = cascade_visibility(cascade, n, sin_angle, depth_ws, gradient0, filter_uv);
  float requirement = filter_uv > 0.0 ? 1.0 / filter_uv : 0.0;
  bool clamped = filter_uv > 0.0 && g_pcss_clamped;
  if (cascade < u_cascade_count - 1) {
    float begin = cascade == 0 ? 0.0 : u_cascade_far_ws[cascade - 1];
    float band = u_cascade_blend * (u_cascade_far_ws[cascade] - begin);
    float t = band > 0.0 ? (view_depth - (u_cascade_far_ws[cascade] - band)) / band : -1.0;
    if (t > 0.0) {
      float next_filter_uv;
      float next = cascade_visibility(cascade + 1, n, sin_angle, depth_ws, gradient0, next_filter_uv);
      visibility = mix(visibility, next, clamp(t, 0.0, 1.0));
    }
  }
#endif

#if defined(SCREEN_SPACE_GBUFFER)
  float eye_z = max(dot(v_world - u_camera_position, u_camera_forward), 1e-6);
  o_position = vec4(v_world, visibility > 0.5 ? eye_z : -eye_z);
  o_light = vec4(g_sc.xy, g_sc.z - g_constant_bias, depth_ws);
  return;
#endif
  if (u_light_perspective) {
    float cos_axis = dot(-to_light, u_light_direction);
    visibility *= smoothstep(u_spot_cos_outer, u_spot_cos_inner, cos_axis);
  }
  float direct = max(n_dot_l, 0.0) * visibility;
  vec3 radiance = u_albedo * u_light_color * (u_ambient + (1.0 - u_ambient) * direct);
  if (u_show_cascades) {
    const vec3 tint[MAX_CASCADES] = vec3[](vec3(1.0, 0.55, 0.55), vec3(0.55, 1.0, 0.55), vec3(0.55, 0.55, 1.0), vec3(1.0, 1.0, 0.5));
    radiance *= tint[cascade];
  }
#if !defined(SCREEN_SPACE_GBUFFER)
  o_color = vec4(radiance, 1.0);
  o_visibility = visibility;
#endif
#if defined(PCSS_REQUIREMENT)
  o_requirement = vec2(requirement, float(cascade) + (clamped ? 0.5 : 0.0));
#endif
#if defined(COUNT_SHADOW_READS)
  const uint slot = (uint(gl_FragCoord.x) + 17u * uint(gl_FragCoord.y)) % uint(SHADOW_READ_SLOTS);
  atomicAdd(read_pixels[slot], 1u);
  atomicAdd(read_instructions[slot], g_read_instructions);
  atomicAdd(read_texels[slot], g_read_texels);
  atomicAdd(read_bytes[slot], g_read_bytes);
#endif
}
