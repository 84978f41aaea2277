// The window apps' undo of a panel change the view cannot draw (gui::SettingsUndo): the refusal is
// kept for the panel, the settings that drew last come back and are drawn, and the app goes on.
// No window: the draw is a function that refuses as the renderer does.
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "gui/settings_panel.h"
#include "shadows/virtual_shadow_map.h"

namespace {

using penumbra::shadows::ShadowSettings;

TEST(SettingsUndo, AChangeTheRendererRefusesIsUndoneAndTheLastSettingsDraw) {
  penumbra::gui::SettingsUndo undo;
  std::vector<int> drawn;  // the pool sizes drawn, in order
  auto draw = [&](ShadowSettings& s) {
    if (s.map.virtual_pool_pages < 4) throw penumbra::shadows::PoolTooSmall("--map.virtual_pool_pages 1: too small for this view", 4);
    drawn.push_back(s.map.virtual_pool_pages);
  };
  ShadowSettings settings;
  settings.map.virtual_pool_pages = 32;
  EXPECT_EQ(undo.render(settings, draw), "");
  settings.map.virtual_pool_pages = 8;  // a change that draws
  EXPECT_EQ(undo.render(settings, draw), "");
  settings.map.virtual_pool_pages = 1;  // a change the view cannot draw
  const std::string refused = undo.render(settings, draw);
  EXPECT_NE(refused.find("--map.virtual_pool_pages 1"), std::string::npos) << refused;
  EXPECT_EQ(settings.map.virtual_pool_pages, 8) << "the change is undone";
  EXPECT_EQ(drawn, (std::vector<int>{32, 8, 8})) << "the frame is drawn with the last settings that drew";
  // A refusal the last settings share is not hidden: it ends the app as before.
  auto broken = [](ShadowSettings&) { throw std::runtime_error("the context is lost"); };
  EXPECT_THROW(undo.render(settings, broken), std::runtime_error);
}

}  // namespace
