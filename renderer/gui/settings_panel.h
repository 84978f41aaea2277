#pragma once
// ImGui widgets generated from the parameters tables (shadows/settings.h): one row, one widget.
#include "shadows/settings.h"

namespace penumbra::gui {

// Draws every row of the table of `params`; returns true when a value changed.
template <class P>
bool settings_panel(const char* id, P& params);

// Technique combo plus the active technique's table and the shared map table.
bool shadow_settings_panel(shadows::ShadowSettings& settings);

}  // namespace penumbra::gui
