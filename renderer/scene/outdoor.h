#pragma once
// The outdoor scene: a procedural town on 600 m × 600 m of terrain, for measuring shadow maps where
// engines use cascades. About a million triangles, generated from a seed (the same seed gives the
// same scene on every run), with the thin casters that a coarse map loses: a lattice tower crane
// (Kreuzer 2017, Fig. 6.1), wires between rows of poles, bare trees down to 1–2 cm twigs, a mesh
// fence around the construction site; and a camera path of 360 frames that walks along a street
// at eye height past the site and then rises to an overview of the town.
//
// Objects (one merged mesh each, so another engine's scene can stand in for any of them):
//   ground     terrain, flat under the town (|x|, |z| < 150 m), rolling hills beyond
//   buildings  blocks on a 40 m street grid: boxes 6–70 m tall with parapets, floor ledges,
//              setback towers, rooftop units and antennas
//   site       the construction site's footing, container, and a three-storey concrete frame
//   crane      tower crane: 45 m lattice mast (1.8 m panels), 50 m triangular jib (1.25 m
//              panels), counter-jib, pendants and hook cable
//   fence      2 m mesh fence around the site (bars every 0.17 m)
//   trees      bare deciduous trees, five branching levels
//   poles      wooden utility poles with cross-arms along two streets
//   wires      three sagging wires per span between the poles (2.5 cm thick)
//
// Lighting: one shadow-casting light, as every scene has. `sun`: directional, 40° above the
// horizon from the south-south-east, 1° angular diameter (a slightly hazy sun; the clear sun is
// 0.53°). `floodlight`: the same town at night under a spot light on the crane's mast, 30 m up,
// aimed at the street. The two are separate built-in scenes ("outdoor", "outdoor-spot") because
// the renderer shades with the scene's one light.
#include <cstdint>

#include <penumbra/scene/scene.h>

namespace penumbra::scene {

enum class OutdoorLight { sun, floodlight };

struct OutdoorOptions {
  std::uint32_t seed = 1;
  OutdoorLight light = OutdoorLight::sun;
};

Scene make_outdoor_scene(const OutdoorOptions& options);

}  // namespace penumbra::scene
