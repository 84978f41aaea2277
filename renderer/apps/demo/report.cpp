#include "apps/demo/report.h"

#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <map>

#include "io/report.h"
#include "shadows/frame_report.h"
#include "shadows/settings.h"
#include "stats/summary.h"

namespace penumbra::stats {
// {"median", "p10", "p90", "min", "max"}; here beside its one user, so that stats/summary.h stays free of JSON.
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(Spread, median, p10, p90, min, max)
}  // namespace penumbra::stats

namespace penumbra::demo {

namespace {

using stats::Spread;
using stats::spread;

// printf onto the end of `out` (the tables are text that a shard's part carries to the merge).
__attribute__((format(printf, 2, 3))) void appendf(std::string& out, const char* format, ...) {
  std::va_list args, copy;
  va_start(args, format);
  va_copy(copy, args);
  const int n = std::vsnprintf(nullptr, 0, format, copy);
  va_end(copy);
  if (n > 0) {
    const std::size_t at = out.size();
    out.resize(at + static_cast<std::size_t>(n) + 1);
    std::vsnprintf(out.data() + at, static_cast<std::size_t>(n) + 1, format, args);
    out.resize(at + static_cast<std::size_t>(n));
  }
  va_end(args);
}

double mean_of(const std::vector<double>& v) {
  double sum = 0;
  for (double x : v) sum += x;
  return v.empty() ? 0.0 : sum / static_cast<double>(v.size());
}

double min_of(const std::vector<double>& v) { return v.empty() ? NAN : *std::min_element(v.begin(), v.end()); }
double max_of(const std::vector<double>& v) { return v.empty() ? NAN : *std::max_element(v.begin(), v.end()); }

nlohmann::json reference_error_json(const std::vector<metrics::ImageError>& errors) {
  if (errors.empty()) return nullptr;
  std::vector<double> rmse, mean_abs, ssim;
  for (const auto& e : errors) rmse.push_back(e.rmse), mean_abs.push_back(e.mean_abs), ssim.push_back(e.ssim);
  // rmse_mean is reference_rmse(), the error the front is read at.
  return {{"frames", errors.size()}, {"rmse_mean", mean_of(rmse)}, {"rmse_per_frame", rmse}, {"mean_abs_mean", mean_of(mean_abs)},
          {"ssim_mean", mean_of(ssim)}, {"ssim_min", min_of(ssim)}};
}

// What a configuration's shadow gave the GPU to do (ShadowWork per frame, spread over the path's
// frames) and what its shading's lookups read per pixel shown (over the reference frames): the
// counts a cost model turns into a GPU's time (scripts/gpu_cost_model.py).
nlohmann::json work_json(const Series& s) {
  std::vector<double> primitives, fragments, compute, depth;
  for (const ShadowWork& w : s.work)
    primitives.push_back(w.primitives), fragments.push_back(w.fragments), compute.push_back(w.compute_invocations),
        depth.push_back(w.depth_texels);
  nlohmann::json j = {{"frames", s.work.size()},
                      {"primitives", spread(primitives)},
                      {"fragments", spread(fragments)},
                      {"depth_texels", spread(depth)},
                      {"compute_invocations", spread(compute)}};
  if (s.read_frames > 0) {
    const shadows::ShadowReads& r = s.reads;
    j["reads"] = {{"frames", s.read_frames},
                  {"pixels_per_frame", static_cast<double>(r.pixels) / s.read_frames},
                  {"instructions_per_pixel", r.per_pixel(r.instructions)},
                  {"texels_per_pixel", r.per_pixel(r.texels)},
                  {"bytes_per_pixel", r.per_pixel(r.bytes)}};
  }
  return j;
}

// Every cascade of the adaptive maps, as most frames along the path had them ("2624+3904").
std::string usual_resolution(const Series& s) {
  std::map<std::string, int> seen;
  for (const auto& r : s.resolution) ++seen[r];
  if (seen.empty()) return "";
  return std::max_element(seen.begin(), seen.end(), [](const auto& a, const auto& b) { return a.second < b.second; })->first;
}


// The thin casters' shadow and gaps a configuration keeps, relative to the reference's.
double shadow_kept(const TechniqueRun& run, const Series& s) { return s.thin_shadow / std::max(run.reference_thin_shadow, 1e-9); }
double gaps_kept(const TechniqueRun& run, const Series& s) { return run.gap_pixels > 0 ? s.gaps / std::max(run.reference_gaps, 1e-9) : 1.0; }

// FLIP's pooled values over the reference frames: the means of each value, the largest max, and
// each frame's.
nlohmann::json flip_json(const FlipSeries& f) {
  if (f.frames.empty()) return nullptr;
  std::vector<double> mean, median, share, q1, q3, max;
  nlohmann::json per_frame = nlohmann::json::array();
  for (const auto& p : f.frames) {
    mean.push_back(p.mean), median.push_back(p.weighted_median), share.push_back(p.share_above), max.push_back(p.max);
    q1.push_back(p.weighted_q1), q3.push_back(p.weighted_q3);
    per_frame.push_back({{"mean", p.mean}, {"weighted_median", p.weighted_median}, {"weighted_q1", p.weighted_q1},
                         {"weighted_q3", p.weighted_q3}, {"share_above", p.share_above}, {"max", p.max}});
  }
  // mean is f.mean(), the error the front is read at.
  return {{"frames", f.frames.size()},        {"mean", f.mean()},       {"weighted_median_mean", mean_of(median)},
          {"weighted_q1_mean", mean_of(q1)},  {"weighted_q3_mean", mean_of(q3)},
          {"threshold", f.frames.front().threshold}, {"share_above_mean", mean_of(share)}, {"max_max", max_of(max)},
          {"per_frame", per_frame}};
}

// The frame observer's verdict over the reference frames.
nlohmann::json observer_json(const ObserverSeries& o) {
  if (o.frames.empty()) return nullptr;
  std::vector<double> p;
  std::vector<int> visible_patches, patches;
  for (const auto& f : o.frames) p.push_back(f.p_detect_max), visible_patches.push_back(f.patches_visible), patches.push_back(f.patches);
  return {{"frames", o.frames.size()},  {"criterion_f", o.criterion_f},       {"visible", o.visible()},
          {"p_detect_max", o.p_detect_max()}, {"p_detect_max_per_frame", p}, {"patches_visible_per_frame", visible_patches},
          {"patches_per_frame", patches}};
}

// `subject` (a series index) read against the family's front at its error `subject_error` by `measure`.
FrontComparison compare_on(const TechniqueRun& run, ErrorMeasure measure, const std::vector<std::size_t>& family, std::size_t subject,
                           double subject_error, const std::vector<double> Series::*per_frame, bool median_cost) {
  std::vector<stats::Candidate> candidates;
  for (const std::size_t k : family) {
    const auto& v = run.series[k].*per_frame;
    candidates.push_back({error_of(run.series[k], measure), median_cost ? stats::median(v) : mean_of(v)});
  }
  FrontComparison out;
  const std::vector<std::size_t> front = stats::pareto_front(candidates);
  for (const std::size_t f : front) out.front.push_back(family[f]);
  if (front.empty()) return out;
  out.reading = stats::read_front(candidates, front, subject_error);
  out.reading.lo = family[out.reading.lo], out.reading.hi = family[out.reading.hi];
  out.ratio = stats::paired_ratio(run.series[out.reading.lo].*per_frame, run.series[out.reading.hi].*per_frame, out.reading.weight,
                                  run.series[subject].*per_frame);
  return out;
}

nlohmann::json comparison_json(const TechniqueRun& run, const FrontComparison& c, const std::string& unit) {
  nlohmann::json front = nlohmann::json::array();
  for (const std::size_t k : c.front) front.push_back(run.series[k].config.name);
  return {{"front", front},
          {"position", std::string(stats::to_string(c.reading.position))},
          {"between", {run.series[c.reading.lo].config.name, run.series[c.reading.hi].config.name}},
          {"weight", c.reading.weight},
          {"front_" + unit, c.reading.cost},
          {"ratio", {{"median", c.ratio.median}, {"ci95", {c.ratio.lo, c.ratio.hi}}, {"frames", c.ratio.n}}}};
}

// "1.19x [1.10, 1.25]", with "≥" / "≤" where the adaptive error lies beyond the front's ends.
std::string ratio_text(const FrontComparison& c) {
  const char* bound = c.reading.position == stats::FrontReading::Position::more_accurate   ? ">= "
                      : c.reading.position == stats::FrontReading::Position::less_accurate ? "<= "
                                                                                          : "";
  char text[96];
  std::snprintf(text, sizeof text, "%s%.2fx [%.2f, %.2f]", bound, c.ratio.median, c.ratio.lo, c.ratio.hi);
  return text;
}

std::string where_text(const TechniqueRun& run, const FrontComparison& c) {
  const std::string& lo = run.series[c.reading.lo].config.name;
  const std::string& hi = run.series[c.reading.hi].config.name;
  switch (c.reading.position) {
    case stats::FrontReading::Position::more_accurate: return "more accurate than the front's best, " + lo;
    case stats::FrontReading::Position::less_accurate: return "less accurate than the front's cheapest, " + lo;
    case stats::FrontReading::Position::on_front: return lo == hi ? "on " + lo : "between " + lo + " and " + hi;
  }
  return "";
}

}  // namespace

double reference_rmse(const Series& s) {
  if (s.vs_reference.empty()) return NAN;
  std::vector<double> rmse;
  for (const auto& e : s.vs_reference) rmse.push_back(e.rmse);
  return mean_of(rmse);
}

Unseen cheapest_unseen(const TechniqueRun& run) {
  Unseen u;
  for (std::size_t k = 0; k < run.series.size(); ++k) {
    const Series& s = run.series[k];
    if (!s.config.timed() || s.seen.frames.empty()) continue;
    u.measured = true;
    u.criterion_f = s.seen.criterion_f;
    if (s.seen.visible()) continue;
    u.unseen.push_back(k);
    const auto cheaper = [&](const std::optional<std::size_t>& best, const std::vector<double> Series::*cost, bool median) {
      if (!best) return true;
      const auto& a = s.*cost;
      const auto& b = run.series[*best].*cost;
      return median ? stats::median(a) < stats::median(b) : mean_of(a) < mean_of(b);
    };
    if (cheaper(u.by_time, &Series::ms, true)) u.by_time = k;
    if (cheaper(u.by_memory, &Series::allocated, false)) u.by_memory = k;
  }
  return u;
}

std::string unseen_line(const TechniqueRun& run, const Unseen& u) {
  std::size_t timed = 0;
  for (const Series& s : run.series) timed += s.config.timed() ? 1 : 0;
  char line[512];
  if (!u.measured) {
    std::snprintf(line, sizeof line, "%-6s the frame observer: not run (--no-reference or --no-flip)", run.technique.c_str());
  } else if (!u.by_time) {
    std::snprintf(line, sizeof line, "%-6s the frame observer (F = %.3f) tells every configuration (%zu) from the reference: none it cannot",
                  run.technique.c_str(), u.criterion_f, timed);
  } else {
    const Series& t = run.series[*u.by_time];
    const Series& m = run.series[*u.by_memory];
    std::snprintf(line, sizeof line,
                  "%-6s the frame observer (F = %.3f) cannot tell %zu of %zu configurations from the reference; the cheapest: %s "
                  "(%.1f ms), by memory %s (%.2f Mtexels)",
                  run.technique.c_str(), u.criterion_f, u.unseen.size(), timed, t.config.name.c_str(), stats::median(t.ms),
                  m.config.name.c_str(), mean_of(m.allocated) / 1e6);
  }
  return line;
}

const char* measure_label(ErrorMeasure m) { return m == ErrorMeasure::rmse ? "RMSE" : "FLIP"; }

double error_of(const Series& s, ErrorMeasure m) {
  switch (m) {
    case ErrorMeasure::flip: return s.flip.mean();
    case ErrorMeasure::flip_ray_traced: return s.flip_ray_traced.mean();
    case ErrorMeasure::rmse: return reference_rmse(s);
  }
  return NAN;
}

std::vector<const EqualError*> EqualErrors::shown() const {
  std::vector<const EqualError*> out;
  if (flip.available) out.push_back(&flip);
  if (flip_ray_traced.available) out.push_back(&flip_ray_traced);
  out.push_back(&rmse);
  return out;
}

EqualErrors equal_errors(const TechniqueRun& run) {
  return {equal_error(run, ErrorMeasure::flip), equal_error(run, ErrorMeasure::flip_ray_traced), equal_error(run, ErrorMeasure::rmse)};
}

EqualError equal_error(const TechniqueRun& run, ErrorMeasure measure) {
  EqualError eq;
  eq.measure = measure;
  for (std::size_t k = 0; k < run.series.size(); ++k)
    if (run.series[k].config.engine_family()) eq.family.push_back(k);
  eq.adaptive_error = error_of(run.series[run.adaptive], measure);
  if (std::isnan(eq.adaptive_error)) {
    eq.why_not = measure == ErrorMeasure::rmse              ? "no reference (--no-reference): no error to compare at"
                 : measure == ErrorMeasure::flip_ray_traced ? "no second reference (PCSS only): no error to compare at"
                                                            : "no perceptual difference (--no-reference or --no-flip): no error to compare at";
    return eq;
  }
  if (eq.family.size() < 2) {
    eq.why_not = "no engine family (--no-baselines): no front";
    return eq;
  }
  eq.time = compare_on(run, measure, eq.family, run.adaptive, eq.adaptive_error, &Series::ms, true);
  eq.memory = compare_on(run, measure, eq.family, run.adaptive, eq.adaptive_error, &Series::allocated, false);
  const bool floor = !run.floor_ms.empty();
  if (floor) eq.shadow = compare_on(run, measure, eq.family, run.adaptive, eq.adaptive_error, &Series::shadow_ms, true);
  eq.available = !eq.time.front.empty() && !eq.memory.front.empty();
  if (!eq.available) eq.why_not = "no engine configuration was measured against the reference";
  for (std::size_t k = 0; k < run.series.size() && eq.available; ++k) {
    if (run.series[k].config.role != Role::virtual_pages) continue;
    VirtualReading v;
    v.measure = measure;
    v.series = k;
    v.error = error_of(run.series[k], measure);
    v.time = compare_on(run, measure, eq.family, k, v.error, &Series::ms, true);
    v.memory = compare_on(run, measure, eq.family, k, v.error, &Series::allocated, false);
    if (floor) v.shadow = compare_on(run, measure, eq.family, k, v.error, &Series::shadow_ms, true);
    eq.virtual_maps.push_back(v);
  }
  return eq;
}

namespace {
// One configuration read against the front: "pcf    [LABEL ]at RMSE ...: speedup ..., memory ratio ...";
// PCSS's FLIP against the ray-traced sun says so.
std::string reading_line(const TechniqueRun& run, ErrorMeasure measure, const std::string& label, double error,
                         const FrontComparison& time, const FrontComparison& memory, const FrontComparison& shadow) {
  char line[768];
  const std::string shadow_text = shadow.front.empty() ? "" : ", shadow cost " + ratio_text(shadow);
  std::snprintf(line, sizeof line, "%-6s %sat %s %.4f%s: speedup %s, memory ratio %s%s (time: %s; memory: %s)", run.technique.c_str(),
                label.empty() ? "" : (label + " ").c_str(), measure_label(measure), error,
                measure == ErrorMeasure::flip_ray_traced ? " against the ray-traced sun" : "", ratio_text(time).c_str(),
                ratio_text(memory).c_str(), shadow_text.c_str(), where_text(run, time).c_str(), where_text(run, memory).c_str());
  return line;
}
}  // namespace

std::string virtual_headline(const TechniqueRun& run, const VirtualReading& v) {
  return reading_line(run, v.measure, run.series[v.series].config.name, v.error, v.time, v.memory, v.shadow);
}

std::string headline(const TechniqueRun& run, const EqualError& eq) {
  char line[512];
  if (!eq.available) {
    std::snprintf(line, sizeof line, "%-6s %s", run.technique.c_str(), eq.why_not.c_str());
    return line;
  }
  return reading_line(run, eq.measure, "", eq.adaptive_error, eq.time, eq.memory, eq.shadow);
}

namespace {
// A reading's entry in report.json: the error it is read at, the two comparisons, the headline.
nlohmann::json equal_json(const TechniqueRun& run, const EqualError& eq, const std::string& error) {
  if (!eq.available) return {{"unavailable", eq.why_not}};
  return {{"error", error},
          {"adaptive_error", eq.adaptive_error},
          {"time", comparison_json(run, eq.time, "ms")},
          {"memory", comparison_json(run, eq.memory, "texels")},
          {"shadow_cost", eq.shadow.front.empty() ? nlohmann::json(nullptr) : comparison_json(run, eq.shadow, "ms")},
          {"headline", headline(run, eq)}};
}
nlohmann::json virtual_json(const TechniqueRun& run, const EqualError& eq, std::size_t k) {
  const auto reading = std::find_if(eq.virtual_maps.begin(), eq.virtual_maps.end(), [&](const VirtualReading& v) { return v.series == k; });
  if (reading == eq.virtual_maps.end()) return {{"why_not", eq.why_not}};
  const VirtualReading& v = *reading;
  return {{"error", v.error},
          {"time", comparison_json(run, v.time, "ms")},
          {"memory", comparison_json(run, v.memory, "texels")},
          {"shadow_cost", v.shadow.front.empty() ? nlohmann::json(nullptr) : comparison_json(run, v.shadow, "ms")},
          {"headline", virtual_headline(run, v)}};
}
}  // namespace

nlohmann::json technique_json(const TechniqueRun& run, const EqualErrors& eqs) {
  const EqualError& eq = eqs.rmse;
  const Series& ca = run.series[run.adaptive];
  const Series& cf = run.series[run.fixed];
  std::vector<double> res_a;
  for (const auto& r : ca.resolution) res_a.push_back(std::stod(r.substr(0, r.find('+'))));
  const Spread sf = spread(cf.ms), sa = spread(ca.ms), sr = spread(res_a);
  nlohmann::json t;
  t["technique"] = run.technique;
  t["fixed"] = {{"resolution_texels", cf.config.settings.map.resolution_texels}, {"frame_ms", sf}, {"passes", io::to_json(cf.timer->stats())}};
  if (!run.floor_ms.empty())
    t["floor"] = {{"frame_ms", spread(run.floor_ms)},
                  {"what", "the frame without a meaningful shadow (shadows::unshadowed_floor: hard shadows from one 1x1 unfitted map), "
                           "same camera and shading, timed as the configurations; shadow cost = frame ms - floor ms, per frame"}};
  t["adaptive"] = {{"resolution_texels", sr},
                   {"cascades_most_frames", usual_resolution(ca)},
                   {"storage", ca.info.storage},
                   {"resolution_source", ca.info.resolution_source},
                   {"frame_ms", sa},
                   {"passes", io::to_json(ca.timer->stats())}};
  if (ca.info.pcss_requirement.valid)
    t["adaptive"]["pcss_requirement"] = {{"clamped_fraction", ca.info.pcss_requirement.clamped_fraction},
                                         {"clamped_fraction_mean", mean_of(ca.pcss_clamped)},
                                         {"above_max_fraction", ca.info.pcss_requirement.above_max_fraction}};
  t["speedup_median"] = sf.median / std::max(sa.median, 1e-9);
  t["image"] = {{"ssim_min", min_of(run.ssim_fixed_adaptive)},
                {"ssim_mean", mean_of(run.ssim_fixed_adaptive)},
                {"max_abs_max", max_of(run.max_abs_fixed_adaptive)},
                {"share_above_1_255_max", max_of(run.share_fixed_adaptive)}};
  if (run.reference_frames > 0)
    t["reference"] = {{"description", run.reference_description},
                      {"frames", run.reference_frames},
                      {"render_ms_mean", run.reference_ms / run.reference_frames},
                      {"compared_at", run.mask_description},
                      {"compared_pixels", run.mask_pixels}};
  if (run.thin && run.reference_frames > 0)
    t["thin_casters"] = {{"objects", thin_casters()},
                         {"shadow_pixels", run.thin_pixels},
                         {"gap_pixels", run.gap_pixels},
                         {"reference_shadow_darkness_mean", run.thin_pixels > 0 ? run.reference_thin_shadow / static_cast<double>(run.thin_pixels) : 0.0},
                         {"reference_gap_visibility_mean", run.gap_pixels > 0 ? run.reference_gaps / static_cast<double>(run.gap_pixels) : 0.0},
                         {"crop_frame", run.thin_crops.frame}};
  if (!run.gain_crops.tiles.empty()) t["gain_crop"] = {{"frame", run.gain_crops.frame}, {"error_removed_sum", run.gain_crops.score}};
  for (const Series& s : run.series) {
    t["flicker"].push_back({{"configuration", s.config.name},
                            {"mean_abs_mean", mean_of(s.flicker_mean_abs)},
                            {"share_changed_mean", mean_of(s.flicker_share)},
                            {"mean_abs_per_frame", s.flicker_mean_abs},
                            {"resolution_changes", s.resolution_changes}});
    nlohmann::json row = {{"configuration", s.config.name},
                          {"frame_ms", s.ms},
                          {"texels", s.texels},
                          {"allocated", s.allocated},
                          {"resolution", s.resolution}};
    if (!s.pages_drawn.empty()) row["pages_drawn"] = s.pages_drawn;  // a virtual map's
    if (!s.pages_drawn.empty() && s.config.settings.map.virtual_cache)
      row["pages_invalidated"] = s.pages_invalidated;  // cached: the pages a moved caster (the van) dropped
    t["along_path"].push_back(row);
  }
  auto on = [](const FrontComparison& c, std::size_t k) { return std::find(c.front.begin(), c.front.end(), k) != c.front.end(); };
  auto measured = [&](std::size_t k, nlohmann::json& j) {
    const Series& s = run.series[k];
    j["name"] = s.config.name;  // as the front readings' "between" name it
    j["texels_rendered"] = spread(s.texels);
    j["texels_allocated"] = mean_of(s.allocated);
    j["map_triangles"] = spread(s.map_triangles);
    if (!s.shadow_ms.empty()) j["shadow_ms"] = spread(s.shadow_ms);  // frame ms minus the floor, per frame
    j["work"] = work_json(s);
    j["ssim_vs_engine_min"] = min_of(s.ssim_vs_engine);
    j["reference_error"] = reference_error_json(s.vs_reference);
    if (run.perceptual) j["flip"] = flip_json(s.flip), j["observer"] = observer_json(s.seen);
    if (run.converged) {
      j["flip_ray_traced"] = flip_json(s.flip_ray_traced);
      j["observer_ray_traced"] = observer_json(s.seen_ray_traced);
      j["reference_error_converged"] = reference_error_json(s.vs_converged);
    }
    if (run.thin_pixels > 0) j["thin_casters"] = {{"shadow_kept", shadow_kept(run, s)}, {"gaps_kept", gaps_kept(run, s)}};
    if (eq.available && s.config.engine_family()) j["on_front"] = {{"time", on(eq.time, k)}, {"memory", on(eq.memory, k)}};
    if (eqs.flip.available && s.config.engine_family())
      j["on_front_flip"] = {{"time", on(eqs.flip.time, k)}, {"memory", on(eqs.flip.memory, k)}};
  };
  measured(run.fixed, t["fixed"]);
  measured(run.adaptive, t["adaptive"]);
  for (std::size_t k = 0; k < run.series.size(); ++k) {
    const Series& s = run.series[k];
    if (s.config.role == Role::no_hysteresis)
      t["adaptive"]["without_hysteresis"] = {{"resolution_changes", s.resolution_changes},
                                             {"texels_rendered", spread(s.texels)},
                                             {"reference_error", reference_error_json(s.vs_reference)}};
    if (s.config.role != Role::engine) continue;
    nlohmann::json b = {{"name", s.config.name},
                        {"settings", shadows::to_json(s.config.settings)},
                        {"frame_ms", spread(s.ms)},
                        {"passes", io::to_json(s.timer->stats())}};
    measured(k, b);
    t["baselines"].push_back(b);
  }
  // Every virtual configuration, read against the front where there is one (its equal_error),
  // else with the reason there is none.
  for (std::size_t k = 0; k < run.series.size(); ++k) {
    const Series& s = run.series[k];
    if (s.config.role != Role::virtual_pages) continue;
    nlohmann::json j = {{"name", s.config.name},
                        {"settings", shadows::to_json(s.config.settings)},
                        {"frame_ms", spread(s.ms)},
                        {"passes", io::to_json(s.timer->stats())},
                        {"pages_marked", s.resolution}};
    j["equal_error"] = virtual_json(run, eq, k);
    if (run.perceptual) j["equal_flip"] = virtual_json(run, eqs.flip, k);
    if (run.converged) j["equal_flip_ray_traced"] = virtual_json(run, eqs.flip_ray_traced, k);
    if (s.info.virtual_map) {
      j["last_frame"] = shadows::virtual_map_json(*s.info.virtual_map);  // as penumbra-render's report.json
    }
    measured(k, j);
    t["virtual"].push_back(j);
  }
  t["engine_baseline"] = run.series[run.engine].config.name;
  t["speedup_vs_engine_median"] = spread(run.series[run.engine].ms).median / std::max(sa.median, 1e-9);
  t["equal_error"] = equal_json(run, eq, "rmse_mean against the reference");
  if (run.perceptual) {
    t["perceptual"] = {{"target", run.target_description},
                       {"pixels_per_degree", run.pixels_per_degree},
                       {"lit_frames", {{"composed", "per pixel base + V direct in linear RGB from the frame's shading (apps/demo/perceptual.h)"},
                                       {"max_code_difference", run.lit_code_difference.max},
                                       {"share_above_2_codes", static_cast<double>(run.lit_code_difference.above_2) /
                                                                   static_cast<double>(std::max<std::int64_t>(run.lit_code_difference.pixels, 1))}}},
                       {"flip_evaluations", run.flip_frames_evaluated},
                       {"flip_ms", run.flip_ms},
                       {"montage_frame", run.flip_montage_frame}};
    if (run.converged) t["perceptual"]["converged_render_ms_mean"] = run.converged_ms / std::max(run.reference_frames, 1);
    t["equal_flip"] = equal_json(run, eqs.flip, "flip mean against " + run.target_description);
    const Unseen u = cheapest_unseen(run);
    nlohmann::json unseen = nlohmann::json::array();
    for (const std::size_t k : u.unseen) unseen.push_back(run.series[k].config.name);
    t["observer"] = {{"criterion_f", u.criterion_f},
                     {"against", run.target_description},
                     {"not_told_apart", unseen},
                     {"cheapest_by_time", u.by_time ? nlohmann::json(run.series[*u.by_time].config.name) : nlohmann::json("none")},
                     {"cheapest_by_memory", u.by_memory ? nlohmann::json(run.series[*u.by_memory].config.name) : nlohmann::json("none")},
                     {"line", unseen_line(run, u)}};
  }
  if (run.converged) t["equal_flip_ray_traced"] = equal_json(run, eqs.flip_ray_traced, "flip mean against " + run.reference_description);
  return t;
}

std::string single_map_row(const TechniqueRun& run) {
  std::string out;
  const Series& ca = run.series[run.adaptive];
  const Series& cf = run.series[run.fixed];
  const Spread sf = spread(cf.ms), sa = spread(ca.ms);
  const double speedup = sf.median / std::max(sa.median, 1e-9);
  appendf(out, "%-6s %10.4f %8.1f [%6.1f, %6.1f] %10.4f %8.1f [%6.1f, %6.1f] %7.2fx %20s %8.4f %9.4f %9.4f\n", run.technique.c_str(),
              reference_rmse(cf), sf.median, sf.p10, sf.p90, reference_rmse(ca), sa.median, sa.p10, sa.p90, speedup,
              (usual_resolution(ca) + "²").c_str(), min_of(run.ssim_fixed_adaptive), max_of(run.max_abs_fixed_adaptive),
              max_of(run.share_fixed_adaptive));
  return out;
}

std::string tables(const TechniqueRun& run, const EqualErrors& eqs) {
  std::string out;
  const EqualError& eq = *eqs.shown().front();  // the headline's reading marks its fronts
  const auto& series = run.series;
  const double engine_median = spread(series[run.engine].ms).median;
  appendf(out, "%s: every configuration against %s (the engine baseline) and the reference; * on the time front, + on the memory front "
              "(at equal %s)\n",
              run.technique.c_str(), series[run.engine].config.name.c_str(), measure_label(eq.measure));
  appendf(out, "  %-26s %24s %7s %10s %9s %9s %8s %9s %8s %7s %7s", "configuration", "frame ms", "vs eng.", "Mtex drawn", "allocated",
              "Mtri maps", "SSIM eng", "RMSE ref", "SSIM ref", "thin", "gaps");
  if (run.perceptual) appendf(out, " %8s %8s %7s %6s", "FLIP", "FLIP>.05", "max", "p_det");
  if (run.converged) appendf(out, " %9s %9s %6s", "RMSE conv", "FLIP sun", "p_sun");
  appendf(out, "\n");
  for (std::size_t k = 0; k < series.size(); ++k) {
    const Series& s = series[k];
    if (!s.config.timed()) continue;
    const Spread ms = spread(s.ms);
    std::string name = s.config.name;
    if (eq.available && std::find(eq.time.front.begin(), eq.time.front.end(), k) != eq.time.front.end()) name += " *";
    if (eq.available && std::find(eq.memory.front.begin(), eq.memory.front.end(), k) != eq.memory.front.end()) name += " +";
    appendf(out, "  %-26s %8.1f [%6.1f, %6.1f] %6.2fx %10.2f %9.2f %9.3f %8.4f", name.c_str(), ms.median, ms.p10, ms.p90,
                engine_median / std::max(ms.median, 1e-9), spread(s.texels).median / 1e6, mean_of(s.allocated) / 1e6,
                spread(s.map_triangles).median / 1e6, min_of(s.ssim_vs_engine));
    if (const nlohmann::json err = reference_error_json(s.vs_reference); !err.is_null())
      appendf(out, " %9.5f %8.4f", err["rmse_mean"].get<double>(), err["ssim_mean"].get<double>());
    if (run.thin_pixels > 0) appendf(out, " %7.3f %7.3f", shadow_kept(run, s), gaps_kept(run, s));
    if (const nlohmann::json f = flip_json(s.flip); run.perceptual && !f.is_null())
      appendf(out, " %8.5f %7.2f%% %7.3f %5.2f%s", f["mean"].get<double>(), 100 * f["share_above_mean"].get<double>(),
                  f["max_max"].get<double>(), s.seen.p_detect_max(), s.seen.visible() ? "!" : " ");
    if (run.converged && !s.vs_converged.empty())
      appendf(out, " %9.5f %9.5f %5.2f%s", reference_error_json(s.vs_converged)["rmse_mean"].get<double>(), s.flip_ray_traced.mean(),
                  s.seen_ray_traced.p_detect_max(), s.seen_ray_traced.visible() ? "!" : " ");
    appendf(out, "\n");
  }
  if (run.perceptual)
    appendf(out, "  FLIP: LDR-FLIP of the lit frame against %s at %.2f pixels per degree, mean over the reference frames (FLIP>.05: share "
                "of pixels above 0.05; max: the largest pixel); p_det: the frame observer's detection probability, the largest patch's over the reference frames, "
                "! where above F = %.3f%s\n",
                run.target_description.c_str(), run.pixels_per_degree, cheapest_unseen(run).criterion_f,
                run.converged ? "; RMSE conv: visibility against it; FLIP sun, p_sun: against the ray-traced sun" : "");
  if (run.reference_frames > 0)
    appendf(out, "  reference: %s; compared at %s (%lld pixels over %d frames)\n", run.reference_description.c_str(),
                run.mask_description.c_str(), static_cast<long long>(run.mask_pixels), run.reference_frames);
  if (run.thin && run.reference_frames > 0)
    appendf(out, "  thin casters (crane, wires): %lld shadow and %lld gap pixels over %d frames; thin = their shadow kept, gaps = "
                "their gaps kept, relative to the reference\n",
                static_cast<long long>(run.thin_pixels), static_cast<long long>(run.gap_pixels), run.reference_frames);
  const Series& ca = series[run.adaptive];
  if (!ca.pcss_clamped.empty())
    appendf(out, "  PCSS: %.1f %% of the filtered pixels held at the minimum penumbra (clamped; mean over the path, %.1f %% in its last "
                "frame)\n",
                100 * mean_of(ca.pcss_clamped), 100 * ca.pcss_clamped.back());
  if (ca.flicker_mean_abs.empty()) return out;
  appendf(out, "  %-26s %16s %14s %12s\n", "flicker along the path", "mean |dV|", "share > 1/255", "res changes");
  for (const Series& s : series)
    appendf(out, "  %-26s %16.5f %14.4f %12d\n", s.config.name.c_str(), mean_of(s.flicker_mean_abs), mean_of(s.flicker_share),
                s.resolution_changes);
  return out;
}

}  // namespace penumbra::demo
