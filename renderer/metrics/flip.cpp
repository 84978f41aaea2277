#include "metrics/flip.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "metrics/image_checks.h"

namespace penumbra::metrics {
namespace {

constexpr double kPi = 3.14159265358979323846;
using C = FlipConstants;
using Mat3 = std::array<std::array<double, 3>, 3>;

// Linear sRGB to CIE XYZ, D65: the sRGB standard's matrix (IEC 61966-2-1) in the exact fractions
// the reference implementation uses, so that its white point comes out as theirs.
constexpr Mat3 kRgbToXyz = {{{10135552.0 / 24577794.0, 8788810.0 / 24577794.0, 4435075.0 / 24577794.0},
                             {2613072.0 / 12288897.0, 8788810.0 / 12288897.0, 887015.0 / 12288897.0},
                             {1425312.0 / 73733382.0, 8788810.0 / 73733382.0, 70074185.0 / 73733382.0}}};

Mat3 inverse(const Mat3& m) {
  const double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                     m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
  Mat3 r{};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      // cofactor of m[j][i]
      const int a = (j + 1) % 3, b = (j + 2) % 3, c = (i + 1) % 3, d = (i + 2) % 3;
      r[i][j] = (m[a][c] * m[b][d] - m[a][d] * m[b][c]) / det;
    }
  return r;
}

struct Colour {
  double v[3];
};

Colour mul(const Mat3& m, const Colour& c) {
  Colour r{};
  for (int i = 0; i < 3; ++i) r.v[i] = m[i][0] * c.v[0] + m[i][1] * c.v[1] + m[i][2] * c.v[2];
  return r;
}

// The display's white (linear RGB 1, 1, 1) in XYZ: the reference white of YCxCz and L*a*b*.
Colour white() { return mul(kRgbToXyz, {{1.0, 1.0, 1.0}}); }

double srgb_to_linear(double v) { return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4); }

// CIE L*a*b* from XYZ relative to `w`.
Colour xyz_to_lab(const Colour& xyz, const Colour& w) {
  constexpr double delta = 6.0 / 29.0;
  auto f = [](double t) { return t > delta * delta * delta ? std::cbrt(t) : t / (3.0 * delta * delta) + 4.0 / 29.0; };
  const double fx = f(xyz.v[0] / w.v[0]), fy = f(xyz.v[1] / w.v[1]), fz = f(xyz.v[2] / w.v[2]);
  return {{116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)}};
}

// Hunt adjustment: chroma shrinks with lightness (a, b times L/100).
Colour hunt(const Colour& lab) { return {{lab.v[0], 0.01 * lab.v[0] * lab.v[1], 0.01 * lab.v[0] * lab.v[2]}}; }

double hyab(const Colour& p, const Colour& q) {
  return std::abs(p.v[0] - q.v[0]) + std::hypot(p.v[1] - q.v[1], p.v[2] - q.v[2]);
}

// c_max: the largest HyAB^q_c between two colours of the RGB cube, green against blue (Hunt-adjusted).
double cmax() {
  const Colour w = white();
  const Colour green = hunt(xyz_to_lab(mul(kRgbToXyz, {{0, 1, 0}}), w));
  const Colour blue = hunt(xyz_to_lab(mul(kRgbToXyz, {{0, 0, 1}}), w));
  return std::pow(hyab(green, blue), C::qc);
}

// The contrast-sensitivity Gaussian a·√(π/b)·exp(−π²x²/b) split into two 1D factors whose outer
// products sum to the 2D filter: √(a·√(π/b))·exp(−π²x²/b) for each of the (up to) two Gaussians of a
// channel, both scaled by 1/√(S1² + S2²) (S: a factor's sum), so that the 2D filter sums to 1.
struct SpatialKernels {
  cv::Mat first, second;  // CV_32F rows; `second` empty where a2 = 0
};

int spatial_radius(double ppd) {
  double b_max = 0;
  for (int c = 0; c < 3; ++c) b_max = std::max({b_max, C::b1[c], C::b2[c]});
  return static_cast<int>(std::ceil(3.0 * std::sqrt(b_max / (2.0 * kPi * kPi)) * ppd));
}

SpatialKernels spatial_kernels(int channel, double ppd, int radius) {
  const int n = 2 * radius + 1;
  std::vector<double> k1(static_cast<std::size_t>(n)), k2(static_cast<std::size_t>(n));
  double s1 = 0, s2 = 0;
  for (int i = 0; i < n; ++i) {
    const double x_deg = (i - radius) / ppd;
    const double x2 = x_deg * x_deg;
    k1[static_cast<std::size_t>(i)] = std::sqrt(C::a1[channel] * std::sqrt(kPi / C::b1[channel])) * std::exp(-kPi * kPi * x2 / C::b1[channel]);
    k2[static_cast<std::size_t>(i)] = std::sqrt(C::a2[channel] * std::sqrt(kPi / C::b2[channel])) * std::exp(-kPi * kPi * x2 / C::b2[channel]);
    s1 += k1[static_cast<std::size_t>(i)];
    s2 += k2[static_cast<std::size_t>(i)];
  }
  const double norm = 1.0 / std::sqrt(s1 * s1 + s2 * s2);
  SpatialKernels k;
  k.first = cv::Mat(1, n, CV_32F);
  for (int i = 0; i < n; ++i) k.first.at<float>(i) = static_cast<float>(k1[static_cast<std::size_t>(i)] * norm);
  if (C::a2[channel] != 0) {
    k.second = cv::Mat(1, n, CV_32F);
    for (int i = 0; i < n; ++i) k.second.at<float>(i) = static_cast<float>(k2[static_cast<std::size_t>(i)] * norm);
  }
  return k;
}

// Correlation with the separable kernel kx (along rows) ⊗ ky (along columns), edges repeated.
cv::Mat separable(const cv::Mat& src, const cv::Mat& kx, const cv::Mat& ky) {
  cv::Mat dst;
  cv::sepFilter2D(src, dst, CV_32F, kx, ky, cv::Point(-1, -1), 0.0, cv::BORDER_REPLICATE);
  return dst;
}

cv::Mat spatial_filter(const cv::Mat& plane, const SpatialKernels& k) {
  cv::Mat out = separable(plane, k.first, k.first);
  if (!k.second.empty()) out += separable(plane, k.second, k.second);
  return out;
}

// The Gaussian (g), its first (dg) and second (ddg) derivative along one axis, σ = w/2 degrees.
// g sums to 1; the positive weights of dg and ddg sum to 1 and their negative weights to −1, so that
// a constant image gives 0 and a unit step a response of 1.
struct FeatureKernels {
  cv::Mat g, dg, ddg;
};

FeatureKernels feature_kernels(double ppd) {
  const double sigma = 0.5 * C::w_deg * ppd;
  const int radius = static_cast<int>(std::ceil(3.0 * sigma));
  const int n = 2 * radius + 1;
  std::vector<double> g(static_cast<std::size_t>(n)), dg(g.size()), ddg(g.size());
  double g_sum = 0, dg_pos = 0, dg_neg = 0, ddg_pos = 0, ddg_neg = 0;
  for (int i = 0; i < n; ++i) {
    const double x = i - radius;
    const auto u = static_cast<std::size_t>(i);
    g[u] = std::exp(-x * x / (2.0 * sigma * sigma));
    dg[u] = -x * g[u];
    ddg[u] = (x * x / (sigma * sigma) - 1.0) * g[u];
    g_sum += g[u];
    (dg[u] > 0 ? dg_pos : dg_neg) += std::abs(dg[u]);
    (ddg[u] > 0 ? ddg_pos : ddg_neg) += std::abs(ddg[u]);
  }
  // At a fraction of a pixel per degree σ is so small that the outer taps underflow to 0: a side
  // with no weight stays 0 instead of 0/0.
  auto normalized = [](double v, double positive_sum, double negative_sum) {
    const double sum = v > 0 ? positive_sum : negative_sum;
    return sum > 0 ? v / sum : 0.0;
  };
  FeatureKernels k{cv::Mat(1, n, CV_32F), cv::Mat(1, n, CV_32F), cv::Mat(1, n, CV_32F)};
  for (int i = 0; i < n; ++i) {
    const auto u = static_cast<std::size_t>(i);
    k.g.at<float>(i) = static_cast<float>(g[u] / g_sum);
    k.dg.at<float>(i) = static_cast<float>(normalized(dg[u], dg_pos, dg_neg));
    k.ddg.at<float>(i) = static_cast<float>(normalized(ddg[u], ddg_pos, ddg_neg));
  }
  return k;
}

void check_image(const image::ImageF& img, const char* role) {
  if (img.width <= 0 || img.height <= 0)
    throw std::invalid_argument(std::string("LDR-FLIP: the ") + role + " image is empty (" + std::to_string(img.width) + "×" +
                                std::to_string(img.height) + ")");
  if (img.channels < 1 || img.channels > 4)
    throw std::invalid_argument(std::string("LDR-FLIP: the ") + role + " image has " + std::to_string(img.channels) +
                                " channels; expected 1 (grey), 2 (grey, alpha), 3 (RGB) or 4 (RGBA)");
  const std::size_t expected = static_cast<std::size_t>(img.width) * static_cast<std::size_t>(img.height) * static_cast<std::size_t>(img.channels);
  if (img.pixels.size() != expected)
    throw std::invalid_argument(std::string("LDR-FLIP: the ") + role + " image holds " + std::to_string(img.pixels.size()) +
                                " values, expected width × height × channels = " + std::to_string(expected));
  for (std::size_t i = 0; i < img.pixels.size(); ++i)
    if (!std::isfinite(img.pixels[i])) {
      const std::size_t p = i / static_cast<std::size_t>(img.channels);
      throw std::invalid_argument(std::string("LDR-FLIP: the ") + role + " image has a non-finite value at pixel (" +
                                  std::to_string(p % static_cast<std::size_t>(img.width)) + ", " +
                                  std::to_string(p / static_cast<std::size_t>(img.width)) + ")");
    }
}

// The image as YCxCz planes (CV_32F): values clamped to [0, 1], decoded from sRGB where encoded so.
std::array<cv::Mat, 3> to_ycxcz(const image::ImageF& img, Encoding encoding) {
  const Colour w = white();
  std::array<cv::Mat, 3> planes;
  for (auto& p : planes) p = cv::Mat(img.height, img.width, CV_32F);
  const int grey = img.channels < 3;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      Colour rgb{};
      for (int c = 0; c < 3; ++c) {
        const double v = std::clamp(static_cast<double>(img.at(x, y, grey ? 0 : c)), 0.0, 1.0);
        rgb.v[c] = encoding == Encoding::srgb ? srgb_to_linear(v) : v;
      }
      const Colour xyz = mul(kRgbToXyz, rgb);
      const double xn = xyz.v[0] / w.v[0], yn = xyz.v[1] / w.v[1], zn = xyz.v[2] / w.v[2];
      planes[0].at<float>(y, x) = static_cast<float>(116.0 * yn - 16.0);
      planes[1].at<float>(y, x) = static_cast<float>(500.0 * (xn - yn));
      planes[2].at<float>(y, x) = static_cast<float>(200.0 * (yn - zn));
    }
  return planes;
}

// Hunt-adjusted L*a*b* of a blurred YCxCz pixel, through linear RGB clamped to the unit cube (the
// blur may leave the gamut).
Colour filtered_to_hunt_lab(double yc, double cx, double cz, const Mat3& xyz_to_rgb, const Colour& w) {
  const double yn = (yc + 16.0) / 116.0;
  const Colour xyz{{(yn + cx / 500.0) * w.v[0], yn * w.v[1], (yn - cz / 200.0) * w.v[2]}};
  Colour rgb = mul(xyz_to_rgb, xyz);
  for (double& v : rgb.v) v = std::clamp(v, 0.0, 1.0);
  return hunt(xyz_to_lab(mul(kRgbToXyz, rgb), w));
}

// Edge and point strengths of the normalized luminance Y/Y_n = (Y' + 16)/116.
struct Features {
  cv::Mat edge, point;
};

Features features(const cv::Mat& ycxcz_y, const FeatureKernels& k) {
  cv::Mat lum;
  ycxcz_y.convertTo(lum, CV_32F, 1.0 / 116.0, 16.0 / 116.0);
  Features f;
  cv::magnitude(separable(lum, k.dg, k.g), separable(lum, k.g, k.dg), f.edge);
  cv::magnitude(separable(lum, k.ddg, k.g), separable(lum, k.g, k.ddg), f.point);
  return f;
}

void check_options(const FlipOptions& options) {
  const double ppd = options.pixels_per_degree;
  if (!(std::isfinite(ppd) && ppd > 0))
    throw std::invalid_argument("LDR-FLIP: pixels per degree must be finite and positive, got " + std::to_string(ppd));
  if (!(options.threshold >= 0 && options.threshold <= 1))
    throw std::invalid_argument("LDR-FLIP: threshold must lie in [0, 1], got " + std::to_string(options.threshold));
}

// One image's half of LDR-FLIP: the Hunt-adjusted L*a*b* of its filtered colours, and its edge and
// point strengths.
struct Prepared {
  std::vector<double> lab;  // 3 per pixel
  cv::Mat edge, point;
};

Prepared prepare(const image::ImageF& img, Encoding encoding, double ppd) {
  const std::array<cv::Mat, 3> planes = to_ycxcz(img, encoding);
  // Colour: each opponent channel through its contrast-sensitivity filter.
  const int radius = spatial_radius(ppd);
  std::array<cv::Mat, 3> filtered;
  for (int c = 0; c < 3; ++c) {
    const auto u = static_cast<std::size_t>(c);
    filtered[u] = spatial_filter(planes[u], spatial_kernels(c, ppd, radius));
  }
  const Colour w = white();
  const Mat3 xyz_to_rgb = inverse(kRgbToXyz);
  Prepared p;
  p.lab.resize(3 * static_cast<std::size_t>(img.width) * static_cast<std::size_t>(img.height));
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      const Colour lab = filtered_to_hunt_lab(filtered[0].at<float>(y, x), filtered[1].at<float>(y, x), filtered[2].at<float>(y, x),
                                              xyz_to_rgb, w);
      const std::size_t i = 3 * (static_cast<std::size_t>(y) * static_cast<std::size_t>(img.width) + static_cast<std::size_t>(x));
      for (std::size_t c = 0; c < 3; ++c) p.lab[i + c] = lab.v[c];
    }
  // Features: on the unfiltered luminance.
  Features f = features(planes[0], feature_kernels(ppd));
  p.edge = std::move(f.edge);
  p.point = std::move(f.point);
  return p;
}

std::vector<float> to_vector(const cv::Mat& m) {
  CV_Assert(m.type() == CV_32F && m.isContinuous());
  return std::vector<float>(m.ptr<float>(), m.ptr<float>() + m.total());
}

}  // namespace

double pixels_per_degree(double width_px, double width_m, double distance_m) {
  if (!(std::isfinite(width_px) && width_px > 0) || !(std::isfinite(width_m) && width_m > 0) ||
      !(std::isfinite(distance_m) && distance_m > 0))
    throw std::invalid_argument("pixels per degree: width in pixels, width and distance must be finite and positive");
  return 2.0 * distance_m * std::tan(0.5 * kPi / 180.0) * width_px / width_m;
}

FlipReference::FlipReference(const image::ImageF& reference, Encoding encoding, const FlipOptions& options) : options_(options) {
  check_image(reference, "reference");
  check_options(options);
  width_ = reference.width;
  height_ = reference.height;
  Prepared p = prepare(reference, encoding, options.pixels_per_degree);
  lab_ = std::move(p.lab);
  edge_ = to_vector(p.edge);
  point_ = to_vector(p.point);
}

FlipResult FlipReference::compare(const image::ImageF& test, Encoding test_encoding) const {
  check_image(test, "test");
  check_same_size("LDR-FLIP", width_, height_, test.width, test.height);
  const Prepared t = prepare(test, test_encoding, options_.pixels_per_degree);
  const double c_max = cmax(), pc_cmax = C::pc * c_max;
  FlipResult result;
  result.pixels_per_degree = options_.pixels_per_degree;
  result.map = image::ImageF{width_, height_, 1, std::vector<float>(static_cast<std::size_t>(width_) * static_cast<std::size_t>(height_))};
  for (int y = 0; y < height_; ++y)
    for (int x = 0; x < width_; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(x);
      const Colour p{{lab_[3 * i], lab_[3 * i + 1], lab_[3 * i + 2]}};
      const Colour q{{t.lab[3 * i], t.lab[3 * i + 1], t.lab[3 * i + 2]}};
      const double e = std::pow(hyab(p, q), C::qc);
      // [0, p_c·c_max) onto [0, p_t); the rest, up to c_max, onto [p_t, 1].
      const double delta_c = e < pc_cmax ? C::pt / pc_cmax * e : C::pt + (e - pc_cmax) / (c_max - pc_cmax) * (1.0 - C::pt);
      const double edge = std::abs(static_cast<double>(edge_[i]) - t.edge.at<float>(y, x));
      const double point = std::abs(static_cast<double>(point_[i]) - t.point.at<float>(y, x));
      const double delta_f = std::pow(std::max(edge, point) / std::sqrt(2.0), C::qf);
      result.map.at(x, y) = static_cast<float>(std::clamp(std::pow(delta_c, 1.0 - delta_f), 0.0, 1.0));
    }
  result.pooled = pool_flip(result.map, options_.threshold);
  return result;
}

FlipResult ldr_flip(const image::ImageF& reference, Encoding reference_encoding, const image::ImageF& test, Encoding test_encoding,
                    const FlipOptions& options) {
  check_image(reference, "reference");
  check_image(test, "test");
  check_same_size("LDR-FLIP", reference.width, reference.height, test.width, test.height);
  return FlipReference(reference, reference_encoding, options).compare(test, test_encoding);
}

FlipPooled pool_flip(const image::ImageF& map, double threshold) {
  if (map.channels != 1 || map.width <= 0 || map.height <= 0 ||
      map.pixels.size() != static_cast<std::size_t>(map.width) * static_cast<std::size_t>(map.height))
    throw std::invalid_argument("pool_flip: expected a one-channel map, got " + std::to_string(map.width) + "×" +
                                std::to_string(map.height) + "×" + std::to_string(map.channels));
  if (!(threshold >= 0 && threshold <= 1)) throw std::invalid_argument("pool_flip: threshold must lie in [0, 1], got " + std::to_string(threshold));
  std::vector<double> v(map.pixels.begin(), map.pixels.end());
  std::sort(v.begin(), v.end());
  FlipPooled p;
  p.pixels = static_cast<std::int64_t>(v.size());
  p.threshold = threshold;
  p.min = v.front();
  p.max = v.back();
  double total = 0;
  std::int64_t above = 0;
  for (const double x : v) {
    total += x;
    above += x > threshold;
  }
  p.mean = total / static_cast<double>(v.size());
  p.share_above = static_cast<double>(above) / static_cast<double>(v.size());
  // The smallest value at which the running sum of the sorted values passes `share` of the total.
  auto weighted = [&](double share) {
    double running = 0;
    for (const double x : v) {
      running += x;
      if (running > share * total) return x;
    }
    return 0.0;  // total 0: no error to share
  };
  p.weighted_q1 = weighted(0.25);
  p.weighted_median = weighted(0.5);
  p.weighted_q3 = weighted(0.75);
  return p;
}

image::Image8 flip_magma(const image::ImageF& map) {
  // matplotlib's magma (Smith and van der Walt, CC0; matplotlib 3.6's 256-entry table), sRGB code
  // values, entry 0 for 0 and 255 for 1.
  static constexpr std::uint8_t kMagma[256][3] = {
      {0, 0, 4}, {1, 0, 5}, {1, 1, 6}, {1, 1, 8}, {2, 1, 9}, {2, 2, 11}, {2, 2, 13}, {3, 3, 15},
      {3, 3, 18}, {4, 4, 20}, {5, 4, 22}, {6, 5, 24}, {6, 5, 26}, {7, 6, 28}, {8, 7, 30}, {9, 7, 32},
      {10, 8, 34}, {11, 9, 36}, {12, 9, 38}, {13, 10, 41}, {14, 11, 43}, {16, 11, 45}, {17, 12, 47}, {18, 13, 49},
      {19, 13, 52}, {20, 14, 54}, {21, 14, 56}, {22, 15, 59}, {24, 15, 61}, {25, 16, 63}, {26, 16, 66}, {28, 16, 68},
      {29, 17, 71}, {30, 17, 73}, {32, 17, 75}, {33, 17, 78}, {34, 17, 80}, {36, 18, 83}, {37, 18, 85}, {39, 18, 88},
      {41, 17, 90}, {42, 17, 92}, {44, 17, 95}, {45, 17, 97}, {47, 17, 99}, {49, 17, 101}, {51, 16, 103}, {52, 16, 105},
      {54, 16, 107}, {56, 16, 108}, {57, 15, 110}, {59, 15, 112}, {61, 15, 113}, {63, 15, 114}, {64, 15, 116}, {66, 15, 117},
      {68, 15, 118}, {69, 16, 119}, {71, 16, 120}, {73, 16, 120}, {74, 16, 121}, {76, 17, 122}, {78, 17, 123}, {79, 18, 123},
      {81, 18, 124}, {82, 19, 124}, {84, 19, 125}, {86, 20, 125}, {87, 21, 126}, {89, 21, 126}, {90, 22, 126}, {92, 22, 127},
      {93, 23, 127}, {95, 24, 127}, {96, 24, 128}, {98, 25, 128}, {100, 26, 128}, {101, 26, 128}, {103, 27, 128}, {104, 28, 129},
      {106, 28, 129}, {107, 29, 129}, {109, 29, 129}, {110, 30, 129}, {112, 31, 129}, {114, 31, 129}, {115, 32, 129}, {117, 33, 129},
      {118, 33, 129}, {120, 34, 129}, {121, 34, 130}, {123, 35, 130}, {124, 35, 130}, {126, 36, 130}, {128, 37, 130}, {129, 37, 129},
      {131, 38, 129}, {132, 38, 129}, {134, 39, 129}, {136, 39, 129}, {137, 40, 129}, {139, 41, 129}, {140, 41, 129}, {142, 42, 129},
      {144, 42, 129}, {145, 43, 129}, {147, 43, 128}, {148, 44, 128}, {150, 44, 128}, {152, 45, 128}, {153, 45, 128}, {155, 46, 127},
      {156, 46, 127}, {158, 47, 127}, {160, 47, 127}, {161, 48, 126}, {163, 48, 126}, {165, 49, 126}, {166, 49, 125}, {168, 50, 125},
      {170, 51, 125}, {171, 51, 124}, {173, 52, 124}, {174, 52, 123}, {176, 53, 123}, {178, 53, 123}, {179, 54, 122}, {181, 54, 122},
      {183, 55, 121}, {184, 55, 121}, {186, 56, 120}, {188, 57, 120}, {189, 57, 119}, {191, 58, 119}, {192, 58, 118}, {194, 59, 117},
      {196, 60, 117}, {197, 60, 116}, {199, 61, 115}, {200, 62, 115}, {202, 62, 114}, {204, 63, 113}, {205, 64, 113}, {207, 64, 112},
      {208, 65, 111}, {210, 66, 111}, {211, 67, 110}, {213, 68, 109}, {214, 69, 108}, {216, 69, 108}, {217, 70, 107}, {219, 71, 106},
      {220, 72, 105}, {222, 73, 104}, {223, 74, 104}, {224, 76, 103}, {226, 77, 102}, {227, 78, 101}, {228, 79, 100}, {229, 80, 100},
      {231, 82, 99}, {232, 83, 98}, {233, 84, 98}, {234, 86, 97}, {235, 87, 96}, {236, 88, 96}, {237, 90, 95}, {238, 91, 94},
      {239, 93, 94}, {240, 95, 94}, {241, 96, 93}, {242, 98, 93}, {242, 100, 92}, {243, 101, 92}, {244, 103, 92}, {244, 105, 92},
      {245, 107, 92}, {246, 108, 92}, {246, 110, 92}, {247, 112, 92}, {247, 114, 92}, {248, 116, 92}, {248, 118, 92}, {249, 120, 93},
      {249, 121, 93}, {249, 123, 93}, {250, 125, 94}, {250, 127, 94}, {250, 129, 95}, {251, 131, 95}, {251, 133, 96}, {251, 135, 97},
      {252, 137, 97}, {252, 138, 98}, {252, 140, 99}, {252, 142, 100}, {252, 144, 101}, {253, 146, 102}, {253, 148, 103}, {253, 150, 104},
      {253, 152, 105}, {253, 154, 106}, {253, 155, 107}, {254, 157, 108}, {254, 159, 109}, {254, 161, 110}, {254, 163, 111}, {254, 165, 113},
      {254, 167, 114}, {254, 169, 115}, {254, 170, 116}, {254, 172, 118}, {254, 174, 119}, {254, 176, 120}, {254, 178, 122}, {254, 180, 123},
      {254, 182, 124}, {254, 183, 126}, {254, 185, 127}, {254, 187, 129}, {254, 189, 130}, {254, 191, 132}, {254, 193, 133}, {254, 194, 135},
      {254, 196, 136}, {254, 198, 138}, {254, 200, 140}, {254, 202, 141}, {254, 204, 143}, {254, 205, 144}, {254, 207, 146}, {254, 209, 148},
      {254, 211, 149}, {254, 213, 151}, {254, 215, 153}, {254, 216, 154}, {253, 218, 156}, {253, 220, 158}, {253, 222, 160}, {253, 224, 161},
      {253, 226, 163}, {253, 227, 165}, {253, 229, 167}, {253, 231, 169}, {253, 233, 170}, {253, 235, 172}, {252, 236, 174}, {252, 238, 176},
      {252, 240, 178}, {252, 242, 180}, {252, 244, 182}, {252, 246, 184}, {252, 247, 185}, {252, 249, 187}, {252, 251, 189}, {252, 253, 191},
  };
  image::Image8 out{map.width, map.height, 3, std::vector<std::uint8_t>(static_cast<std::size_t>(map.width) * static_cast<std::size_t>(map.height) * 3)};
  for (int y = 0; y < map.height; ++y)
    for (int x = 0; x < map.width; ++x) {
      const double v = std::clamp(static_cast<double>(map.at(x, y, 0)), 0.0, 1.0);
      const auto i = static_cast<std::size_t>(std::lround(255.0 * v));
      for (int c = 0; c < 3; ++c) out.at(x, y, c) = kMagma[i][c];
    }
  return out;
}

}  // namespace penumbra::metrics
