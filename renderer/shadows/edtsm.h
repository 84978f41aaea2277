#pragma once
// EDT shadow mapping (Macedo & Apolinario, "Euclidean Distance Transform Shadow Mapping", 2016):
// the post passes after the G-buffer. Declared in screen_space.h (run_edtsm) beside the other
// screen-space techniques; this header only names the file's contract:
//   sites        3x3 silhouette sites of the input shadows (edge-aware)
//   edt          exact EDT: nearest site per pixel
//   edt_penumbra I = 1/2 -+ D/P for D <= P/2, D in world units between G-buffer positions
//   mean_filter  separable edge-aware mean filter of width w_filter z_screen / z_eye pixels
#include "shadows/screen_space.h"
