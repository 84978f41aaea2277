#pragma once
// ImGui widgets generated from the parameters tables (shadows/settings.h): one row, one widget.
#include <functional>
#include <optional>
#include <string>

#include "scene/scene.h"
#include "shadows/renderer.h"
#include "shadows/settings.h"

namespace penumbra::gui {

// Draws every row of the table of `params`; returns true when a value changed.
template <class P>
bool settings_panel(const char* id, P& params);

// Technique combo plus the active technique's table and the shared map table.
bool shadow_settings_panel(shadows::ShadowSettings& settings);

// What a window draws for the panel's `settings` in `scene`: the settings themselves, or, where
// the panel chose map.virtual_pages for a technique or light that cannot read pages, the same with
// maps, and a line in the panel saying why (the renderer would refuse the frame). With a virtual
// frame's `info`, the panel's line on its pages.
shadows::ShadowSettings drawable_settings(const shadows::ShadowSettings& settings, const scene::Scene& scene);
void virtual_pages_line(const shadows::ShadowSettings& settings, const scene::Scene& scene, const shadows::FrameInfo& info);

// A window's frame under the panel's settings: `draw` renders with them; where the renderer or the
// calibration refuses them (a page pool too small for this view, a visibility whose c leaves
// adaptive.c's range), the panel's change is undone (the last settings that drew become `settings`
// again and are drawn) and line() says why in the panel, instead of the app ending.
class SettingsUndo {
 public:
  std::string render(shadows::ShadowSettings& settings, const std::function<void(shadows::ShadowSettings&)>& draw);
  void line() const;  // the last refusal, in the panel (nothing when none)

 private:
  std::optional<shadows::ShadowSettings> last_good_;
  std::string refused_;
};

// The light's size: angular diameter in degrees (directional) or width in world units (spot).
bool light_size_control(scene::Light& light);

}  // namespace penumbra::gui
