#pragma once
// EDT soft shadow mapping (Macedo & Apolinario, "Euclidean Distance Transform Soft Shadow
// Mapping", 2017): the post passes after the G-buffer (run_edtssm, declared in screen_space.h):
//   sites        3x3 silhouette sites; at each, a PCSS blocker search gives
//                w_p = w_light (z_R - z_avg) / z_avg in world units (sites without blockers drop out)
//   edt          exact EDT: nearest site per pixel, which carries its w_p
//   edt_penumbra alpha = 1/2 -+ d / (beta w_p) for d <= beta w_p / 2, d in world units
//   mean_filter  separable edge-aware mean filter of width w_filter z_screen / z_eye pixels
#include "shadows/screen_space.h"
