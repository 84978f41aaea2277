// Camera pass: Lambert shading with the technique's visibility (TECHNIQUE_* and KERNEL_GRID
// are defined by the renderer). Writes linear radiance (encoded to sRGB by the framebuffer), the
// light visibility in [0, 1] (shadow test * spot cone) and, with PCSS_REQUIREMENT, the per-pixel
// resolution requirement the adaptive rule reduces on the GPU (pcss_requirement.comp).
// Screen-space techniques run it twice: with SCREEN_SPACE_GBUFFER it writes the G-buffer (world
// position and eye depth signed by the input test before the spot cone, shadow-map
// coordinates); the second time
// it takes the visibility the post passes left in u_screen_visibility (SCREEN_SPACE_VISIBILITY),
// or, for erosion, PCF scaled by the eroded penumbra width found there (TECHNIQUE_EROSION).
// Screen-space techniques use one map (no cascades).
#include "common.glsl"
#include "shadow_hard.glsl"
#include "shadow_pcf.glsl"
#include "shadow_pcss.glsl"
#include "shadow_vsm.glsl"
#include "shadow_rbsm.glsl"
#include "shadow_msm.glsl"
#include "shadow_evsm.glsl"

in vec3 v_world;
in vec3 v_normal;

uniform float u_cascade_far_ws[MAX_CASCADES];  // camera view depth where cascade i ends
uniform float u_cascade_blend;                 // blend band, fraction of a cascade's depth range
uniform bool u_show_cascades;                  // tint by cascade (debug overlay)
uniform mat4 u_camera_view;

uniform mat4 u_light_view;
uniform vec3 u_light_direction;   // direction light travels
uniform vec3 u_light_position;    // spot
uniform float u_spot_cos_outer;   // spot cone
uniform float u_spot_cos_inner;
uniform vec3 u_light_color;
uniform float u_ambient;
uniform vec3 u_albedo;
uniform float u_normal_offset_texels;
uniform float u_depth_bias_texels;

uniform int u_taps;
uniform bool u_rotate;
uniform int u_max_grid_taps;
uniform int u_blocker_taps;

layout(binding = 4) uniform sampler2D u_screen_visibility;  // screen-space techniques, by pixel

#if defined(SCREEN_SPACE_GBUFFER)
uniform vec3 u_camera_position;
uniform vec3 u_camera_forward;
layout(location = 0) out vec4 o_position;  // world xyz, eye depth signed by the input test (+ lit, - shadowed)
layout(location = 1) out vec4 o_light;     // shadow-map uv, biased reference depth, light-view depth (world)
#else
layout(location = 0) out vec4 o_color;
layout(location = 1) out float o_visibility;
#endif
#if defined(PCSS_REQUIREMENT)
layout(location = 2) out vec2 o_requirement;  // (1 / filter radius in map uv, cascade + 0.5 if clamped)
#endif

vec3 g_sc = vec3(0.0);  // map coordinates of the last cascade_visibility call (G-buffer pass)

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
  visibility = texelFetch(u_screen_visibility, ivec2(gl_FragCoord.xy), 0).r;
#elif defined(TECHNIQUE_EROSION)
  float eroded_ws = texelFetch(u_screen_visibility, ivec2(gl_FragCoord.xy), 0).r;
  visibility = eroded_ws > 0.0 ? pcf_poisson(sc, gradient, 0.5 * eroded_ws * uv_per_ws(depth_ws), u_taps, poisson_rotation(u_rotate))
                               : shadow_hard(sc);
#elif defined(TECHNIQUE_HARD)
  visibility = shadow_hard(sc);
#elif defined(TECHNIQUE_PCF)
  float radius_uv = filter_radius_uv(depth_ws);
#  if defined(KERNEL_GRID)
  visibility = pcf_grid(sc, gradient, radius_uv * g_shadow_res, u_max_grid_taps);
#  else
  visibility = pcf_poisson(sc, gradient, radius_uv, u_taps, poisson_rotation(u_rotate));
#  endif
#elif defined(TECHNIQUE_PCSS)
#  if defined(KERNEL_GRID)
  const bool grid = true;
#  else
  const bool grid = false;
#  endif
  visibility = shadow_pcss(sc, gradient, depth_ws, u_blocker_taps, u_taps, grid, u_max_grid_taps,
                           poisson_rotation(true), filter_uv);
#elif defined(TECHNIQUE_VSM)
  float t = clamp((depth_ws - u_light_near_ws) / (u_light_far_ws - u_light_near_ws), 0.0, 1.0);
  visibility = shadow_vsm(sc.xy, t);
#elif defined(TECHNIQUE_RBSM)
  visibility = shadow_rbsm(sc, gradient);
#elif defined(TECHNIQUE_RPCF)
  float rpcf_radius_texels = filter_radius_texels(depth_ws);
  visibility = shadow_rpcf(sc, gradient, rpcf_radius_texels, u_rpcf_max_grid_taps);
#elif defined(TECHNIQUE_MSM)
  float t = clamp((depth_ws - u_light_near_ws) / (u_light_far_ws - u_light_near_ws), 0.0, 1.0);
  visibility = shadow_msm(sc.xy, t);
#elif defined(TECHNIQUE_EVSM)
  float t = clamp((depth_ws - u_light_near_ws) / (u_light_far_ws - u_light_near_ws), 0.0, 1.0);
  visibility = shadow_evsm(sc.xy, t);
#else
#  error "no TECHNIQUE_* defined"
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
}
