// Draw units and culling (scene/mesh.h, scene/culling.h), GL-free: what a unit covers, which
// units a camera or a shadow map drops, the outdoor town as units with bounds, and units split into
// clusters (what a virtual shadow map's page culls by) against a brute-force test per triangle.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/mat4x4.hpp>

#include "scene/culling.h"
#include "scene/outdoor.h"
#include "scene/scene.h"

namespace penumbra::scene {
namespace {

Aabb box_at(glm::vec3 centre, float half) { return {centre - glm::vec3(half), centre + glm::vec3(half)}; }

TEST(DrawUnits, CoverEveryIndexOnceAndAnEmptyCloseAddsNothing) {
  MeshData m;
  EXPECT_TRUE(m.draw_units().empty()) << "an empty mesh has no unit";
  m.append(make_box({1, 1, 1}), glm::mat4(1));
  m.close_unit();
  m.close_unit();  // nothing since the last: no unit
  m.append(make_box({1, 1, 1}), glm::translate(glm::mat4(1), {10, 0, 0}));
  m.append(make_box({2, 2, 2}), glm::translate(glm::mat4(1), {10, 0, 0}));
  m.close_unit();
  m.append(make_box({1, 1, 1}), glm::translate(glm::mat4(1), {0, 0, -20}));  // left open
  ASSERT_EQ(m.units.size(), 2u);
  const std::vector<DrawUnit> units = m.draw_units();
  ASSERT_EQ(units.size(), 3u);
  std::uint32_t next = 0;
  for (const DrawUnit& u : units) {
    EXPECT_EQ(u.first_index, next);
    EXPECT_EQ(u.index_count % 3, 0u);
    next += u.index_count;
  }
  EXPECT_EQ(next, m.indices.size());
  EXPECT_EQ(units[0].bounds.lo, glm::vec3(-0.5f));
  EXPECT_EQ(units[1].bounds.lo, glm::vec3(9, -1, -1)) << "the larger box of the second unit";
  EXPECT_EQ(units[2].bounds.hi, glm::vec3(0.5f, 0.5f, -19.5f));

  MeshData whole = make_sphere(1);
  ASSERT_EQ(whole.draw_units().size(), 1u) << "a mesh without closed units is one unit";
  EXPECT_EQ(whole.draw_units()[0].index_count, whole.indices.size());
}

TEST(Culling, AShadowMapKeepsCastersTowardTheLightAndDropsThoseBesideIt) {
  // A map looking down -y over x, z in [-10, 10], depth range y in [0, 20].
  const glm::mat4 map = glm::ortho(-10.0f, 10.0f, -10.0f, 10.0f, 0.0f, 20.0f) * glm::lookAt(glm::vec3(0, 20, 0), glm::vec3(0), glm::vec3(0, 0, -1));
  EXPECT_TRUE(may_touch(map, box_at({0, 5, 0}, 1), CullVolume::caster));
  EXPECT_TRUE(may_touch(map, box_at({0, 5, 0}, 1), CullVolume::view));
  // Above the near plane (toward the light): still casts into the map; no camera would see it.
  EXPECT_TRUE(may_touch(map, box_at({0, 100, 0}, 1), CullVolume::caster));
  EXPECT_FALSE(may_touch(map, box_at({0, 100, 0}, 1), CullVolume::view));
  // Beside the map's sides: no texel is covered.
  EXPECT_FALSE(may_touch(map, box_at({12, 5, 0}, 1), CullVolume::caster));
  EXPECT_FALSE(may_touch(map, box_at({0, 5, -11.5f}, 1), CullVolume::caster));
  // Straddling a side, or larger than the map: kept.
  EXPECT_TRUE(may_touch(map, box_at({10.5f, 5, 0}, 1), CullVolume::caster));
  EXPECT_TRUE(may_touch(map, box_at({0, 5, 0}, 50), CullVolume::caster));
  EXPECT_FALSE(may_touch(map, Aabb{}, CullVolume::caster)) << "an empty box covers nothing";
}

TEST(Culling, TheCameraDropsWhatIsBehindItOrBeyondItsFarPlane) {
  Camera cam;
  cam.position = {0, 2, 0};
  cam.target = {0, 2, -1};
  cam.far_ws = 50;
  const glm::mat4 vp = cam.projection_matrix(16.0f / 9.0f) * cam.view();
  EXPECT_TRUE(may_touch(vp, box_at({0, 2, -10}, 1), CullVolume::view));
  EXPECT_FALSE(may_touch(vp, box_at({0, 2, 10}, 1), CullVolume::view)) << "behind the camera";
  EXPECT_FALSE(may_touch(vp, box_at({0, 2, -60}, 1), CullVolume::view)) << "beyond the far plane";
  EXPECT_FALSE(may_touch(vp, box_at({40, 2, -10}, 1), CullVolume::view)) << "far to the right";
  EXPECT_TRUE(may_touch(vp, box_at({0, 2, 0}, 1), CullVolume::view)) << "around the eye";
}

TEST(Culling, KeptNeighboursBecomeOneRangeAndTrianglesAreCounted) {
  MeshData m;
  for (float x : {0.0f, 2.0f, 100.0f, 4.0f}) {
    m.append(make_box({1, 1, 1}), glm::translate(glm::mat4(1), {x, 0, 0}));
    m.close_unit();
  }
  const glm::mat4 map = glm::ortho(-10.0f, 10.0f, -10.0f, 10.0f, 0.0f, 20.0f) * glm::lookAt(glm::vec3(0, 10, 0), glm::vec3(0), glm::vec3(0, 0, -1));
  const DrawRanges r = cull_units(m.draw_units(), map, CullVolume::caster);
  const std::uint32_t box = static_cast<std::uint32_t>(make_box({1, 1, 1}).indices.size());
  ASSERT_EQ(r.first_index.size(), 2u) << "boxes 0 and 1 merge; box 2 is dropped; box 3 alone";
  EXPECT_EQ(r.first_index[0], 0u);
  EXPECT_EQ(r.index_count[0], 2 * box);
  EXPECT_EQ(r.first_index[1], 3 * box);
  EXPECT_EQ(r.index_count[1], box);
  EXPECT_EQ(r.triangles, 3u * box / 3);
}

TEST(Culling, FootprintsKeepWhatAPagesCasterVolumeKeeps) {
  MeshData m;
  for (float x : {0.0f, 2.0f, 100.0f, 4.0f}) {
    m.append(make_box({1, 1, 1}), glm::translate(glm::mat4(1), {x, 0, 0}));
    m.close_unit();
  }
  std::vector<DrawUnit> units = m.draw_units();
  units.push_back({0, 36, Aabb{}});  // empty bounds: never kept
  // A light looking down -y: light-space x is world x, light-space y is world -z.
  const glm::mat4 light = glm::lookAt(glm::vec3(0, 10, 0), glm::vec3(0), glm::vec3(0, 0, -1));
  const std::vector<Footprint> f = unit_footprints(units, light);
  ASSERT_EQ(f.size(), units.size());
  // Box 1's corners at x 1.5 and y 0.5, the footprint widened by rounding's margin only (affine_bounds).
  EXPECT_LE(f[1].lo.x, 1.5f);
  EXPECT_GT(f[1].lo.x, 1.5f - 1e-5f);
  EXPECT_GE(f[1].hi.y, 0.5f);
  EXPECT_LT(f[1].hi.y, 0.5f + 1e-5f);
  const DrawRanges r = cull_units(units, f, Footprint{{-1, -1}, {3, 1}});
  const std::uint32_t box = static_cast<std::uint32_t>(make_box({1, 1, 1}).indices.size());
  ASSERT_EQ(r.first_index.size(), 1u) << "boxes 0 and 1 merge; 2 and 3 lie beside the window, 4 is empty";
  EXPECT_EQ(r.index_count[0], 2 * box);
  EXPECT_TRUE(cull_units(units, f, Footprint{{3.6f, -1}, {3.7f, 1}}).triangles > 0) << "a window inside box 3";
  EXPECT_EQ(cull_units(units, f, Footprint{{5, -1}, {99, 1}}).triangles, 0u) << "between boxes 3 and 2";
  // Degenerate windows: one touching box 1's side exactly keeps it (conservative); a point inside
  // box 0 keeps it; an empty (inverted) window keeps nothing.
  EXPECT_EQ(cull_units(units, f, Footprint{{2.5f, -1}, {3.0f, 1}}).triangles, static_cast<std::uint64_t>(box / 3)) << "touches box 1 only";
  EXPECT_EQ(cull_units(units, f, Footprint{{0.1f, 0.1f}, {0.1f, 0.1f}}).triangles, static_cast<std::uint64_t>(box / 3)) << "a point in box 0";
  EXPECT_EQ(cull_units(units, f, Footprint{{1, 1}, {-1, -1}}).triangles, 0u) << "an inverted window";
  // Far from the origin (10 km), a page-sized window still tells apart boxes 2 cm beyond its edge.
  MeshData far;
  for (float x : {10000.0f, 10002.57f}) {
    far.append(make_box({0.5f, 0.5f, 0.5f}), glm::translate(glm::mat4(1), {x, 0, 0}));
    far.close_unit();
  }
  const std::vector<DrawUnit> far_units = far.draw_units();
  const std::vector<Footprint> ff = unit_footprints(far_units, light);
  EXPECT_EQ(cull_units(far_units, ff, Footprint{{9999.0f, -1}, {10002.3f, 1}}).index_count.size(), 1u);
  EXPECT_EQ(cull_units(far_units, ff, Footprint{{9999.0f, -1}, {10002.3f, 1}}).first_index.front(), 0u) << "the first box only";
}

// The eight corners' images in double precision: what unit_footprints and may_touch bound.
void corner_bounds(const glm::mat4& m, const Aabb& box, glm::dvec3& lo, glm::dvec3& hi) {
  lo = glm::dvec3(std::numeric_limits<double>::infinity());
  hi = -lo;
  for (int i = 0; i < 8; ++i) {
    const glm::dvec4 p = glm::dmat4(m) * glm::dvec4(glm::dvec3(box.corner(i)), 1.0);
    lo = glm::min(lo, glm::dvec3(p) / p.w);
    hi = glm::max(hi, glm::dvec3(p) / p.w);
  }
}

TEST(Culling, AffineMatricesBoundBoxesByCentreAndExtentHoldingEveryCornerWithinRounding) {
  // unit_footprints and may_touch bound an affine matrix's image of a box by its centre and half
  // extent instead of eight corners. Against the corners in double precision: every corner lies in
  // the bounds, which exceed the corners by no more than rounding's margin (16 float epsilons of the
  // terms' magnitude), for boxes from a point to 10 km out and matrices with mirrors, shears and a
  // zero scale; a perspective keeps the corners' own bounds.
  std::mt19937 rng(47);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
  std::uniform_int_distribution<int> pick(0, 5);
  int compared = 0, kept_by_corners = 0, kept_only_by_bounds = 0;
  for (int trial = 0; trial < 4000; ++trial) {
    const float reach = std::pow(10.0f, static_cast<float>(pick(rng)) - 1.0f);  // 0.1 m to 10 km
    glm::mat4 m = glm::rotate(glm::mat4(1), 3.2f * unit(rng), glm::normalize(glm::vec3(unit(rng), unit(rng), unit(rng)) + glm::vec3(0, 0, 1e-3f)));
    m = glm::scale(m, {1.0f + unit(rng), trial % 7 == 0 ? 0.0f : 1.0f + 0.5f * unit(rng), trial % 5 == 0 ? -2.0f : 1.0f});  // zero scale, mirror
    m[1][0] += 0.3f * unit(rng);  // shear
    m[3] = glm::vec4(reach * unit(rng), reach * unit(rng), reach * unit(rng), 1.0f);
    const glm::vec3 centre(reach * unit(rng), reach * unit(rng), reach * unit(rng));
    const glm::vec3 half = trial % 11 == 0 ? glm::vec3(0.0f) : glm::abs(glm::vec3(unit(rng), unit(rng), unit(rng))) * (0.01f * reach);  // a point
    const Aabb box{centre - half, centre + half};
    glm::dvec3 lo, hi;
    corner_bounds(m, box, lo, hi);
    const Footprint f = unit_footprints({DrawUnit{0, 3, box}}, m).front();
    double margin = 0;  // 16 epsilons of the terms' magnitude, as affine_bounds widens, and as much again for its rounding
    for (int axis = 0; axis < 2; ++axis) {
      double scale = std::abs(m[3][axis]);
      for (int col = 0; col < 3; ++col) scale += std::abs(m[col][axis]) * std::max(std::abs(box.lo[col]), std::abs(box.hi[col]));
      margin = 32.0 * std::numeric_limits<float>::epsilon() * scale;
      ASSERT_LE(f.lo[axis], lo[axis]) << "trial " << trial << " axis " << axis;
      ASSERT_GE(f.hi[axis], hi[axis]) << "trial " << trial << " axis " << axis;
      ASSERT_GE(f.lo[axis], lo[axis] - margin) << "trial " << trial << " axis " << axis;
      ASSERT_LE(f.hi[axis], hi[axis] + margin) << "trial " << trial << " axis " << axis;
    }
    // may_touch through an orthographic volume around a point near the box: a box the corners put
    // inside is kept, and one dropped while the corners keep it never happens; kept only by the
    // bounds means a corner within the margin of a side.
    const glm::vec3 at = glm::vec3(m * glm::vec4(centre, 1.0f)) + glm::vec3(unit(rng), unit(rng), unit(rng)) * (0.02f * reach);
    const float side = 0.01f * reach;
    const glm::mat4 clip = glm::ortho(-side, side, -side, side, -reach, reach) * glm::translate(glm::mat4(1), -at) * m;
    for (CullVolume volume : {CullVolume::caster, CullVolume::view}) {
      glm::dvec3 clo, chi;
      corner_bounds(clip, box, clo, chi);
      const int axes = volume == CullVolume::view ? 3 : 2;
      bool by_corners = true;
      for (int a = 0; a < axes; ++a) by_corners = by_corners && chi[a] >= -1.0 && clo[a] <= 1.0;
      const bool kept = may_touch(clip, box, volume);
      ++compared;
      if (by_corners) {
        ++kept_by_corners;
        ASSERT_TRUE(kept) << "trial " << trial << ": a box inside the volume dropped";
      } else if (kept) {
        ++kept_only_by_bounds;
        double gap = std::numeric_limits<double>::infinity();
        for (int a = 0; a < axes; ++a) gap = std::min({gap, chi[a] < -1.0 ? -1.0 - chi[a] : gap, clo[a] > 1.0 ? clo[a] - 1.0 : gap});
        EXPECT_LT(gap, 1e-3) << "trial " << trial << ": kept a box " << gap << " of the volume's side away";
      }
    }
  }
  EXPECT_GT(kept_by_corners, compared / 10) << "the volumes must keep some boxes for the comparison to mean anything";
  EXPECT_LT(kept_by_corners, compared * 9 / 10);
  EXPECT_LT(kept_only_by_bounds, compared / 100);
  // A perspective is not affine: its bounds are the corners' own, divided by w.
  const glm::mat4 proj = glm::perspective(1.0f, 1.5f, 0.1f, 100.0f);
  const Aabb box{{-1, -1, -9}, {2, 1, -3}};
  glm::dvec3 lo, hi;
  corner_bounds(proj, box, lo, hi);
  const Footprint f = unit_footprints({DrawUnit{0, 3, box}}, proj).front();
  EXPECT_NEAR(f.lo.x, lo.x, 1e-6);
  EXPECT_NEAR(f.hi.y, hi.y, 1e-6);
}

// The draw units of each run of objects with one name (an object and its instances), bounds in
// world space: what culling tests.
std::vector<std::pair<std::string, std::vector<DrawUnit>>> units_of(const Scene& s) {
  std::vector<std::pair<std::string, std::vector<DrawUnit>>> out;
  for (const auto& o : s.objects) {
    if (out.empty() || out.back().first != o.name) out.emplace_back(o.name, std::vector<DrawUnit>{});
    for (DrawUnit u : o.mesh->draw_units()) {
      u.bounds = u.bounds.transformed(o.model);
      out.back().second.push_back(u);
    }
  }
  return out;
}

TEST(OutdoorUnits, TheTownIsAboutTwoThousandUnitsWithTheSameBoundsForASeed) {
  const Scene a = make_outdoor_scene({});
  const auto units = units_of(a);
  std::size_t total = 0;
  for (const auto& [name, list] : units) {
    SCOPED_TRACE(name);
    total += list.size();
    for (const DrawUnit& u : list) EXPECT_FALSE(u.bounds.empty());
  }
  const auto count = [&](const std::string& name) {
    return std::find_if(units.begin(), units.end(), [&](const auto& p) { return p.first == name; })->second.size();
  };
  EXPECT_EQ(count("ground"), 256u) << "16 × 16 tiles";
  EXPECT_GT(count("buildings"), 300u) << "body, ledges, parapet, each rooftop unit and antenna of 108 buildings";
  EXPECT_GT(count("trees"), 800u) << "the trunk and each main limb of 224 trees";
  EXPECT_GT(count("wires"), 40u) << "one unit per span";
  EXPECT_GT(count("fence"), 30u) << "one unit per panel (an instance each)";
  EXPECT_GT(count("crane"), 50u) << "one unit per mast or jib panel (an instance each)";
  EXPECT_GT(total, 1500u);

  const auto again = units_of(make_outdoor_scene({}));
  ASSERT_EQ(again.size(), units.size());
  for (std::size_t i = 0; i < units.size(); ++i) {
    ASSERT_EQ(again[i].second.size(), units[i].second.size());
    for (std::size_t k = 0; k < units[i].second.size(); ++k) {
      EXPECT_EQ(again[i].second[k].first_index, units[i].second[k].first_index);
      EXPECT_EQ(again[i].second[k].bounds.lo, units[i].second[k].bounds.lo);
      EXPECT_EQ(again[i].second[k].bounds.hi, units[i].second[k].bounds.hi);
    }
  }
  OutdoorOptions other;
  other.seed = 7;
  const auto trees = units_of(make_outdoor_scene(other));
  ASSERT_EQ(trees[5].first, "trees");
  EXPECT_NE(trees[5].second.front().bounds.hi, units[5].second.front().bounds.hi) << "another seed, other trees";
}

TEST(OutdoorUnits, FootprintCullingOfPagesAgreesWithTheCasterVolumeUpToRounding) {
  // A virtual shadow map's pages of a low sun over the town: each window's units by their
  // footprints equal those may_touch keeps for the window's orthographic volume, but for units
  // whose footprint ends within rounding of the window's edge.
  const Scene town = make_outdoor_scene({});
  const glm::mat4 light = glm::lookAt(glm::vec3(0), glm::normalize(glm::vec3(0.5f, -0.6f, 0.3f)), glm::vec3(0, 1, 0));
  std::size_t kept = 0, compared = 0;
  for (const auto& [name, list] : units_of(town)) {
    SCOPED_TRACE(name);
    const std::vector<Footprint> f = unit_footprints(list, light);
    for (float side : {2.56f, 10.24f, 40.96f})
      for (float x = -160; x < 160; x += 37.3f)
        for (float y = -160; y < 160; y += 41.9f) {
          const Footprint window{{x, y}, {x + side, y + side}};
          const glm::mat4 clip = glm::ortho(x, x + side, y, y + side, -500.0f, 500.0f) * light;
          for (std::size_t k = 0; k < list.size(); ++k) {
            const bool by_volume = may_touch(clip, list[k].bounds, CullVolume::caster);
            const bool by_footprint = cull_units({list[k]}, {f[k]}, window).triangles > 0;
            ++compared;
            kept += by_footprint ? 1 : 0;
            if (by_volume == by_footprint) continue;
            const float gap = std::min({std::abs(f[k].hi.x - x), std::abs(f[k].lo.x - x - side), std::abs(f[k].hi.y - y),
                                        std::abs(f[k].lo.y - y - side)});
            EXPECT_LT(gap, 1e-3f) << "unit " << k << " at window (" << x << ", " << y << ") side " << side;
          }
        }
  }
  EXPECT_GT(kept, 1000u) << "of " << compared;
  EXPECT_LT(kept, compared / 4);
}

// Checks that `c` splits `m`'s units into clusters of at most `max_triangles` (0: the units
// themselves) that run through the index list in order, each inside its unit, with the exact
// bounds of the vertices it uses.
void expect_clusters_partition(const MeshData& m, const ClusteredUnits& c, std::uint32_t max_triangles) {
  const std::vector<DrawUnit> units = m.draw_units();
  ASSERT_EQ(c.units.size(), units.size());
  ASSERT_EQ(c.first_cluster.size(), units.size() + 1);
  EXPECT_EQ(c.first_cluster.front(), 0u);
  EXPECT_EQ(c.first_cluster.back(), c.clusters.size());
  std::uint32_t next = 0;  // every index once, in order
  for (std::size_t u = 0; u < units.size(); ++u) {
    EXPECT_EQ(c.units[u].first_index, units[u].first_index);
    EXPECT_EQ(c.units[u].index_count, units[u].index_count);
    ASSERT_LE(c.first_cluster[u], c.first_cluster[u + 1]);
    if (max_triangles == 0) {
      EXPECT_EQ(c.first_cluster[u + 1] - c.first_cluster[u], 1u) << "no split: a unit is its one cluster";
    }
    std::uint32_t in_unit = 0;
    for (std::uint32_t k = c.first_cluster[u]; k < c.first_cluster[u + 1]; ++k) {
      const DrawUnit& cl = c.clusters[k];
      EXPECT_EQ(cl.first_index, next) << "cluster " << k << " is not where the previous one ended";
      EXPECT_GT(cl.index_count, 0u);
      EXPECT_EQ(cl.index_count % 3, 0u) << "whole triangles";
      if (max_triangles > 0) {
        EXPECT_LE(cl.index_count, 3ull * max_triangles);
      }
      Aabb exact;
      for (std::uint32_t i = cl.first_index; i < cl.first_index + cl.index_count; ++i) exact.extend(m.vertices[m.indices[i]].position);
      EXPECT_EQ(cl.bounds.lo, exact.lo) << "cluster " << k;
      EXPECT_EQ(cl.bounds.hi, exact.hi) << "cluster " << k;
      next += cl.index_count;
      in_unit += cl.index_count;
    }
    EXPECT_EQ(in_unit, units[u].index_count) << "unit " << u << "'s clusters hold all its triangles and no other's";
  }
  EXPECT_EQ(next, m.indices.size());
}

// A mesh of units large and small: a sphere of 2304 triangles, a box of 12, a fence of 312 and a
// tube of 8 × 40 left open after the last close.
MeshData mixed_mesh() {
  MeshData m;
  m.append(make_sphere(1.5f), glm::translate(glm::mat4(1), {-3, 2, 0}));
  m.close_unit();
  m.append(make_box({1, 1, 1}), glm::translate(glm::mat4(1), {4, 0.5f, 2}));
  m.close_unit();
  m.append(make_lattice(5, 3, 9, 5, 0.05f), glm::translate(glm::mat4(1), {2, 1.5f, -3}));
  m.close_unit();
  std::vector<glm::vec3> points;
  std::vector<float> radii;
  for (int i = 0; i <= 40; ++i) {
    points.emplace_back(-6 + 0.3f * static_cast<float>(i), 3 + std::sin(0.3f * static_cast<float>(i)), 1);
    radii.push_back(0.1f);
  }
  m.append(make_tube(points, radii, 8), glm::mat4(1));
  return m;
}

TEST(Clusters, CoverEveryTriangleOnceContiguousInsideTheirUnitsWithTheirBounds) {
  const MeshData m = mixed_mesh();
  for (std::uint32_t n : {0u, 1u, 5u, 16u, 64u, 5000u, 0xffffffffu}) {
    SCOPED_TRACE(n);
    const ClusteredUnits c = cluster_units(m, n);
    expect_clusters_partition(m, c, n);
    if (n == 16) {
      EXPECT_EQ(c.first_cluster[1] - c.first_cluster[0], 2304u / 16) << "the sphere in full clusters";
    }
  }
  EXPECT_TRUE(cluster_units(MeshData{}, 16).clusters.empty()) << "an empty mesh has none";
  // Every mesh of the town, at the renderer's size.
  const Scene town = make_outdoor_scene({});
  std::size_t units = 0, clusters = 0;
  for (const Object& o : town.objects) {
    SCOPED_TRACE(o.name);
    const ClusteredUnits c = cluster_units(*o.mesh, 16);
    expect_clusters_partition(*o.mesh, c, 16);
    units += c.units.size();
    clusters += c.clusters.size();
  }
  EXPECT_GT(clusters, 10 * units) << "the town's units are split";
}

TEST(Clusters, CullingByClustersKeepsEveryTriangleOverTheWindowAndFewerThanByUnits) {
  // Brute force: a triangle whose vertices' light-space x, y bounds meet the window must lie in a
  // kept range; and no range keeps anything culling by units would not.
  const MeshData m = mixed_mesh();
  const ClusteredUnits c = cluster_units(m, 16);
  const glm::mat4 light = glm::lookAt(glm::vec3(0), glm::normalize(glm::vec3(-0.4f, -1.0f, -0.3f)), glm::vec3(0, 1, 0));
  const ClusterFootprints f = cluster_footprints(c, light);
  ASSERT_EQ(f.units.size(), c.units.size());
  ASSERT_EQ(f.clusters.size(), c.clusters.size());
  const std::vector<Footprint> unit_f = unit_footprints(c.units, light);
  std::uint64_t by_clusters = 0, by_units = 0, over = 0;
  for (float side : {0.25f, 1.0f, 4.0f})
    for (float x = -8; x < 8; x += 0.7f)
      for (float y = -8; y < 8; y += 0.9f) {
        const Footprint window{{x, y}, {x + side, y + side}};
        const DrawRanges kept = cull_clusters(c, f, window), whole = cull_units(c.units, unit_f, window);
        std::vector<bool> in(m.indices.size() / 3, false), in_whole(m.indices.size() / 3, false);
        std::uint64_t counted = 0;
        for (std::size_t r = 0; r < kept.first_index.size(); ++r) {
          if (r > 0) {
            EXPECT_LT(kept.first_index[r - 1] + kept.index_count[r - 1], kept.first_index[r]) << "neighbours merge";
          }
          for (std::uint32_t i = kept.first_index[r]; i < kept.first_index[r] + kept.index_count[r]; i += 3) in[i / 3] = true, ++counted;
        }
        EXPECT_EQ(counted, kept.triangles);
        for (std::size_t r = 0; r < whole.first_index.size(); ++r)
          for (std::uint32_t i = whole.first_index[r]; i < whole.first_index[r] + whole.index_count[r]; i += 3) in_whole[i / 3] = true;
        for (std::size_t t = 0; t < in.size(); ++t) {
          glm::vec2 lo(std::numeric_limits<float>::infinity()), hi(-std::numeric_limits<float>::infinity());
          for (int k = 0; k < 3; ++k) {
            const glm::vec4 p = light * glm::vec4(m.vertices[m.indices[3 * t + k]].position, 1.0f);
            lo = glm::min(lo, glm::vec2(p)), hi = glm::max(hi, glm::vec2(p));
          }
          const bool overlaps = hi.x >= window.lo.x && lo.x <= window.hi.x && hi.y >= window.lo.y && lo.y <= window.hi.y;
          over += overlaps;
          if (overlaps) {
            EXPECT_TRUE(in[t]) << "triangle " << t << " over window (" << x << ", " << y << ") side " << side << " dropped";
          }
          if (in[t]) {
            EXPECT_TRUE(in_whole[t]) << "triangle " << t << " kept by its cluster but not by its unit";
          }
        }
        by_clusters += kept.triangles;
        by_units += whole.triangles;
      }
  EXPECT_GT(over, 1000u) << "windows over the mesh";
  EXPECT_LT(by_clusters, by_units / 2) << "clusters keep fewer triangles than units: " << by_clusters << " against " << by_units;
  EXPECT_GE(by_clusters, over) << "at least the triangles over the windows";
  // Without a split, culling by clusters is culling by units.
  const ClusteredUnits whole_units = cluster_units(m, 0);
  const Footprint window{{-2, -2}, {1, 1}};
  EXPECT_EQ(cull_clusters(whole_units, cluster_footprints(whole_units, light), window).triangles,
            cull_units(whole_units.units, unit_f, window).triangles);
}

// The triangles of `r` as flags, one per triangle of the index list.
std::vector<bool> triangles_in(const DrawRanges& r, std::size_t triangles) {
  std::vector<bool> in(triangles, false);
  for (std::size_t k = 0; k < r.first_index.size(); ++k)
    for (std::uint32_t i = r.first_index[k]; i < r.first_index[k] + r.index_count[k]; i += 3) in[i / 3] = true;
  return in;
}

TEST(Clusters, AMapsCullingByClustersKeepsEveryTriangleInItsFrustumAndFewerThanByUnits) {
  // Brute force: a triangle whose three vertices do not all lie outside one of a map's four sides
  // (in clip space, x = ±w, y = ±w) must lie in a kept range, wherever it lies in depth (a caster in
  // front of the near plane still casts); and no range keeps what culling by units would not. The
  // maps: cascades' orthographic windows of one light view over a depth range thinner than the
  // mesh, and a spot's perspective aimed around it (corners behind the eye included).
  const MeshData m = mixed_mesh();
  const ClusteredUnits c = cluster_units(m, 16);
  const std::size_t triangles = m.indices.size() / 3;
  const glm::vec3 to_light = glm::normalize(glm::vec3(0.4f, 1.0f, 0.3f));
  const glm::mat4 light = glm::lookAt(20.0f * to_light, glm::vec3(0), glm::vec3(0, 0, -1));
  std::vector<glm::mat4> maps;
  for (float side : {1.0f, 3.0f, 8.0f})
    for (float x = -9; x < 8; x += 1.3f)
      for (float y = -7; y < 6; y += 1.7f) maps.push_back(glm::ortho(x, x + side, y, y + side, 19.0f, 21.0f) * light);
  for (const glm::vec3 target : {glm::vec3(-3, 2, 0), glm::vec3(4, 0.5f, 2), glm::vec3(2, 1.5f, -3), glm::vec3(-4, 3, 1), glm::vec3(6, -2, 9)})
    maps.push_back(glm::perspective(glm::radians(30.0f), 1.0f, 0.5f, 40.0f) * glm::lookAt(glm::vec3(1, 3, 2), target, glm::vec3(0, 1, 0)));
  std::uint64_t by_clusters = 0, by_units = 0, over = 0, in_front = 0;
  for (std::size_t k = 0; k < maps.size(); ++k) {
    const glm::mat4& clip = maps[k];
    const DrawRanges kept = cull_clusters(c, clip, CullVolume::caster), whole = cull_units(c.units, clip, CullVolume::caster);
    for (std::size_t r = 1; r < kept.first_index.size(); ++r) {
      EXPECT_LT(kept.first_index[r - 1] + kept.index_count[r - 1], kept.first_index[r]) << "neighbours merge";
    }
    const std::vector<bool> in = triangles_in(kept, triangles), in_whole = triangles_in(whole, triangles);
    EXPECT_EQ(static_cast<std::uint64_t>(std::count(in.begin(), in.end(), true)), kept.triangles);
    for (std::size_t t = 0; t < triangles; ++t) {
      unsigned outside_all = 0x3fu;  // -x, +x, -y, +y, and for the count: -z, +z
      for (int v = 0; v < 3; ++v) {
        const glm::vec4 p = clip * glm::vec4(m.vertices[m.indices[3 * t + v]].position, 1.0f);
        outside_all &= (p.x < -p.w ? 1u : 0u) | (p.x > p.w ? 2u : 0u) | (p.y < -p.w ? 4u : 0u) | (p.y > p.w ? 8u : 0u) |
                       (p.z < -p.w ? 16u : 0u) | (p.z > p.w ? 32u : 0u);
      }
      if ((outside_all & 0x0fu) == 0) {
        ++over;
        in_front += (outside_all & 16u) != 0;
        EXPECT_TRUE(in[t]) << "triangle " << t << " in map " << k << "'s frustum dropped";
      }
      if (in[t]) {
        EXPECT_TRUE(in_whole[t]) << "triangle " << t << " kept by its cluster but not by its unit, map " << k;
      }
    }
    by_clusters += kept.triangles;
    by_units += whole.triangles;
  }
  EXPECT_GT(over, 10000u) << "maps over the mesh";
  EXPECT_GT(in_front, 1000u) << "triangles in front of the near plane, kept";
  EXPECT_LT(by_clusters, by_units / 2) << "clusters keep fewer triangles than units: " << by_clusters << " against " << by_units;
  EXPECT_GE(by_clusters, over) << "at least the triangles in the frustums";
  // Without a split, culling by clusters is culling by units.
  const ClusteredUnits whole_units = cluster_units(m, 0);
  for (const glm::mat4& clip : {maps[maps.size() / 2], maps.back()}) {
    const DrawRanges a = cull_clusters(whole_units, clip, CullVolume::caster), b = cull_units(whole_units.units, clip, CullVolume::caster);
    EXPECT_EQ(a.first_index, b.first_index);
    EXPECT_EQ(a.index_count, b.index_count);
  }
}

}  // namespace
}  // namespace penumbra::scene
