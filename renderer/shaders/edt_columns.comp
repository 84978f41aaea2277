// Exact EDT, pass 1 of 2 (Meijster, Roerdink & Hesselink 2000, phase 1): for every pixel, the row
// of the nearest site in its own column, or -1 when the column has no site. One invocation sweeps
// one whole column down and then up, so the result is exact integers for any image height.
layout(local_size_x = 64) in;

layout(binding = 0, r8ui) uniform readonly uimage2D u_sites;   // != 0: site
layout(binding = 1, r32i) uniform coherent iimage2D u_column_site;

void main() {
  ivec2 size = imageSize(u_sites);
  int x = int(gl_GlobalInvocationID.x);
  if (x >= size.x) return;

  int above = -1;  // nearest site at or above the current row
  for (int y = 0; y < size.y; ++y) {
    if (imageLoad(u_sites, ivec2(x, y)).r != 0u) above = y;
    imageStore(u_column_site, ivec2(x, y), ivec4(above));
  }
  int below = -1;  // nearest site at or below; replaces `above` where strictly nearer
  for (int y = size.y - 1; y >= 0; --y) {
    if (imageLoad(u_sites, ivec2(x, y)).r != 0u) below = y;
    if (below < 0) continue;
    int a = imageLoad(u_column_site, ivec2(x, y)).r;
    if (a < 0 || below - y < y - a) imageStore(u_column_site, ivec2(x, y), ivec4(below));
  }
}
