#include "observers/image_observer.h"

#include <cmath>
#include <numbers>
#include <vector>

namespace penumbra::observers {

namespace {

// Lit fraction of a disk of radius r whose centre is `s` px on the lit side of a straight edge.
double disk_edge(double s, double r) {
  if (s >= r) return 1.0;
  if (s <= -r) return 0.0;
  return 1.0 - (r * r * std::acos(s / r) - s * std::sqrt(r * r - s * s)) / (std::numbers::pi * r * r);
}

std::vector<double> gaussian_blur(const std::vector<double>& img, int n, double sigma) {
  if (sigma <= 0.05) return img;
  const int half = static_cast<int>(std::ceil(3 * sigma));
  std::vector<double> w(2 * half + 1);
  double sum = 0;
  for (int k = -half; k <= half; ++k) sum += w[k + half] = std::exp(-0.5 * k * k / (sigma * sigma));
  for (double& v : w) v /= sum;
  std::vector<double> tmp(img.size()), out(img.size());
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      double acc = 0;
      for (int k = -half; k <= half; ++k) acc += w[k + half] * img[y * n + std::clamp(x + k, 0, n - 1)];
      tmp[y * n + x] = acc;
    }
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      double acc = 0;
      for (int k = -half; k <= half; ++k) acc += w[k + half] * tmp[std::clamp(y + k, 0, n - 1) * n + x];
      out[y * n + x] = acc;
    }
  return out;
}

}  // namespace

double ImageObserver::straightness_residual(const io::Image8& image, const stimuli::StimulusSpec& spec,
                                            const stimuli::Geometry& g, bool add_noise) {
  const int n = image.width;
  std::vector<double> lum(static_cast<std::size_t>(n) * n);
  for (std::size_t i = 0; i < lum.size(); ++i) lum[i] = stimuli::decode(image.pixels[i], spec.transfer);
  lum = gaussian_blur(lum, n, params_.blur_sigma_arcmin / 60.0 * params_.pixels_per_degree);
  // The band around the edge where the stimulus is not flat; noise outside it is the same for
  // both images and only adds variance.
  const double r = spec.filter_radius_px, norm = std::sqrt(1 + g.line_m * g.line_m);
  const double band = r + spec.artifact_px + 2;
  struct Px {
    double u;  // canonical q.y - m q.x
    double v;
  };
  std::vector<Px> px;
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const glm::dvec2 q = g.to_canonical * glm::dvec2(x + 0.5 - 0.5 * n, (n - 1 - y) + 0.5 - 0.5 * n);
      const double u = q.y - g.line_m * q.x;
      if (std::abs(u - g.line_b) / norm > band) continue;
      double v = lum[static_cast<std::size_t>(y) * n + x];
      if (add_noise) {
        // Box–Muller from the platform-independent uniforms.
        const double u1 = 1.0 - random_.uniform(), u2 = random_.uniform();
        v += params_.noise_sd * std::sqrt(-2 * std::log(u1)) * std::cos(2 * std::numbers::pi * u2);
      }
      px.push_back({u, v});
    }
  auto sse = [&](double b) {
    double e = 0;
    for (const Px& p : px) {
      const double d = p.v - spec.lit_linear * disk_edge((p.u - b) / norm, r);
      e += d * d;
    }
    return e;
  };
  // Golden-section search for the edge offset within one texel of the drawn edge.
  double lo = g.line_b - spec.artifact_px, hi = g.line_b + spec.artifact_px;
  const double phi = 0.5 * (std::sqrt(5.0) - 1);
  double x1 = hi - phi * (hi - lo), x2 = lo + phi * (hi - lo), f1 = sse(x1), f2 = sse(x2);
  for (int it = 0; it < 40 && hi - lo > 1e-3; ++it) {
    if (f1 < f2) {
      hi = x2, x2 = x1, f2 = f1, x1 = hi - phi * (hi - lo), f1 = sse(x1);
    } else {
      lo = x1, x1 = x2, f1 = f2, x2 = lo + phi * (hi - lo), f2 = sse(x2);
    }
  }
  return std::min(f1, f2);
}

bool ImageObserver::first_is_jagged(const io::Image8& first, const io::Image8& second,
                                    const stimuli::StimulusSpec& spec, const stimuli::Geometry& g) {
  return straightness_residual(first, spec, g, true) > straightness_residual(second, spec, g, true);
}

}  // namespace penumbra::observers
