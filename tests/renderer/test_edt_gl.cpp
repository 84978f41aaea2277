// The GPU Euclidean distance transform against OpenCV's cv::distanceTransform (DIST_L2 with
// DIST_MASK_PRECISE: exact distances; labels only exist for the 5x5 mask, whose Voronoi
// diagram is approximate, so labels are compared by the distance of the site they name) and
// against brute force on small images. Label `gl`.
#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "gl/context.h"
#include "gl/shader_library.h"
#include "gl_test_env.h"
#include "shadows/edt.h"

namespace penumbra {
namespace {

struct Mask {
  std::string name;
  int width, height;
  std::vector<std::uint8_t> sites;  // row-major, != 0: site
  std::uint8_t at(int x, int y) const { return sites[static_cast<std::size_t>(y) * width + x]; }
};

struct Result {
  std::vector<int> nearest;      // x, y per pixel
  std::vector<int> distance_sq;  // per pixel
};

Result run_edt(shadows::Edt& edt, const Mask& m) {
  gl::Texture sites({GL_R8UI, m.width, m.height, 1}, "test sites");
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glTextureSubImage2D(sites.id(), 0, 0, 0, m.width, m.height, GL_RED_INTEGER, GL_UNSIGNED_BYTE, m.sites.data());
  edt.compute(sites);
  Result r;
  const std::size_t n = static_cast<std::size_t>(m.width) * m.height;
  r.nearest.resize(2 * n);
  r.distance_sq.resize(n);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glGetTextureImage(edt.nearest().id(), 0, GL_RG_INTEGER, GL_INT, static_cast<GLsizei>(r.nearest.size() * sizeof(int)),
                    r.nearest.data());
  glGetTextureImage(edt.distance_sq().id(), 0, GL_RED_INTEGER, GL_INT,
                    static_cast<GLsizei>(r.distance_sq.size() * sizeof(int)), r.distance_sq.data());
  gl::check_errors("EDT read-back");
  return r;
}

class EdtTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    library_ = new gl::ShaderLibrary();
    edt_ = new shadows::Edt(*library_);
  }
  static void TearDownTestSuite() {
    delete edt_;
    delete library_;
  }

  // Every check of one mask; `brute_force` for images small enough for the O(n * sites) reference.
  static void check(const Mask& m, bool brute_force) {
    SCOPED_TRACE(m.name + " " + std::to_string(m.width) + "x" + std::to_string(m.height));
    const Result r = run_edt(*edt_, m);
    std::vector<std::pair<int, int>> site_list;
    for (int y = 0; y < m.height; ++y)
      for (int x = 0; x < m.width; ++x)
        if (m.at(x, y)) site_list.emplace_back(x, y);

    if (site_list.empty()) {
      for (std::size_t i = 0; i < r.distance_sq.size(); ++i) {
        ASSERT_EQ(r.distance_sq[i], -1) << "pixel " << i;
        ASSERT_EQ(r.nearest[2 * i], -1);
        ASSERT_EQ(r.nearest[2 * i + 1], -1);
      }
      return;
    }

    // OpenCV: distance to the nearest zero pixel, so sites are the zeros.
    cv::Mat src(m.height, m.width, CV_8UC1);
    for (int y = 0; y < m.height; ++y)
      for (int x = 0; x < m.width; ++x) src.at<std::uint8_t>(y, x) = m.at(x, y) ? 0 : 1;
    cv::Mat precise;
    cv::distanceTransform(src, precise, cv::DIST_L2, cv::DIST_MASK_PRECISE, CV_32F);
    cv::Mat approx, labels;
    cv::distanceTransform(src, approx, labels, cv::DIST_L2, cv::DIST_MASK_5, cv::DIST_LABEL_PIXEL);
    std::vector<std::pair<int, int>> label_site(static_cast<std::size_t>(m.width) * m.height + 1, {-1, -1});
    for (const auto& [x, y] : site_list) label_site[static_cast<std::size_t>(labels.at<int>(y, x))] = {x, y};

    long label_same_distance = 0;
    for (int y = 0; y < m.height; ++y) {
      for (int x = 0; x < m.width; ++x) {
        const std::size_t i = static_cast<std::size_t>(y) * m.width + x;
        const int d2 = r.distance_sq[i];
        const int sx = r.nearest[2 * i], sy = r.nearest[2 * i + 1];
        ASSERT_TRUE(sx >= 0 && sx < m.width && sy >= 0 && sy < m.height) << "(" << x << "," << y << ")";
        ASSERT_TRUE(m.at(sx, sy)) << "nearest of (" << x << "," << y << ") is not a site";
        ASSERT_EQ((x - sx) * (x - sx) + (y - sy) * (y - sy), d2) << "(" << x << "," << y << ")";
        // Exact against OpenCV's precise transform (float sqrt of an exact integer below 2^24).
        const double cv_d = precise.at<float>(y, x);
        ASSERT_EQ(std::lround(cv_d * cv_d), d2) << "(" << x << "," << y << ") OpenCV " << cv_d;
        // OpenCV's labelled site can be no nearer than the exact nearest one.
        const auto [lx, ly] = label_site[static_cast<std::size_t>(labels.at<int>(y, x))];
        ASSERT_GE(lx, 0);
        const int label_d2 = (x - lx) * (x - lx) + (y - ly) * (y - ly);
        ASSERT_GE(label_d2, d2) << "(" << x << "," << y << ")";
        label_same_distance += label_d2 == d2;
      }
    }
    const double n = static_cast<double>(m.width) * m.height;
    ::testing::Test::RecordProperty(m.name + "_opencv_label_exact_fraction", std::to_string(label_same_distance / n));

    if (brute_force) {
      for (int y = 0; y < m.height; ++y)
        for (int x = 0; x < m.width; ++x) {
          int best = std::numeric_limits<int>::max();
          for (const auto& [sx, sy] : site_list) best = std::min(best, (x - sx) * (x - sx) + (y - sy) * (y - sy));
          ASSERT_EQ(r.distance_sq[static_cast<std::size_t>(y) * m.width + x], best) << "(" << x << "," << y << ")";
        }
    }
  }

  static inline gl::ShaderLibrary* library_ = nullptr;
  static inline shadows::Edt* edt_ = nullptr;
};

Mask make(const std::string& name, int w, int h, auto&& is_site) {
  Mask m{name, w, h, std::vector<std::uint8_t>(static_cast<std::size_t>(w) * h)};
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) m.sites[static_cast<std::size_t>(y) * w + x] = is_site(x, y) ? 1 : 0;
  return m;
}

Mask random_mask(int w, int h, double density, unsigned seed) {
  std::mt19937 rng(seed);
  std::bernoulli_distribution site(density);
  return make("random" + std::to_string(density), w, h, [&](int, int) { return site(rng); });
}

TEST_F(EdtTest, RandomMasksOfManyDensitiesAndShapes) {
  const int sizes[][2] = {{64, 64}, {37, 91}, {91, 37}, {128, 33}};
  unsigned seed = 1;
  for (const auto& s : sizes)
    for (double density : {0.0005, 0.01, 0.1, 0.5, 0.95}) check(random_mask(s[0], s[1], density, seed++), true);
}

TEST_F(EdtTest, AdversarialMasks) {
  for (const auto& s : std::vector<std::pair<int, int>>{{1, 1}, {1, 57}, {57, 1}, {2, 2}, {33, 17}, {64, 64}}) {
    const int w = s.first, h = s.second;
    check(make("empty", w, h, [](int, int) { return false; }), true);
    check(make("full", w, h, [](int, int) { return true; }), true);
    check(make("centre", w, h, [&](int x, int y) { return x == w / 2 && y == h / 2; }), true);
    check(make("corner00", w, h, [](int x, int y) { return x == 0 && y == 0; }), true);
    check(make("cornerWH", w, h, [&](int x, int y) { return x == w - 1 && y == h - 1; }), true);
    check(make("cornerW0", w, h, [&](int x, int y) { return x == w - 1 && y == 0; }), true);
    check(make("stripes_x", w, h, [](int x, int) { return x % 7 == 3; }), true);
    check(make("stripes_y", w, h, [](int, int y) { return y % 5 == 0; }), true);
    check(make("diagonal", w, h, [](int x, int y) { return (x + y) % 9 == 0; }), true);
    check(make("checkerboard", w, h, [](int x, int y) { return (x + y) % 2 == 0; }), true);
    check(make("first_column", w, h, [](int x, int) { return x == 0; }), true);
    check(make("last_row", w, h, [&](int, int y) { return y == h - 1; }), true);
    // Two sites far apart on one row: every pixel between them is a tie or a near tie.
    check(make("two_far", w, h, [&](int x, int y) { return y == h / 2 && (x == 0 || x == w - 1); }), true);
    // A circle: many equidistant sites from the centre.
    check(make("circle", w, h, [&](int x, int y) {
            const double r = std::hypot(x - (w - 1) / 2.0, y - (h - 1) / 2.0);
            return std::abs(r - std::min(w, h) / 3.0) < 0.5;
          }),
          true);
  }
}

TEST_F(EdtTest, LongLinesAndScreenSize) {
  check(random_mask(1, 4000, 0.001, 7), true);
  check(random_mask(4000, 1, 0.001, 8), true);
  check(random_mask(1280, 720, 0.001, 9), false);
  // A single site in a corner of a screen-size image: the largest distances.
  check(make("corner", 1280, 720, [](int x, int y) { return x == 1279 && y == 0; }), false);
}

TEST_F(EdtTest, RefusesWrongFormatAndSize) {
  gl::Texture wrong({GL_R8, 4, 4, 1}, "R8 sites");
  EXPECT_THROW(edt_->compute(wrong), std::invalid_argument);
}

// Cost of the transform alone at 1280x720 (median of 5 after a warm-up; wall clock around
// glFinish), reported as a test property.
TEST_F(EdtTest, TimingAt720p) {
  const Mask m = random_mask(1280, 720, 0.01, 11);
  gl::Texture sites({GL_R8UI, m.width, m.height, 1}, "timing sites");
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glTextureSubImage2D(sites.id(), 0, 0, 0, m.width, m.height, GL_RED_INTEGER, GL_UNSIGNED_BYTE, m.sites.data());
  edt_->compute(sites);
  glFinish();
  std::vector<double> ms;
  for (int i = 0; i < 5; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    edt_->compute(sites);
    glFinish();
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  }
  std::sort(ms.begin(), ms.end());
  RecordProperty("edt_1280x720_wall_finish_ms", std::to_string(ms[2]));
  std::printf("EDT 1280x720: median %.2f ms (wall_finish, %s)\n", ms[2], test::GlEnvironment::info().renderer.c_str());
  EXPECT_GT(ms[2], 0.0);
}

}  // namespace
}  // namespace penumbra
