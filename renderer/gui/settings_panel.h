#pragma once
// ImGui widgets generated from the parameters tables (shadows/settings.h): one row, one widget.
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

// The light's size: angular diameter in degrees (directional) or width in world units (spot).
bool light_size_control(scene::Light& light);

}  // namespace penumbra::gui
