#include "metrics/temporal.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace penumbra::metrics {
namespace {

void check(const FrameSample& f, const char* which, int width, int height) {
  const std::string name(which);
  if (!f.visibility || !f.surface) throw std::invalid_argument("flicker: " + name + " frame lacks its visibility or surface image");
  if (f.visibility->channels != 1) throw std::invalid_argument("flicker: " + name + " visibility must have one channel");
  if (f.surface->channels != 4) throw std::invalid_argument("flicker: " + name + " surface image must have four channels");
  if (f.visibility->width != width || f.visibility->height != height || f.surface->width != width || f.surface->height != height)
    throw std::invalid_argument("flicker: " + name + " frame's images differ in size from the current visibility");
}

glm::vec3 position(const io::ImageF& s, int x, int y) { return {s.at(x, y, 0), s.at(x, y, 1), s.at(x, y, 2)}; }

// Distance to the nearer of the two neighbours along one axis on the same object; +inf when
// neither is.
float spacing(const io::ImageF& s, int x, int y, int dx, int dy, float id, const glm::vec3& p) {
  float best = std::numeric_limits<float>::infinity();
  for (int sign : {-1, 1}) {
    const int nx = x + sign * dx, ny = y + sign * dy;
    if (nx < 0 || ny < 0 || nx >= s.width || ny >= s.height || s.at(nx, ny, 3) != id) continue;
    best = std::min(best, glm::distance(position(s, nx, ny), p));
  }
  return best;
}

}  // namespace

Flicker flicker(const FrameSample& previous, const FrameSample& current, const FlickerOptions& options) {
  if (!current.visibility) throw std::invalid_argument("flicker: current frame lacks its visibility image");
  const int w = current.visibility->width, h = current.visibility->height;
  check(current, "current", w, h);
  check(previous, "previous", w, h);
  const io::ImageF& surf = *current.surface;
  const io::ImageF& prev_surf = *previous.surface;
  const io::ImageF& vis = *current.visibility;
  const io::ImageF& prev_vis = *previous.visibility;

  Flicker out;
  double sum = 0, sum_sq = 0;
  std::int64_t changed = 0;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const float id = surf.at(x, y, 3);
      if (id == 0) continue;
      ++out.surface_pixels;
      const glm::vec3 p = position(surf, x, y);
      const float step = std::max(spacing(surf, x, y, 1, 0, id, p), spacing(surf, x, y, 0, 1, id, p));
      if (!std::isfinite(step)) continue;  // a sliver one pixel wide: no surface to interpolate on
      const glm::vec4 clip = previous.view_projection * glm::vec4(p, 1);
      const glm::vec4 clip_now = current.view_projection * glm::vec4(p, 1);
      if (!(clip.w > 0) || !(clip_now.w > 0)) continue;
      const glm::vec3 ndc = glm::vec3(clip) / clip.w;
      // Continuous pixel coordinates in the previous image: centres at integers, rows top down.
      const double u = (static_cast<double>(ndc.x) * 0.5 + 0.5) * w - 0.5;
      const double v = (h - 1) - ((static_cast<double>(ndc.y) * 0.5 + 0.5) * h - 0.5);
      // Within 1/100 of a pixel centre counts as on it: the same view reprojects onto itself
      // exactly, not through small weights (float rounding of the probe's positions) on the neighbours.
      const auto snap = [](double c) { return std::abs(c - std::round(c)) < 1e-2 ? std::round(c) : c; };
      const double su = snap(u), sv = snap(v);
      const double x0 = std::floor(su), y0 = std::floor(sv);
      if (x0 < 0 || y0 < 0 || x0 + 1 >= w || y0 + 1 >= h) continue;
      const double fx = su - x0, fy = sv - y0;
      // The previous pixels sit a pixel apart at the previous distance (perspective: w is depth).
      const float tolerance = static_cast<float>(options.continuity_spacings) * step * std::max(1.0f, clip.w / clip_now.w);
      double interpolated = 0;
      bool continuous = true;
      for (int k = 0; k < 4 && continuous; ++k) {
        const int qx = static_cast<int>(x0) + (k & 1), qy = static_cast<int>(y0) + (k >> 1);
        const double weight = ((k & 1) ? fx : 1 - fx) * ((k >> 1) ? fy : 1 - fy);
        if (weight == 0) continue;
        continuous = prev_surf.at(qx, qy, 3) == id && glm::distance(position(prev_surf, qx, qy), p) <= tolerance;
        interpolated += weight * prev_vis.at(qx, qy);
      }
      if (!continuous) continue;
      const double d = std::abs(static_cast<double>(vis.at(x, y)) - interpolated);
      ++out.matched_pixels;
      sum += d;
      sum_sq += d * d;
      changed += d > options.changed_threshold;
    }
  }
  if (out.matched_pixels > 0) {
    const auto n = static_cast<double>(out.matched_pixels);
    out.mean_abs = sum / n;
    out.rms = std::sqrt(sum_sq / n);
    out.share_changed = static_cast<double>(changed) / n;
  }
  return out;
}

}  // namespace penumbra::metrics
