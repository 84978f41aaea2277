// Depth only: a shadow map (the rasterizer writes depth, with the raster depth offset), and the
// camera's depth prepass with shading.vert (map.depth_prepass).
void main() {}
