#pragma once
// ImGui widgets generated from the parameters tables (shadows/settings.h): one row, one widget.
#include "scene/scene.h"
#include "shadows/settings.h"

namespace penumbra::gui {

// Draws every row of the table of `params`; returns true when a value changed.
template <class P>
bool settings_panel(const char* id, P& params);

// Technique combo plus the active technique's table and the shared map table.
bool shadow_settings_panel(shadows::ShadowSettings& settings);

// The light's size: angular diameter in degrees (directional) or width in world units (spot).
bool light_size_control(scene::Light& light);

}  // namespace penumbra::gui
