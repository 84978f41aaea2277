#include "observers/image_observer.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <vector>

#include "psychometric/psychometric.h"

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

// Golden-section search for the minimum of f on [lo, hi]; returns the argument, f there in *f_min.
template <class F>
double golden_min(F f, double lo, double hi, double* f_min) {
  const double phi = 0.5 * (std::sqrt(5.0) - 1);
  double x1 = hi - phi * (hi - lo), x2 = lo + phi * (hi - lo), f1 = f(x1), f2 = f(x2);
  for (int it = 0; it < 40 && hi - lo > 1e-3; ++it) {
    if (f1 < f2) {
      hi = x2, x2 = x1, f2 = f1, x1 = hi - phi * (hi - lo), f1 = f(x1);
    } else {
      lo = x1, x1 = x2, f1 = f2, x2 = lo + phi * (hi - lo), f2 = f(x2);
    }
  }
  *f_min = std::min(f1, f2);
  return f1 < f2 ? x1 : x2;
}

double band_half_width(const stimuli::StimulusSpec& spec) { return spec.filter_radius_px + spec.artifact_px + 2; }

}  // namespace

std::vector<ImageObserver::Sample> ImageObserver::band_samples(const io::Image8& image,
                                                                const stimuli::StimulusSpec& spec,
                                                                const stimuli::Geometry& g, bool add_noise) {
  const int n = image.width;
  std::vector<double> lum(static_cast<std::size_t>(n) * n);
  for (std::size_t i = 0; i < lum.size(); ++i) lum[i] = stimuli::decode(image.pixels[i], spec.transfer);
  lum = gaussian_blur(lum, n, params_.blur_sigma_arcmin / 60.0 * params_.pixels_per_degree);
  // The band around the edge where the stimulus is not flat; noise outside it is the same for
  // both images and only adds variance.
  const double norm = std::sqrt(1 + g.line_m * g.line_m), band = band_half_width(spec);
  std::vector<Sample> out;
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const glm::dvec2 q = g.to_canonical * glm::dvec2(x + 0.5 - 0.5 * n, (n - 1 - y) + 0.5 - 0.5 * n);
      const double v = (q.y - g.line_m * q.x - g.line_b) / norm;
      if (std::abs(v) > band) continue;
      double l = lum[static_cast<std::size_t>(y) * n + x];
      if (add_noise) {
        // Box–Muller from the platform-independent uniforms.
        const double u1 = 1.0 - random_.uniform(), u2 = random_.uniform();
        l += params_.noise_sd * std::sqrt(-2 * std::log(u1)) * std::cos(2 * std::numbers::pi * u2);
      }
      out.push_back({(q.x + g.line_m * q.y) / norm, v, l});
    }
  return out;
}

double ImageObserver::straightness_residual(const io::Image8& image, const stimuli::StimulusSpec& spec,
                                            const stimuli::Geometry& g, bool add_noise) {
  const std::vector<Sample> px = band_samples(image, spec, g, add_noise);
  const double r = spec.filter_radius_px;
  auto sse = [&](double e) {
    double sum = 0;
    for (const Sample& p : px) {
      const double d = p.luminance - spec.lit_linear * disk_edge(p.v - e, r);
      sum += d * d;
    }
    return sum;
  };
  double best = 0;
  golden_min(sse, -spec.artifact_px, spec.artifact_px, &best);  // the edge's offset, within a texel
  return best;
}

std::vector<double> ImageObserver::edge_trace(const io::Image8& image, const stimuli::StimulusSpec& spec,
                                              const stimuli::Geometry& g, bool add_noise) {
  std::vector<Sample> px = band_samples(image, spec, g, add_noise);
  std::sort(px.begin(), px.end(), [](const Sample& a, const Sample& b) { return a.s < b.s; });
  const double r = spec.filter_radius_px, a = spec.artifact_px, band = band_half_width(spec);
  const double step = std::max(0.25, std::min(r, a) / 4);
  // Slices of 1 px along the edge, each with how far it reaches across the edge on both sides.
  struct Slice {
    std::size_t begin, end;
    double reach;
  };
  std::vector<Slice> slices;
  double max_reach = 0;
  for (std::size_t begin = 0; begin < px.size();) {
    const double slice = std::floor(px[begin].s);
    std::size_t end = begin;
    double v_min = band, v_max = -band;
    for (; end < px.size() && std::floor(px[end].s) == slice; ++end) {
      v_min = std::min(v_min, px[end].v);
      v_max = std::max(v_max, px[end].v);
    }
    slices.push_back({begin, end, std::min(-v_min, v_max)});
    max_reach = std::max(max_reach, slices.back().reach);
    begin = end;
  }
  // Slices cut short by the stimulus border (near its corners) do not trace the edge; where the
  // band is wider than the stimulus (radius near its half size) the best-covered half suffices.
  const double needed = std::min(band - 1.5, 0.5 * max_reach);
  std::vector<double> trace;
  for (const Slice& sl : slices) {
    if (sl.reach < needed) continue;
    auto sse = [&](double e) {
      double sum = 0;
      for (std::size_t i = sl.begin; i < sl.end; ++i) {
        const double d = px[i].luminance - spec.lit_linear * disk_edge(px[i].v - e, r);
        sum += d * d;
      }
      return sum;
    };
    // A coarse scan first: a jagged edge's slice can sit up to a texel away from the original.
    double best_e = 0, best = INFINITY;
    for (double e = -a - 1; e <= a + 1; e += step) {
      const double f = sse(e);
      if (f < best) best = f, best_e = e;
    }
    trace.push_back(golden_min(sse, best_e - step, best_e + step, &best));
  }
  return trace;
}

double ImageObserver::local_deviation(const io::Image8& image, const stimuli::StimulusSpec& spec,
                                      const stimuli::Geometry& g, bool add_noise) {
  const std::vector<double> e = edge_trace(image, spec, g, add_noise);
  const double r = spec.filter_radius_px;
  const int n = static_cast<int>(e.size());
  if (n < 4) throw std::runtime_error("image observer: the edge crosses fewer than 4 px of the stimulus");
  const int window = std::min(n, std::max(4, static_cast<int>(std::ceil(params_.window_r * r))));
  const int stride = std::max(1, window / 4);
  double worst = 0;
  for (int start = 0;; start += stride) {
    start = std::min(start, n - window);
    // Least-squares line through the window, then the RMS of what it leaves.
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    for (int i = 0; i < window; ++i) {
      const double x = i, y = e[static_cast<std::size_t>(start + i)];
      sx += x, sy += y, sxx += x * x, sxy += x * y;
    }
    const double w = window, slope = (w * sxy - sx * sy) / (w * sxx - sx * sx), offset = (sy - slope * sx) / w;
    double ss = 0;
    for (int i = 0; i < window; ++i) {
      const double d = e[static_cast<std::size_t>(start + i)] - (offset + slope * i);
      ss += d * d;
    }
    worst = std::max(worst, std::sqrt(ss / w));
    if (start + window >= n) break;
  }
  return worst / r;
}

double ImageObserver::decision(const io::Image8& image, const stimuli::StimulusSpec& spec, const stimuli::Geometry& g) {
  if (params_.criterion == StraightnessCriterion::global) return straightness_residual(image, spec, g, true);
  const double u1 = 1.0 - random_.uniform(), u2 = random_.uniform();
  const double z = std::sqrt(-2 * std::log(u1)) * std::cos(2 * std::numbers::pi * u2);
  return local_deviation(image, spec, g, params_.noise_sd > 0) + params_.weber * z;
}

bool ImageObserver::first_is_jagged(const io::Image8& first, const io::Image8& second,
                                    const stimuli::StimulusSpec& spec, const stimuli::Geometry& g) {
  const double d_first = decision(first, spec, g);
  return d_first > decision(second, spec, g);
}

bool ImageObserver::judges_jagged(const io::Image8& image, const stimuli::StimulusSpec& spec,
                                  const stimuli::Geometry& g) {
  if (params_.criterion != StraightnessCriterion::local)
    throw std::invalid_argument("image observer: yes/no answers need the local criterion");
  if (!(params_.false_alarm > 0 && params_.false_alarm < 1))
    throw std::invalid_argument("image observer: false_alarm must be in (0, 1)");
  // The observer knows what a straight edge at this blur looks like on this display: its own
  // straight template (the analytic filtered edge, quantized to 8 bits like the stimulus) has a
  // small deviation d0 (quantization). A straight stimulus then gives d0 + N(0, weber), which
  // exceeds d0 + z(1 - fa) weber with probability fa.
  io::Image8 straight{image.width, image.height, 1, std::vector<std::uint8_t>(image.pixels.size())};
  const int n = image.width;
  const double norm = std::sqrt(1 + g.line_m * g.line_m);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const glm::dvec2 q = g.to_canonical * glm::dvec2(x + 0.5 - 0.5 * n, (n - 1 - y) + 0.5 - 0.5 * n);
      const double v = (q.y - g.line_m * q.x - g.line_b) / norm;
      straight.at(x, y) = stimuli::encode(spec.lit_linear * disk_edge(v, spec.filter_radius_px), spec.transfer);
    }
  const double d0 = local_deviation(straight, spec, g, false);
  const double criterion = d0 + std::sqrt(2.0) * psychometric::inverse_erf(1 - 2 * params_.false_alarm) * params_.weber;
  return decision(image, spec, g) > criterion;
}

}  // namespace penumbra::observers
