// plan_frame on the CPU (no GL): pass selection, cascades, the resolution rule, its hysteresis
// and the atlas layout, including the extremes the GL tests exercise through whole frames.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/glm.hpp>

#include "adaptive/resolution_rule.h"
#include "scene/scene.h"
#include "shadows/frame_plan.h"

namespace penumbra::shadows {
namespace {

constexpr int kWidth = 320, kHeight = 180;

FramePlan plan(const ShadowSettings& s, const scene::Scene& scene = scene::make_builtin_scene("demo")) {
  AdaptiveState state;
  return plan_frame(s, scene, kWidth, kHeight, state);
}

ShadowSettings with(Technique t) {
  ShadowSettings s;
  s.technique = t;
  return s;
}

// PCF with a world-space radius (what the rule is for) and adaptive resolution on.
ShadowSettings adaptive_pcf(float radius_ws) {
  ShadowSettings s = with(Technique::pcf);
  s.adaptive.enabled = true;
  s.pcf.radius_unit = RadiusUnit::world;
  s.pcf.radius = radius_ws;
  return s;
}

TEST(FramePlan, PassesFollowTheTechnique) {
  using P = PassId;
  // The camera's depth prepass (map.depth_prepass, on by default) before the shading of every map
  // technique; the screen-space techniques' G-buffer pass leaves that depth itself.
  EXPECT_EQ(plan(with(Technique::hard)).passes, (std::vector<P>{P::shadow_map, P::depth_prepass, P::shading}));
  EXPECT_EQ(plan(with(Technique::pcf)).passes, (std::vector<P>{P::shadow_map, P::depth_prepass, P::shading}));
  for (Technique t : {Technique::vsm, Technique::msm, Technique::evsm})
    EXPECT_EQ(plan(with(t)).passes, (std::vector<P>{P::shadow_map, P::moments_blur, P::depth_prepass, P::shading})) << to_string(t);
  for (Technique t : {Technique::edtsm, Technique::edtssm, Technique::erosion})
    EXPECT_EQ(plan(with(t)).passes, (std::vector<P>{P::shadow_map, P::gbuffer, P::post, P::shading})) << to_string(t);
  ShadowSettings pcss = with(Technique::pcss);
  EXPECT_EQ(plan(pcss).passes, (std::vector<P>{P::shadow_map, P::depth_prepass, P::shading}));
  pcss.adaptive.enabled = true;
  EXPECT_EQ(plan(pcss).passes, (std::vector<P>{P::shadow_map, P::depth_prepass, P::shading, P::pcss_requirement}));
  pcss.adaptive.pcss = PcssRequirement::min_penumbra;
  EXPECT_EQ(plan(pcss).passes, (std::vector<P>{P::shadow_map, P::depth_prepass, P::shading}));
  pcss.pcss.hierarchical = true;  // bounds from the min-max depth pyramid before the search
  EXPECT_EQ(plan(pcss).passes, (std::vector<P>{P::shadow_map, P::depth_minmax, P::depth_prepass, P::shading}));
  pcss.map.depth_prepass = false;  // the shading pass tests depth itself
  EXPECT_EQ(plan(pcss).passes, (std::vector<P>{P::shadow_map, P::depth_minmax, P::shading}));
  EXPECT_EQ(resource_names(pass_io(P::shading, plan(pcss)).reads), "scene meshes, depth atlas, depth min-max pyramid");
  pcss.map.depth_prepass = true;
  EXPECT_EQ(resource_names(pass_io(P::shading, plan(pcss)).reads), "scene meshes, depth atlas, depth min-max pyramid, camera depth");
  // The floor a frame's shadow cost is taken above has the prepass of the frame it is the floor of.
  EXPECT_EQ(plan(unshadowed_floor(pcss)).passes, (std::vector<P>{P::shadow_map, P::depth_prepass, P::shading}));
  pcss.map.depth_prepass = false;
  EXPECT_EQ(plan(unshadowed_floor(pcss)).passes, (std::vector<P>{P::shadow_map, P::shading}));
}

// Issue 28: the passes' reads and writes were declared and read by nothing. Every plan of every
// technique (fixed, adaptive, cascaded, PCSS measuring its requirement, hierarchical) is a frame:
// each pass reads only what an earlier one wrote; and a plan missing a writer is named.
TEST(FramePlan, EveryPlanIsAFrameWhosePassesReadWhatEarlierOnesWrote) {
  for (const auto name : technique_names()) {
    for (const bool adaptive : {false, true})
      for (const int cascades : {1, 3}) {
        ShadowSettings s = with(technique_from_string(name));
        s.adaptive.enabled = adaptive;
        s.map.cascades = cascades;
        s.pcss.hierarchical = cascades == 3;
        const FramePlan p = plan(s);
        EXPECT_EQ(plan_problem(p), "") << name << " adaptive " << adaptive << " cascades " << cascades;
      }
  }
  FramePlan vsm = plan(with(Technique::vsm));
  EXPECT_EQ(resource_names(pass_io(PassId::shading, vsm).reads), "scene meshes, depth atlas, moments, camera depth");
  vsm.passes.erase(vsm.passes.begin());  // no shadow_map
  EXPECT_EQ(plan_problem(vsm), "pass vsm_blur reads moments, which no earlier pass of the frame writes");
  FramePlan pcf = plan(with(Technique::pcf));
  pcf.passes.pop_back();  // no shading
  EXPECT_EQ(plan_problem(pcf), "the frame never writes its colour, visibility");
  pcf.passes.push_back(PassId::shading);
  pcf.passes.push_back(PassId::shadow_map);
  EXPECT_EQ(plan_problem(pcf), "pass shadow_map runs twice or out of order");
  FramePlan unprepared = plan(with(Technique::pcf));
  ASSERT_TRUE(unprepared.depth_prepass);
  unprepared.passes.erase(std::find(unprepared.passes.begin(), unprepared.passes.end(), PassId::depth_prepass));
  EXPECT_EQ(plan_problem(unprepared), "pass shading reads camera depth, which no earlier pass of the frame writes");
  ShadowSettings pcss = with(Technique::pcss);
  pcss.adaptive.enabled = true;
  FramePlan measured = plan(pcss);
  ASSERT_TRUE(measured.pcss_requirement);
  measured.pcss_requirement = false;  // shading no longer writes the requirement image
  EXPECT_EQ(plan_problem(measured), "pass pcss_requirement reads requirement image, which no earlier pass of the frame writes");
}

// The sun's virtual shadow map: pages instead of maps, read by box PCF with a world radius or PCSS
// with a box filter; a spot light, another kernel or technique, or a radius in texels is refused
// in one line naming it.
TEST(FramePlan, VirtualPagesReplaceTheMapsForBoxPcfInWorldUnits) {
  ShadowSettings s = with(Technique::pcf);
  s.pcf.kernel = Kernel::grid;
  s.pcf.radius_unit = RadiusUnit::world;
  s.pcf.radius = 0.12f;
  s.map.virtual_pages = VirtualPages::rule;
  s.map.cascades = 4;  // ignored: the pages cover the view
  const FramePlan p = plan(s);
  EXPECT_EQ(p.passes, (std::vector<PassId>{PassId::virtual_pages, PassId::shading}));
  EXPECT_EQ(plan_problem(p), "");
  EXPECT_EQ(resource_names(pass_io(PassId::shading, p).reads), "scene meshes, virtual pages, camera depth") << "the position pass's";
  EXPECT_EQ(p.resolution_source, "virtual_rule");
  ASSERT_EQ(p.cascades.size(), 1u);
  EXPECT_EQ(p.atlas.width * p.atlas.height, 1) << "no map is drawn";
  s.map.virtual_pages = VirtualPages::footprint;
  EXPECT_EQ(plan(s).resolution_source, "virtual_footprint");

  auto refused = [&](const ShadowSettings& bad, const scene::Scene& scene, const std::string& says) {
    try {
      plan(bad, scene);
      ADD_FAILURE() << "accepted: " << says;
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(says), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("map.virtual_pages"), std::string::npos) << e.what();
    }
  };
  const scene::Scene demo = scene::make_builtin_scene("demo");
  scene::Scene spot = demo;
  spot.light.type = scene::Light::Type::spot;
  spot.light.position = {0, 12, 0};
  refused(s, spot, "spot light");
  ShadowSettings poisson = s;
  poisson.pcf.kernel = Kernel::poisson;
  refused(poisson, demo, "kernel=poisson");
  ShadowSettings texels = s;
  texels.pcf.radius_unit = RadiusUnit::texels;
  refused(texels, demo, "radius_unit=texels");
  ShadowSettings vsm = with(Technique::vsm);
  vsm.map.virtual_pages = VirtualPages::rule;
  refused(vsm, demo, "not vsm");
  ShadowSettings pcss = with(Technique::pcss);
  pcss.map.virtual_pages = VirtualPages::rule;
  refused(pcss, demo, "kernel=poisson");
  pcss.pcss.kernel = Kernel::grid;  // PCSS with a box filter reads pages: its search, then its penumbra's
  EXPECT_EQ(plan(pcss).passes, (std::vector<PassId>{PassId::virtual_pages, PassId::shading}));
}

TEST(FramePlan, FixedSingleMapFillsItsTextureWithoutGuardBand) {
  ShadowSettings s = with(Technique::pcf);
  s.map.resolution_texels = 777;
  const FramePlan p = plan(s);
  ASSERT_EQ(p.cascades.size(), 1u);
  EXPECT_EQ(p.cascades[0].resolution_texels, 777);
  EXPECT_EQ(p.resolution_source, "fixed");
  EXPECT_EQ(p.atlas.guard, 0);
  EXPECT_EQ(p.atlas.width, 777);
  EXPECT_EQ(p.atlas.height, 777);
  EXPECT_EQ(p.cascades[0].atlas_x, 0);
  EXPECT_FLOAT_EQ(p.filter_radius_texels, s.pcf.radius);  // radius given in texels
}

TEST(FramePlan, CascadesSplitTheViewAndTileTheAtlas) {
  for (int n = 2; n <= 4; ++n) {
    ShadowSettings s = with(Technique::pcf);
    s.map.cascades = n;
    s.map.resolution_texels = 256;
    const FramePlan p = plan(s);
    ASSERT_EQ(static_cast<int>(p.cascades.size()), n);
    EXPECT_EQ(p.atlas.guard, kGuardTexels);
    EXPECT_EQ(p.atlas.width, 2 * (256 + 2 * kGuardTexels));
    EXPECT_EQ(p.atlas.height, ((n + 1) / 2) * (256 + 2 * kGuardTexels));
    for (int i = 0; i < n; ++i) {
      const CascadeInfo& c = p.cascades[static_cast<std::size_t>(i)];
      EXPECT_LT(c.split_near_ws, c.split_far_ws);
      if (i > 0) {
        EXPECT_FLOAT_EQ(c.split_near_ws, p.cascades[static_cast<std::size_t>(i - 1)].split_far_ws);
      }
      // Each region with its guard band lies inside the atlas and apart from the others.
      EXPECT_GE(c.atlas_x, kGuardTexels);
      EXPECT_LE(c.atlas_x + 256 + kGuardTexels, p.atlas.width);
      EXPECT_LE(c.atlas_y + 256 + kGuardTexels, p.atlas.height);
      for (int j = 0; j < i; ++j) {
        const CascadeInfo& o = p.cascades[static_cast<std::size_t>(j)];
        const bool apart = std::abs(c.atlas_x - o.atlas_x) >= 256 + 2 * kGuardTexels ||
                           std::abs(c.atlas_y - o.atlas_y) >= 256 + 2 * kGuardTexels;
        EXPECT_TRUE(apart) << "cascades " << i << " and " << j << " overlap";
      }
    }
    // Nearer cascades cover less of the light's view plane.
    EXPECT_LT(p.cascades.front().light.extent_ws, p.cascades.back().light.extent_ws);
  }
}

TEST(FramePlan, ScreenSpaceAndSpotLightsUseOneMap) {
  ShadowSettings s = with(Technique::edtsm);
  s.map.cascades = 4;
  EXPECT_EQ(plan(s).cascades.size(), 1u);
  s.technique = Technique::pcf;
  scene::Scene spot = scene::make_builtin_scene("demo");
  spot.light.type = scene::Light::Type::spot;
  spot.light.position = {0, 12, 0};
  EXPECT_EQ(plan(s, spot).cascades.size(), 1u);
}

TEST(FramePlan, EmptySceneHasOneMap) {
  ShadowSettings s = with(Technique::pcf);
  s.map.cascades = 4;
  const FramePlan p = plan(s, scene::make_builtin_scene("empty"));
  EXPECT_EQ(p.cascades.size(), 1u);
  EXPECT_GT(p.cascades[0].resolution_texels, 0);
}

TEST(FramePlan, RuleGivesCTimesExtentOverRadius) {
  ShadowSettings s = adaptive_pcf(0.05f);
  s.adaptive.quantum_texels = 1;
  const FramePlan p = plan(s);
  ASSERT_EQ(p.cascades.size(), 1u);
  EXPECT_EQ(p.resolution_source, "rule");
  const double expected = adaptive::required_texels_ws(s.adaptive.c, adaptive::LightExtentWs{p.cascades[0].light.extent_ws},
                                                      adaptive::FilterRadiusWs{0.05});
  // The requirement comes from the frame at the previous resolution (here: max_texels), so the
  // extent differs by the texel-sized padding only.
  EXPECT_NEAR(p.cascades[0].required_texels, expected, 0.01 * expected);
  EXPECT_EQ(p.cascades[0].resolution_texels, static_cast<int>(std::ceil(p.cascades[0].required_texels)));
  // Doubling the radius halves the requirement.
  s.pcf.radius = 0.1f;
  EXPECT_NEAR(plan(s).cascades[0].required_texels, p.cascades[0].required_texels / 2, 0.01 * p.cascades[0].required_texels);
}

// adaptive.max_texel_ws: no map's texel wider than the ceiling (for casters thinner than the
// rule's texel), the rule alone where its texel is already narrower, for PCF and for PCSS's
// measured requirement.
TEST(FramePlan, TexelCeilingRaisesTheRuleOnlyWhereItsTexelIsWider) {
  ShadowSettings s = adaptive_pcf(0.4f);
  s.adaptive.quantum_texels = 1;
  const FramePlan rule = plan(s);
  const double extent = rule.cascades[0].light.extent_ws;
  const double rule_texel = extent / rule.cascades[0].required_texels;
  s.adaptive.max_texel_ws = static_cast<float>(rule_texel / 4);
  const FramePlan capped = plan(s);
  EXPECT_NEAR(capped.cascades[0].required_texels, 4 * rule.cascades[0].required_texels, 0.02 * 4 * rule.cascades[0].required_texels);
  EXPECT_LE(capped.cascades[0].light.extent_ws / capped.cascades[0].resolution_texels, s.adaptive.max_texel_ws * 1.0001);
  s.adaptive.max_texel_ws = static_cast<float>(rule_texel * 4);  // coarser than the rule's: no effect
  EXPECT_DOUBLE_EQ(plan(s).cascades[0].required_texels, rule.cascades[0].required_texels);
  s.adaptive.max_texel_ws = 1e-9f;  // a ceiling no map can meet: the largest map
  EXPECT_EQ(plan(s).cascades[0].resolution_texels, s.adaptive.max_texels);

  // Cascades: each one at least its own extent over the ceiling (within the 1-2 % the padding
  // changes between the frame the requirement is read from and the final one).
  ShadowSettings c = s;
  c.map.cascades = 3;
  c.adaptive.max_texel_ws = static_cast<float>(rule_texel / 2);
  const FramePlan cascaded = plan(c);
  ASSERT_EQ(cascaded.cascades.size(), 3u);
  for (const auto& ci : cascaded.cascades)
    EXPECT_GE(ci.resolution_texels * 1.02, ci.light.extent_ws / c.adaptive.max_texel_ws) << ci.split_near_ws;

  // PCSS: a measured requirement below the ceiling is raised to it.
  ShadowSettings p = with(Technique::pcss);
  p.adaptive.enabled = true;
  const scene::Scene demo = scene::make_builtin_scene("demo");
  AdaptiveState state;
  state.last.valid = true;
  state.last.required_texels = {10.0};
  state.last_cascades = 1;
  state.last_c = p.adaptive.c;
  p.adaptive.max_texel_ws = 0.05f;
  const FramePlan measured = plan_frame(p, demo, kWidth, kHeight, state);
  EXPECT_EQ(measured.resolution_source, "pcss_per_pixel");
  EXPECT_NEAR(measured.cascades[0].required_texels, measured.cascades[0].light.extent_ws / 0.05, 0.02 * measured.cascades[0].light.extent_ws / 0.05);
}

// adaptive.min_texel_px: a cascade needs no texel narrower than a pixel footprint at its near
// split; the first cascade (from the camera's near plane) keeps the rule, far ones are capped.
TEST(FramePlan, PixelFloorCapsFarCascadesOnly) {
  ShadowSettings s = adaptive_pcf(0.002f);  // a rule far finer than the pixels
  s.adaptive.quantum_texels = 1;
  s.adaptive.max_texels = 65536;
  s.map.cascades = 4;
  const scene::Scene scene = scene::make_builtin_scene("demo");
  const FramePlan rule = plan(s, scene);
  s.adaptive.min_texel_px = 1;
  const FramePlan floored = plan(s, scene);
  ASSERT_EQ(floored.cascades.size(), 4u);
  const double pixel_per_depth = 2 * std::tan(glm::radians(static_cast<double>(scene.camera.fov_y_deg)) / 2) / kHeight;
  for (std::size_t i = 0; i < 4; ++i) {
    const CascadeInfo& c = floored.cascades[i];
    SCOPED_TRACE(i);
    const double cap = c.light.extent_ws / (c.split_near_ws * pixel_per_depth);
    EXPECT_LE(c.required_texels, rule.cascades[i].required_texels * 1.02);
    if (cap < rule.cascades[i].required_texels / 1.05) {
      EXPECT_NEAR(c.required_texels, cap, 0.02 * cap);
    }
  }
  EXPECT_LT(floored.cascades[3].required_texels, rule.cascades[3].required_texels / 2);  // the far end saves most
  // Twice the pixel footprint: half the texels per side where the floor holds.
  s.adaptive.min_texel_px = 2;
  EXPECT_NEAR(plan(s, scene).cascades[3].required_texels, floored.cascades[3].required_texels / 2,
              0.02 * floored.cascades[3].required_texels);
  // The texel ceiling wins over it.
  s.adaptive.max_texel_ws = 1e-4f;
  EXPECT_GE(plan(s, scene).cascades[3].required_texels * 1.02, floored.cascades[3].light.extent_ws / 1e-4);
}

TEST(FramePlan, RuleClampsAtTheExtremes) {
  ShadowSettings s = adaptive_pcf(1e-6f);  // a vanishing filter wants an infinite map
  EXPECT_EQ(plan(s).cascades[0].resolution_texels, s.adaptive.max_texels);
  s.pcf.radius = 0;
  EXPECT_EQ(plan(s).cascades[0].resolution_texels, s.adaptive.max_texels);
  s.pcf.radius = 1e5f;  // a filter wider than the scene needs the fewest texels
  EXPECT_EQ(plan(s).cascades[0].resolution_texels, s.adaptive.min_texels);
  ShadowSettings hard = with(Technique::hard);  // no filter: the rule has nothing to hide
  hard.adaptive.enabled = true;
  EXPECT_EQ(plan(hard).cascades[0].resolution_texels, hard.adaptive.max_texels);
}

TEST(FramePlan, HysteresisGrowsAtOnceAndShrinksAfterTheDelay) {
  ShadowSettings s = adaptive_pcf(0.1f);
  s.adaptive.shrink_delay_frames = 3;
  const scene::Scene scene = scene::make_builtin_scene("demo");
  AdaptiveState state;
  s.pcf.radius = 0.2f;
  const int coarse = plan_frame(s, scene, kWidth, kHeight, state).cascades[0].resolution_texels;
  s.pcf.radius = 0.05f;
  const int fine = plan_frame(s, scene, kWidth, kHeight, state).cascades[0].resolution_texels;
  EXPECT_GT(fine, coarse);  // grows in the same frame
  s.pcf.radius = 0.2f;
  // Keeps the fine map while the smaller requirement holds, shrinks on the delay-th frame.
  for (int i = 0; i < 2; ++i) EXPECT_EQ(plan_frame(s, scene, kWidth, kHeight, state).cascades[0].resolution_texels, fine) << i;
  EXPECT_LT(plan_frame(s, scene, kWidth, kHeight, state).cascades[0].resolution_texels, fine);
  // A changed cascade count or technique restarts the controllers.
  const std::string key = state.key;
  s.map.cascades = 2;
  plan_frame(s, scene, kWidth, kHeight, state);
  EXPECT_NE(state.key, key);
  EXPECT_EQ(state.controllers.size(), 2u);
}

TEST(FramePlan, SubrectStorageReservesMaxTexelsPerCascade) {
  ShadowSettings s = with(Technique::pcf);
  s.adaptive.enabled = true;
  s.adaptive.max_texels = 1024;
  s.map.cascades = 3;
  const FramePlan p = plan(s);
  EXPECT_TRUE(p.subrect);
  EXPECT_EQ(p.atlas.width, 2 * (1024 + 2 * kGuardTexels));
  EXPECT_EQ(p.atlas.height, 2 * (1024 + 2 * kGuardTexels));
  s.adaptive.storage = Storage::realloc;
  const FramePlan r = plan(s);
  EXPECT_FALSE(r.subrect);
  int cell = 0;
  for (const auto& c : r.cascades) cell = std::max(cell, c.resolution_texels + 2 * kGuardTexels);
  EXPECT_EQ(r.atlas.width, 2 * cell);
}

TEST(FramePlan, AutomaticCascadeCountStaysInRange) {
  ShadowSettings s = adaptive_pcf(0.1f);
  s.map.cascades = 0;
  for (float r : {1e-4f, 0.01f, 0.1f, 10.0f}) {
    s.pcf.radius = r;
    const auto n = plan(s).cascades.size();
    EXPECT_GE(n, 1u) << r;
    EXPECT_LE(n, static_cast<std::size_t>(kMaxCascades)) << r;
  }
}

// The automatic count has hysteresis like each cascade's resolution: it grows at once and drops
// only after the smaller count has sufficed for shrink_delay_frames frames in a row.
TEST(FramePlan, AutomaticCascadeCountGrowsAtOnceAndDropsAfterTheDelay) {
  ShadowSettings s = adaptive_pcf(0.1f);
  s.adaptive.max_texels = 1024;
  s.adaptive.shrink_delay_frames = 3;
  s.map.cascades = 0;
  const scene::Scene scene = scene::make_builtin_scene("demo");
  const float wide = 1.0f, fine = 0.01f;  // one map suffices / needs more cascades
  s.pcf.radius = fine;
  ASSERT_GT(plan(s, scene).cascades.size(), 1u) << "the fine filter must need cascades";
  s.pcf.radius = wide;
  ASSERT_EQ(plan(s, scene).cascades.size(), 1u) << "the wide filter must fit one map";

  AdaptiveState state;
  auto count = [&](float radius) {
    s.pcf.radius = radius;
    return plan_frame(s, scene, kWidth, kHeight, state).cascades.size();
  };
  EXPECT_EQ(count(wide), 1u);
  const std::size_t many = count(fine);  // grows at once
  EXPECT_GT(many, 1u);
  EXPECT_EQ(count(wide), many);
  EXPECT_EQ(count(wide), many);
  EXPECT_EQ(count(fine), many);  // needed again: the wait starts over
  EXPECT_EQ(count(wide), many);
  EXPECT_EQ(count(wide), many);
  EXPECT_EQ(count(wide), 1u);  // the third frame in a row
  // Without a delay the count follows the view every frame.
  s.adaptive.shrink_delay_frames = 0;
  AdaptiveState fresh;
  state = fresh;
  EXPECT_EQ(count(fine), many);
  EXPECT_EQ(count(wide), 1u);
}

TEST(FramePlan, PcssUsesTheMeasuredRequirementWhenLower) {
  ShadowSettings s = with(Technique::pcss);
  s.adaptive.enabled = true;
  const scene::Scene scene = scene::make_builtin_scene("demo");
  AdaptiveState state;
  const FramePlan bound = plan_frame(s, scene, kWidth, kHeight, state);
  EXPECT_EQ(bound.resolution_source, "pcss_min_penumbra");
  state.last.valid = true;
  state.last.required_texels = {100.0};
  state.last_cascades = 1;
  state.last_c = s.adaptive.c;
  AdaptiveState fresh = state;
  fresh.controllers.clear();
  fresh.key.clear();
  const FramePlan measured = plan_frame(s, scene, kWidth, kHeight, fresh);
  EXPECT_EQ(measured.resolution_source, "pcss_per_pixel");
  EXPECT_DOUBLE_EQ(measured.cascades[0].required_texels, std::min(100.0, bound.cascades[0].required_texels));
  // Measured with another c: rescaled to this frame's.
  fresh.last_c = s.adaptive.c / 2;
  fresh.controllers.clear();
  fresh.key.clear();
  EXPECT_DOUBLE_EQ(plan_frame(s, scene, kWidth, kHeight, fresh).cascades[0].required_texels,
                   std::min(200.0, bound.cascades[0].required_texels));
}

TEST(FramePlan, RefusesDegenerateRequests) {
  ShadowSettings s = with(Technique::pcf);
  AdaptiveState state;
  const scene::Scene scene = scene::make_builtin_scene("demo");
  EXPECT_THROW(plan_frame(s, scene, 0, 10, state), std::runtime_error);
  EXPECT_THROW(plan_frame(s, scene, 10, -1, state), std::runtime_error);
  s.map.resolution_texels = 0;
  EXPECT_THROW(plan_frame(s, scene, 10, 10, state), std::runtime_error);
  s.map.resolution_texels = 64;
  s.adaptive.enabled = true;
  s.adaptive.min_texels = 512;
  s.adaptive.max_texels = 256;
  EXPECT_THROW(plan_frame(s, scene, 10, 10, state), std::runtime_error);
}

TEST(FramePlan, AtlasLayoutOfOneToFourCells) {
  EXPECT_EQ(layout_atlas({100}, 0).width, 100);
  const AtlasLayout two = layout_atlas({100, 50}, 2);
  EXPECT_EQ(two.width, 208);
  EXPECT_EQ(two.height, 104);
  EXPECT_EQ(two.origin[1], glm::ivec2(106, 2));
  const AtlasLayout three = layout_atlas({64, 64, 64}, 2);
  EXPECT_EQ(three.height, 136);
  EXPECT_EQ(three.origin[2], glm::ivec2(2, 70));
}

}  // namespace
}  // namespace penumbra::shadows
