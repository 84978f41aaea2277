#include "stimuli/reference.h"

#include <opencv2/core.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "json/json_input.h"

namespace penumbra::stimuli {

ImageDifference compare(const io::Image8& a, const io::Image8& b) {
  if (a.width != b.width || a.height != b.height || a.channels != b.channels)
    throw std::invalid_argument("compare: images of different sizes");
  const cv::Mat ma(a.height, a.width, CV_8UC(a.channels), const_cast<std::uint8_t*>(a.pixels.data()));
  const cv::Mat mb(b.height, b.width, CV_8UC(b.channels), const_cast<std::uint8_t*>(b.pixels.data()));
  cv::Mat diff;
  cv::absdiff(ma, mb, diff);
  diff = diff.reshape(1);
  double max_value = 0;
  cv::minMaxLoc(diff, nullptr, &max_value);
  return {cv::countNonZero(diff), static_cast<int>(max_value)};
}

Partner parse_partner(const std::string& name) {
  if (name == "original") return Partner::original;
  if (name == "mean-line" || name == "mean_line") return Partner::mean_line;
  if (name == "bresenham") return Partner::bresenham;
  throw std::invalid_argument("partner '" + json_input::printable(name) + "': expected original, mean-line or bresenham");
}

std::string to_string(Partner partner) {
  return partner == Partner::original ? "original" : partner == Partner::mean_line ? "mean-line" : "bresenham";
}

double stair_mean_line_b(const Geometry& g, double a) {
  // Texel (i, j) is occluded when its centre is below y = x + b, i.e. j - i < t with
  // t = (o_x - o_y + b) / a; column i's staircase top is then at y = o_y + (i + ceil(t)) a, whose
  // mean over the column is the line y = x + o_y - o_x + (ceil(t) - 1/2) a.
  const double t = (g.map_origin_px.x - g.map_origin_px.y + g.line_b) / a;
  return g.map_origin_px.y - g.map_origin_px.x + (std::ceil(t) - 0.5) * a;
}

namespace {

SeedReference search_seed(StimulusRenderer& renderer, StimulusSpec spec, const ReferenceSearch& search,
                          double r_max) {
  SeedReference out;
  out.seed = spec.seed;
  auto difference_at = [&](double r) {
    spec.filter_radius_px = r;
    Geometry g = make_geometry(spec);
    if (search.partner == Partner::mean_line) g.line_b = stair_mean_line_b(g, spec.artifact_px);
    const StimulusPair pair = renderer.render(spec, g);
    ++out.renders;
    if (search.partner == Partner::bresenham) {
      // The same edge rasterized at the display's resolution (texel centres on pixel centres: the
      // midpoint rule Bresenham's algorithm implements) and filtered the same way.
      StimulusSpec fine = spec;
      fine.artifact_px = 1;
      Geometry line = make_geometry(fine);
      line.map_origin_px = glm::floor(line.map_origin_px);
      line.orientation = g.orientation;
      line.to_canonical = g.to_canonical;
      line.line_m = g.line_m;
      // Through the staircase's mean for the stair (texel-centre rasterization displaces a 45-degree
      // edge by up to half a texel, which no blur hides), the original edge for the step.
      line.line_b = spec.pattern == Pattern::stair ? stair_mean_line_b(g, spec.artifact_px) : g.line_b;
      const StimulusPair straight = renderer.render(fine, line);
      ++out.renders;
      return compare(pair.artifact, straight.artifact);
    }
    return compare(pair.artifact, pair.line);
  };
  std::vector<double> scan;
  for (double r = search.r_min_px; r < r_max; r *= search.growth) scan.push_back(r);
  scan.push_back(r_max);
  std::vector<bool> identical(scan.size());
  out.at_r_max = difference_at(r_max);
  const auto same = [&](const ImageDifference& d) { return d.max_abs_levels <= search.tolerance_levels; };
  if (!same(out.at_r_max)) return out;
  identical.back() = true;
  for (std::size_t i = 0; i + 1 < scan.size(); ++i) identical[i] = same(difference_at(scan[i]));
  // The smallest scan index from which every larger scan point is identical.
  std::size_t first = scan.size();
  while (first > 0 && identical[first - 1]) --first;
  if (first == scan.size()) return out;  // still different at r_max
  if (first == 0) {
    out.reference_px = scan[0];
    return out;
  }
  double lo = scan[first - 1], hi = scan[first];
  while (hi - lo > search.resolution_px) {
    const double mid = 0.5 * (lo + hi);
    (same(difference_at(mid)) ? hi : lo) = mid;
  }
  out.reference_px = hi;
  out.bracket_below_px = lo;
  for (std::size_t i = 0; i + 1 < first; ++i)
    if (identical[i]) out.identical_below_px.push_back(scan[i]);
  return out;
}

}  // namespace

Reference find_reference(StimulusRenderer& renderer, const StimulusSpec& spec_in, const ReferenceSearch& search,
                         const std::function<void(int, int)>& progress) {
  StimulusSpec spec = spec_in;
  spec.filter_radius_px = 1.0;
  validate(spec);
  const double showable = 0.5 * spec.size_px;
  const double r_max = search.r_max_px > 0 ? search.r_max_px : showable;
  if (!(search.r_min_px >= 1.0 && search.r_min_px < r_max && r_max <= showable))
    throw std::invalid_argument("reference: expected 1 <= r_min < r_max <= size_px / 2 = " + std::to_string(showable));
  if (!(search.growth > 1.0)) throw std::invalid_argument("reference: scan growth must be > 1");
  if (!(search.resolution_px > 0.0)) throw std::invalid_argument("reference: resolution must be > 0");
  if (search.tolerance_levels < 0) throw std::invalid_argument("reference: tolerance must be >= 0 levels");
  if (search.seeds.empty()) throw std::invalid_argument("reference: at least one seed");
  if (search.partner == Partner::mean_line && spec.pattern != Pattern::stair)
    throw std::invalid_argument("reference: the mean-line partner is defined for the stair pattern only");
  Reference ref;
  ref.spec = spec;
  ref.search = search;
  ref.search.r_max_px = r_max;
  bool all_found = true;
  double worst = 0;
  for (std::size_t i = 0; i < search.seeds.size(); ++i) {
    spec.seed = search.seeds[i];
    SeedReference s = search_seed(renderer, spec, search, r_max);
    if (s.reference_px) worst = std::max(worst, *s.reference_px);
    else all_found = false;
    if (!s.identical_below_px.empty()) ref.monotone = false;
    ref.seeds.push_back(std::move(s));
    if (progress) progress(static_cast<int>(i + 1), static_cast<int>(search.seeds.size()));
  }
  if (all_found) ref.reference_px = worst;
  return ref;
}

// Hand-written: optionals as null, enums as names, part of the spec and renamed keys (differs_at_px).
nlohmann::json to_json(const Reference& r) {
  auto optional = [](const std::optional<double>& v) { return v ? nlohmann::json(*v) : nlohmann::json(nullptr); };
  nlohmann::json seeds = nlohmann::json::array();
  for (const SeedReference& s : r.seeds) {
    seeds.push_back({{"seed", s.seed},
                     {"reference_filter_radius_px", optional(s.reference_px)},
                     {"differs_at_px", s.bracket_below_px},
                     {"identical_below_px", s.identical_below_px},
                     {"at_r_max", {{"differing_pixels", s.at_r_max.differing_pixels},
                                   {"max_abs_levels", s.at_r_max.max_abs_levels}}},
                     {"renders", s.renders}});
  }
  return {{"pattern", to_string(r.spec.pattern)},
          {"contrast", r.spec.lit_linear},
          {"artifact_px", r.spec.artifact_px},
          {"kernel", to_string(r.spec.kernel)},
          {"size_px", r.spec.size_px},
          {"transfer_function", to_string(r.spec.transfer)},
          {"partner", to_string(r.search.partner)},
          {"reference_filter_radius_px", optional(r.reference_px)},
          {"monotone", r.monotone},
          {"search", {{"r_min_px", r.search.r_min_px}, {"r_max_px", r.search.r_max_px},
                      {"tolerance_levels", r.search.tolerance_levels},
                      {"growth", r.search.growth}, {"resolution_px", r.search.resolution_px}}},
          {"seeds", seeds}};
}

}  // namespace penumbra::stimuli
