// One axis of an exact box blur of the VSM moments: output texel i averages [i+0.5-r, i+0.5+r]
// with the two edge texels weighted by coverage (the same box as the grid PCF). One invocation
// slides the window along a whole line, so the cost does not depend on r; the running sum is
// Kahan-compensated so that long lines keep the precision the variance needs.
// The same blur serves every moments technique: the renderer defines MOMENTS_CHANNELS (1: ESM,
// 2: VSM, 4: MSM, EVSM) and MOMENTS_FORMAT (the image format, e.g. rgba16f); the default is VSM's.
// DIRECT_SUMS (EVSM) sums each window anew instead of sliding it, one texel per invocation (see
// below); the sliding blur runs one invocation per line.
layout(local_size_x = 64) in;

#if !defined(MOMENTS_CHANNELS)
#  define MOMENTS_CHANNELS 2
#  define MOMENTS_FORMAT rg32f
#endif
#if MOMENTS_CHANNELS == 4
#  define moments_t vec4
#  define MOMENTS_SWIZZLE rgba
#  define AS_VEC4(v) (v)
#elif MOMENTS_CHANNELS == 1
#  define moments_t float
#  define MOMENTS_SWIZZLE r
#  define AS_VEC4(v) vec4((v), 0.0, 0.0, 0.0)
#else
#  define moments_t vec2
#  define MOMENTS_SWIZZLE rg
#  define AS_VEC4(v) vec4((v), 0.0, 0.0)
#endif

#if defined(DIRECT_SUMS)
// The line in CHUNKS chunks, each summed once per work group (see main).
#  define CHUNKS 256
shared moments_t s_chunk[CHUNKS];
#endif

layout(binding = 0) uniform sampler2D u_source;
layout(binding = 0, MOMENTS_FORMAT) uniform writeonly image2D u_target;

uniform float u_radius_texels;
uniform int u_axis;      // 0: along x (one invocation per row), 1: along y
uniform ivec2 u_origin;  // the map's region in the atlas: u_size^2 texels from u_origin
uniform int u_size;

#if defined(COUNT_FETCHES_BINDING)
// The blur's work for tests (shadows/moments_blur.h): every texel fetched, counted.
layout(std430, binding = COUNT_FETCHES_BINDING) buffer FetchCount { uint u_fetches; };
#endif

// Texel i of the line (clamped to the map's edge); `line` indexes rows for axis 0, columns for axis 1.
moments_t fetch(int i, int line, int len) {
#if defined(COUNT_FETCHES_BINDING)
  atomicAdd(u_fetches, 1u);
#endif
  i = clamp(i, 0, len - 1);
  return texelFetch(u_source, u_origin + (u_axis == 0 ? ivec2(i, line) : ivec2(line, i)), 0).MOMENTS_SWIZZLE;
}

void store(int i, int line, moments_t v) {
  imageStore(u_target, u_origin + (u_axis == 0 ? ivec2(i, line) : ivec2(line, i)), AS_VEC4(v));
}

void main() {
  int len = u_size;
  int lines = u_size;
#if defined(DIRECT_SUMS)
  int line = int(gl_GlobalInvocationID.y);  // x: the texel along the line (see below)
#else
  int line = int(gl_GlobalInvocationID.x);
#endif
  if (line >= lines) return;

  float r = u_radius_texels;
  if (r <= 0.5) {  // the window lies inside one texel
#if defined(DIRECT_SUMS)
    int i = int(gl_GlobalInvocationID.x);
    if (i < len) store(i, line, fetch(i, line, len));
#else
    for (int i = 0; i < len; ++i) store(i, line, fetch(i, line, len));
#endif
    return;
  }
  // Window of texel i: [i + a, i + b]; full texels i+full_lo .. i+full_hi, partial ones at the ends.
  float a = 0.5 - r, b = 0.5 + r;
  int full_lo = int(ceil(a));
  int full_hi = int(floor(b)) - 1;
  float w_left = float(full_lo) - a;     // coverage of texel i + full_lo - 1
  float w_right = b - floor(b);          // coverage of texel i + full_hi + 1
  float norm = 1.0 / (2.0 * r);

#if defined(DIRECT_SUMS)
  // Each invocation sums the window of one texel: i = gl_GlobalInvocationID.x of line
  // gl_GlobalInvocationID.y (the renderer dispatches ceil(u_size / 64) x u_size groups; neighbouring
  // invocations read overlapping windows). A sliding sum keeps an error proportional to the largest
  // value that ever passed through it, which EVSM's warped moments (up to e^84 beside 1) turn into
  // streaks. One texel per invocation also keeps every invocation's loop short: llvmpipe ends an
  // invocation's loops after 65535 iterations in all, which a whole line of windows (len * 2r)
  // exceeds at 2048^2 and r = 16 texels.
  //
  // A wide window would make that len texels per invocation (len^2 per line: 20 s for one EVSM map
  // of 2048^2 at r = 1e6 on llvmpipe). So the 64 invocations of a group (all of one line) first sum
  // the line in CHUNKS chunks into shared memory, and a window wider than a few chunks adds the
  // whole chunks it holds and fetches only the texels at its ends: at most CHUNKS + 2 chunk lengths
  // per texel, bounded by the map and not by r. Still a sum of the window's own texels, no sliding.
  // `chunked` depends on r and the map only, so the barrier is reached by the whole group.
  int chunk = (len + CHUNKS - 1) / CHUNKS;
  bool chunked = full_hi - full_lo + 1 > 4 * chunk;
  if (chunked) {
    for (int k = int(gl_LocalInvocationID.x); k < CHUNKS; k += 64) {
      moments_t s = moments_t(0.0);
      int end = min((k + 1) * chunk, len);
      for (int j = k * chunk; j < end; ++j) s += fetch(j, line, len);
      s_chunk[k] = s;
    }
    memoryBarrierShared();
    barrier();
  }
  int i = int(gl_GlobalInvocationID.x);
  if (i >= len) return;
  int lo = i + full_lo, hi = i + full_hi;
  int first = clamp(lo, 0, len), last = clamp(hi, -1, len - 1);
  moments_t total = float(clamp(-lo, 0, hi - lo + 1)) * fetch(0, line, len) +
                    float(clamp(hi - (len - 1), 0, hi - lo + 1)) * fetch(len - 1, line, len);
  int k0 = (first + chunk - 1) / chunk, k1 = (last + 1) / chunk;  // the whole chunks k0 .. k1 - 1 in [first, last]
  if (chunked && k0 < k1) {
    for (int j = first; j < k0 * chunk; ++j) total += fetch(j, line, len);
    for (int k = k0; k < k1; ++k) total += s_chunk[k];
    for (int j = k1 * chunk; j <= last; ++j) total += fetch(j, line, len);
  } else {
    for (int j = first; j <= last; ++j) total += fetch(j, line, len);
  }
  total += w_left * fetch(lo - 1, line, len) + w_right * fetch(hi + 1, line, len);
  store(i, line, total * norm);
  return;
#endif

  precise moments_t sum = moments_t(0.0);
  precise moments_t comp = moments_t(0.0);
  for (int j = full_lo; j <= full_hi; ++j) {
    precise moments_t y = fetch(j, line, len) - comp;
    precise moments_t t = sum + y;
    comp = (t - sum) - y;
    sum = t;
  }
  for (int i = 0; i < len; ++i) {
    moments_t total = sum + w_left * fetch(i + full_lo - 1, line, len) + w_right * fetch(i + full_hi + 1, line, len);
    store(i, line, total * norm);
    precise moments_t y = (fetch(i + full_hi + 1, line, len) - fetch(i + full_lo, line, len)) - comp;
    precise moments_t t = sum + y;
    comp = (t - sum) - y;
    sum = t;
  }
}
