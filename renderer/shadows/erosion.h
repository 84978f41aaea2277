#pragma once
// Contact-hardening soft shadows using erosion (Klein, Nischwitz & Obermeier 2012, the PCF
// variant of sec. 3): the post passes after the G-buffer (run_erosion, declared in
// screen_space.h):
//   edges          4-neighbour Laplacian edges of the input shadows; at each, a PCSS blocker
//                  search gives the penumbra width (d_R - d_B) w_light / d_B (world units; its
//                  screen size divides by d_obs)
//   erosion_minmax min-max mip-map of (edge, width in pixels)
//   erosion        per pixel, the eroded width (0 outside every penumbra)
// The shading pass then runs PCF with radius width/2 where the width is positive, the hard test
// elsewhere.
#include "shadows/screen_space.h"
