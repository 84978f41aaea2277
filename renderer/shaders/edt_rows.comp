// Exact EDT, pass 2 of 2 (Meijster, Roerdink & Hesselink 2000, phase 2; the lower envelope of
// Felzenszwalb & Huttenlocher in integer form): along each row, the lower envelope of the
// parabolas f_i(x) = (x - i)^2 + g(i)^2, where g(i) is the column distance from pass 1. All
// arithmetic is on integers (images up to 16384 px per side keep every term below 2^31), so the
// squared distance is exact. One invocation per row; the envelope's stack (s, t) lives in the
// output image itself: slot q is read before slot u >= q is overwritten by the result.
layout(local_size_x = 64) in;

layout(binding = 1, r32i) uniform readonly iimage2D u_column_site;
layout(binding = 2, rg32i) uniform coherent iimage2D u_nearest;  // out: nearest site (x, y) or (-1, -1)
layout(binding = 3, r32i) uniform writeonly iimage2D u_distance_sq;  // out: squared distance or -1

int g_inf;  // column distance of a column without a site: larger than any real distance

// Column distance g(i) of column i on row y.
int column_distance(int i, int y) {
  int site_row = imageLoad(u_column_site, ivec2(i, y)).r;
  return site_row < 0 ? g_inf : abs(y - site_row);
}

// floor(a / b) for b > 0 (GLSL integer division truncates toward zero).
int floor_div(int a, int b) {
  return a >= 0 ? a / b : -((-a + b - 1) / b);
}

void main() {
  ivec2 size = imageSize(u_column_site);
  int y = int(gl_GlobalInvocationID.x);
  if (y >= size.y) return;
  int m = size.x;
  g_inf = size.x + size.y;

  // Forward: stack of (site column s, first x where s is the envelope's minimum t).
  int q = 0;
  imageStore(u_nearest, ivec2(0, y), ivec4(0, 0, 0, 0));
  for (int u = 1; u < m; ++u) {
    int gu = column_distance(u, y);
    while (q >= 0) {
      ivec2 st = imageLoad(u_nearest, ivec2(q, y)).xy;
      int gs = column_distance(st.x, y);
      int ds = st.y - st.x, du = st.y - u;
      if (ds * ds + gs * gs > du * du + gu * gu) --q;  // u is strictly lower at t: s never wins
      else break;
    }
    if (q < 0) {
      q = 0;
      imageStore(u_nearest, ivec2(0, y), ivec4(u, 0, 0, 0));
    } else {
      int s = imageLoad(u_nearest, ivec2(q, y)).x;
      int gs = column_distance(s, y);
      // First x where u is strictly lower than s: 1 + floor((u^2 - s^2 + gu^2 - gs^2) / (2 (u - s))).
      int w = 1 + floor_div(u * u - s * s + gu * gu - gs * gs, 2 * (u - s));
      if (w < m) {
        ++q;
        imageStore(u_nearest, ivec2(q, y), ivec4(u, w, 0, 0));
      }
    }
  }
  // Backward: read the envelope and overwrite the stack with the result, right to left.
  for (int u = m - 1; u >= 0; --u) {
    ivec2 st = imageLoad(u_nearest, ivec2(q, y)).xy;
    int site_row = imageLoad(u_column_site, ivec2(st.x, y)).r;
    if (u == st.y) --q;
    if (site_row < 0) {  // no column has a site: the image has none
      imageStore(u_nearest, ivec2(u, y), ivec4(-1, -1, 0, 0));
      imageStore(u_distance_sq, ivec2(u, y), ivec4(-1));
    } else {
      int dx = u - st.x, dy = y - site_row;
      imageStore(u_nearest, ivec2(u, y), ivec4(st.x, site_row, 0, 0));
      imageStore(u_distance_sq, ivec2(u, y), ivec4(dx * dx + dy * dy));
    }
  }
}
