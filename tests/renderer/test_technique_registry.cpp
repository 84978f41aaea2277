// The technique registry (shadows/technique_list.h, shadows/techniques/*): every registered
// technique has a name, a settings section, a shader define the shading pass knows and a stated
// radius reading consistent with its functions. A technique added to the list without one of
// these fails here instead of falling through somewhere at run time.
#include <gtest/gtest.h>

#include <string>

#include "gl/embedded_files.h"
#include "shadows/frame_plan.h"
#include "shadows/settings.h"
#include "shadows/technique.h"

namespace penumbra::shadows {
namespace {

std::string shader_text(std::string_view name) {
  for (const auto& f : embedded::shaders())
    if (f.name == name) return std::string(f.text);
  return {};
}

// Every embedded shader that the shading pass may include (shading.frag and the shadow_*.glsl).
std::string shading_sources() {
  std::string all = shader_text("shading.frag");
  for (const auto& f : embedded::shaders())
    if (f.name.starts_with("shadow_") && f.name.ends_with(".glsl")) all += f.text;
  return all;
}

TEST(TechniqueRegistry, EveryTechniqueHasAnEntryNamedLikeIt) {
  for (std::size_t i = 0; i < technique_names().size(); ++i) {
    const auto t = static_cast<Technique>(i);
    EXPECT_EQ(technique_entry(t).name, technique_names()[i]);
    EXPECT_EQ(technique_from_string(technique_entry(t).name), t);
  }
}

TEST(TechniqueRegistry, EveryTechniqueButHardHasANonEmptySettingsSection) {
  ShadowSettings s;
  for (auto name : technique_names()) {
    s.technique = technique_from_string(name);
    std::size_t rows = 0;
    visit_technique_section(s, [&](std::string_view section, const auto& params) {
      EXPECT_EQ(section, name);
      rows = settings_table(&params).size();
    });
    if (name == "hard") {
      EXPECT_EQ(rows, 0u);
    } else {
      EXPECT_GT(rows, 0u) << name << " has no settings section";
    }
  }
}

TEST(TechniqueRegistry, EveryDefineIsHandledByTheShadingPass) {
  const std::string sources = shading_sources();
  ASSERT_FALSE(sources.empty());
  for (auto name : technique_names()) {
    const TechniqueEntry& e = technique_entry(technique_from_string(name));
    ASSERT_FALSE(e.define.empty()) << name;
    EXPECT_NE(sources.find("defined(" + std::string(e.define) + ")"), std::string::npos)
        << name << ": no shader tests defined(" << e.define << ")";
  }
}

TEST(TechniqueRegistry, EveryTechniqueStatesHowItsRadiusReads) {
  for (auto name : technique_names()) {
    const TechniqueEntry& e = technique_entry(technique_from_string(name));
    SCOPED_TRACE(std::string(name));
    ASSERT_NE(e.radius, RadiusReading::unset);
    EXPECT_EQ(e.radius == RadiusReading::fixed_filter, e.filter_radius != nullptr);
    EXPECT_EQ(e.radius == RadiusReading::fixed_filter, e.set_filter_radius != nullptr);
    EXPECT_EQ(e.radius == RadiusReading::penumbra, e.rule_radius_ws != nullptr);
    if (e.per_pixel_requirement) {
      EXPECT_EQ(e.radius, RadiusReading::penumbra);
    }
  }
}

// Issue 47: who reads the virtual map's pages is the registry's to say (it was four if-chains on
// the technique, two of which disagreed). Every entry states it; the techniques that can are
// listed from the registry alone; the frame plan and the debug views ask the same function.
TEST(TechniqueRegistry, TheRegistryDecidesWhoReadsPages) {
  std::vector<std::string> readers;
  for (auto name : technique_names()) {
    const TechniqueEntry& e = technique_entry(technique_from_string(name));
    SCOPED_TRACE(std::string(name));
    ASSERT_NE(e.pages, PageReading::unset);
    if (e.pages == PageReading::none) {
      EXPECT_EQ(e.pages_need, nullptr);
      continue;
    }
    readers.emplace_back(name);
    if (e.pages == PageReading::blocker_search) {
      EXPECT_NE(e.search_scale, nullptr);
    } else {
      EXPECT_NE(e.filter_radius, nullptr) << "pages are marked by a fixed filter's world radius";
    }
    EXPECT_EQ(e.pages == PageReading::moments, e.moments != nullptr);
  }
  EXPECT_EQ(readers, (std::vector<std::string>{"pcf", "pcss", "vsm"}));
  EXPECT_EQ(page_reading_techniques(), "pcf, pcss or vsm");

  for (auto name : technique_names()) {
    SCOPED_TRACE(std::string(name));
    ShadowSettings s;
    s.technique = technique_from_string(name);
    const TechniqueEntry& e = technique_entry(s.technique);
    if (e.set_filter_radius) e.set_filter_radius(s, {0.05f, RadiusUnit::world});
    s.pcf.kernel = s.pcss.kernel = Kernel::grid;
    const bool reads = e.pages != PageReading::none;
    EXPECT_EQ(virtual_marking_unsupported(s).empty(), reads) << virtual_marking_unsupported(s);
    EXPECT_EQ(virtual_pages_unsupported(s).empty(), reads) << virtual_pages_unsupported(s);
    if (!reads) {
      EXPECT_EQ(virtual_pages_unsupported(s).rfind("pages are read by pcf, pcss or vsm, not " + std::string(name), 0), 0u);
    }
    if (!reads) {
      EXPECT_EQ(virtual_marking_unsupported(s), "pages are marked for pcf, pcss or vsm, not " + std::string(name));
    }
    if (e.set_filter_radius && reads) {
      e.set_filter_radius(s, {2.0f, RadiusUnit::texels});
      EXPECT_EQ(virtual_marking_unsupported(s), std::string(name) + " marks pages by a world radius (--" + std::string(name) + ".radius_unit world)");
      EXPECT_EQ(virtual_pages_unsupported(s).rfind(std::string(name) + " reads pages only with --" + std::string(name) + ".radius_unit world, not " + std::string(name), 0), 0u)
          << virtual_pages_unsupported(s);
    }
  }
  // The shading's own need beyond marking: the pages' filters are boxes. The marking (the debug
  // views) does not need it.
  ShadowSettings pcf;
  pcf.technique = technique_from_string("pcf");
  pcf.pcf.radius_unit = RadiusUnit::world;
  pcf.pcf.kernel = Kernel::poisson;
  EXPECT_EQ(virtual_marking_unsupported(pcf), "");
  EXPECT_NE(virtual_pages_unsupported(pcf).find("pcf reads pages only with --pcf.kernel grid, not pcf"), std::string::npos)
      << virtual_pages_unsupported(pcf);
  pcf.pcf.radius_unit = RadiusUnit::texels;  // both lacking: both named in the one line
  EXPECT_NE(virtual_pages_unsupported(pcf).find("pcf reads pages only with --pcf.radius_unit world --pcf.kernel grid, not pcf"), std::string::npos)
      << virtual_pages_unsupported(pcf);
  ShadowSettings pcss;
  pcss.technique = technique_from_string("pcss");
  pcss.pcss.kernel = Kernel::disk;
  EXPECT_EQ(virtual_marking_unsupported(pcss), "");
  EXPECT_NE(virtual_pages_unsupported(pcss).find("pcss reads pages only with --pcss.kernel grid, not pcss"), std::string::npos)
      << virtual_pages_unsupported(pcss);
}

TEST(TechniqueRegistry, FixedFilterRadiusRoundTripsThroughTheEntry) {
  for (auto name : technique_names()) {
    const TechniqueEntry& e = technique_entry(technique_from_string(name));
    if (!e.filter_radius) continue;
    ShadowSettings s;
    s.technique = technique_from_string(name);
    e.set_filter_radius(s, {0.125f, RadiusUnit::world});
    EXPECT_EQ(e.filter_radius(s).radius, 0.125f) << name;
    EXPECT_EQ(e.filter_radius(s).unit, RadiusUnit::world) << name;
    // and the section's own table sees the same value
    visit_technique_section(s, [&](std::string_view, const auto& params) {
      bool found = false;
      for (const auto& row : settings_table(&params))
        if (row.key == "radius") {
          found = true;
          EXPECT_DOUBLE_EQ(row.get(params), 0.125);
        }
      EXPECT_TRUE(found) << name << ": a fixed filter without a `radius` row";
    });
  }
}

TEST(TechniqueRegistry, ScreenSpaceAndMomentsAreExclusive) {
  ShadowSettings s;
  for (auto name : technique_names()) {
    s.technique = technique_from_string(name);
    const TechniqueEntry& e = technique_entry(s.technique);
    if (e.screen_space()) {
      EXPECT_EQ(e.moments, nullptr) << name;
    }
    if (e.moments) {
      EXPECT_TRUE(e.moments(s).has_value()) << name;
    }
  }
}

}  // namespace
}  // namespace penumbra::shadows
