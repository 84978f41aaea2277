#pragma once
// Debug views of the sun's virtual shadow map (shadows/virtual_shadow_map.h) for the apps
// (penumbra-render --virtual-debug, penumbra-demo --pages): the level each pixel samples, by the
// rule and by the footprint, and the page pool with each slot's state.
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "adaptive/virtual_pages.h"
#include "gl/objects.h"
#include "io/image_io.h"
#include "scene/scene.h"
#include "shadows/settings.h"
#include "shadows/virtual_shadow_map.h"

namespace penumbra::apps {

// How the debug views mark pages for a technique's settings, as the renderer does (the technique's
// registry entry, TechniqueEntry::pages): a fixed filter by its world radius; PCSS in the renderer's
// two rounds (the pages of each pixel's blocker search, then those of the penumbra it finds,
// `pcss`); its c and the pixel floor (1 pixel where the settings have none: the footprint marking
// needs one). `problem`: empty, or why these settings mark no pages (shadows::virtual_marking_unsupported;
// the shading's own needs, such as the pages' box filter, do not matter to the marking).
struct VirtualMarking {
  double radius_ws = 0;                       // PCF
  std::optional<shadows::VirtualPcss> pcss;  // PCSS, for the scene's sun
  adaptive::MarkOptions options;
  std::string problem;
};
VirtualMarking virtual_marking(const shadows::ShadowSettings& s, const scene::Light& light);

// A level image (R32F: the level per pixel, -1 no surface, `levels` beyond the coarsest) in
// colour: a distinct colour per level, no surface black, beyond the coarsest white.
io::Image8 level_image(const gl::Texture& levels_tex, int levels);
// The key of those colours: one band per level, finest on the left, over `width` × `height`.
io::Image8 level_key(int levels, int width, int height);
// The pool as an image of at most `max_side` pixels a side: each slot's depths in grey (light: near
// the sun; stretched over the depths the pages hold), tinted by its state (drawn by the last
// update: green; cached from an earlier one: blue; free: dark red), slots outlined.
io::Image8 pool_image(const shadows::VirtualShadowMap& map, int max_side);

// The virtual map of one scene kept across views (a window's frames): each view() marks the pages
// by the rule and by the footprint, draws the rule's into a pool of 32² slots (keeping what earlier
// views drew), and gives the debug images. For PCSS the pool first holds the searches' pages (the
// same for both markings), and each marking's level image shows its filter's level per pixel
// (-1, black, where the search found nothing in front: no filter pages).
class VirtualDebug {
 public:
  // Throws std::runtime_error for a spot light (the virtual map is the sun's).
  explicit VirtualDebug(const scene::Scene& scene);
  ~VirtualDebug();
  struct View {
    adaptive::MarkResult rule, footprint;  // PCSS: with the searches' pages
    shadows::VirtualMapStats stats;  // the rule's pages drawn into the pool
    io::Image8 rule_levels, footprint_levels;  // level per pixel (level_image)
  };
  // `scene` must be the one given to the constructor, its objects perhaps moved since (the pages
  // over a moved object's old and new place are drawn again).
  View view(const scene::Scene& scene, const scene::Camera& camera, int width, int height, const VirtualMarking& marking,
            bool images = true);
  const shadows::VirtualShadowMap& map() const;
  const adaptive::VirtualMapLayout& layout() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

// For `scene` (a directional light) seen by `camera` at width × height: marks the pages by the rule
// (`marking`) and by the footprint, draws the rule's into a pool of 32² slots, first as `previous`
// sees them (when given) and then as `camera` does, and writes <dir>/virtual-levels.png (rule |
// footprint | key) and <dir>/virtual-pool.png. Returns the counts (pages per marking, drawn, cached).
// Throws std::runtime_error for a spot light.
nlohmann::json write_virtual_debug(const scene::Scene& scene, const scene::Camera* previous, const scene::Camera& camera, int width,
                                   int height, const VirtualMarking& marking, const std::filesystem::path& dir);

}  // namespace penumbra::apps
