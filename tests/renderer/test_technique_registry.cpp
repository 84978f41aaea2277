// The technique registry (shadows/technique_list.h, shadows/techniques/*): every registered
// technique has a name, a settings section, a shader define the shading pass knows and a stated
// radius reading consistent with its functions. A technique added to the list without one of
// these fails here instead of falling through somewhere at run time.
#include <gtest/gtest.h>

#include <string>

#include "gl/embedded_files.h"
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
