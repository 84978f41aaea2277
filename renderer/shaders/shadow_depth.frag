// Depth-only shadow map: the rasterizer writes depth (with the raster depth offset).
void main() {}
