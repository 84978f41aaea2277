#include "fit/frame_fit.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <stdexcept>

namespace penumbra::analysis {

namespace {

struct Cell {
  std::vector<BinomialRow> rows;
  std::set<std::string> participants;
  int trials = 0;
};

FrameThreshold fit_cells(const ModelSpec& base, const std::vector<const Cell*>& cells, double level, const std::string& technique,
                         const std::string& patch) {
  FrameThreshold t;
  t.technique = technique;
  t.patch = patch;
  ModelSpec spec = base;
  std::set<std::string> participants;
  for (const Cell* c : cells) {
    spec.groups.push_back({c->rows, 0, 0.0, std::nullopt});
    participants.insert(c->participants.begin(), c->participants.end());
    t.trials += c->trials;
  }
  t.participants = static_cast<int>(participants.size());
  t.fit = fit(spec);
  const ProfileInterval p = profile_interval(spec, t.fit, 0, level);
  const double u = t.fit.params.u[0];
  t.k = std::pow(10.0, -u);
  // k = 10^-u: the lower end of u is the upper end of k.
  t.k_profile = {std::pow(10.0, -p.hi), std::pow(10.0, -p.lo), p.hi_open, p.lo_open};
  t.beta = std::exp(t.fit.params.log_beta);
  // A slope at its bound is a step: the threshold's place is known, its interval is not to be trusted.
  if (t.beta >= 0.99 * spec.slope.max && !t.fit.flags.has("slope_at_upper_bound")) t.fit.flags.add("slope_at_upper_bound");
  t.usable = t.fit.converged && !p.lo_open && !p.hi_open && !t.fit.flags.has("threshold_at_bound") &&
             !t.fit.flags.has("slope_at_upper_bound") && !t.fit.flags.has("not_converged");
  return t;
}

std::string num(double v, const char* format = "%.3g") {
  char b[40];
  std::snprintf(b, sizeof b, format, v);
  return b;
}

nlohmann::json threshold_json(const FrameThreshold& t) {
  auto finite = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
  nlohmann::json j = {{"trials", t.trials},
                      {"participants", t.participants},
                      {"k", finite(t.k)},
                      {"ci95", {finite(t.k_profile.lo), finite(t.k_profile.hi)}},
                      {"ci95_open", {t.k_profile.lo_open, t.k_profile.hi_open}},
                      {"u", finite(t.fit.params.u[0])},
                      {"beta", finite(t.beta)},
                      {"lapse", finite(t.fit.params.lambda)},
                      {"converged", t.fit.converged},
                      {"usable", t.usable},
                      {"flags", t.fit.flags.list}};
  if (!t.technique.empty()) j["technique"] = t.technique;
  if (!t.patch.empty()) j["patch"] = t.patch;
  return j;
}

std::string interval_text(const FrameThreshold& t) {
  return (t.k_profile.lo_open ? "<" : "[") + num(t.k_profile.lo) + ", " + num(t.k_profile.hi) + (t.k_profile.hi_open ? ">" : "]");
}

}  // namespace

bool is_frame_study(const Dataset& data) {
  std::size_t frames = 0;
  for (const Trial& t : data.trials) frames += t.row.k > 0 ? 1 : 0;
  if (frames == 0) return false;
  if (frames != data.trials.size())
    throw std::runtime_error("the inputs mix a frame study's sessions (k in their logs) with the edge study's; fit them apart");
  return true;
}

FrameStudyFit fit_frame_study(const Dataset& data, const StudyFitOptions& options) {
  if (options.family == psychometric::Model::weibull)
    throw std::invalid_argument("--family weibull: a frame study is fitted in log k (log-weibull, normal or logistic)");
  FrameStudyFit out;
  out.sessions = static_cast<int>(data.sessions.size());
  out.practice_rows_excluded = data.practice_rows;
  std::set<double> p_thresholds, gammas, deltas;
  std::set<std::string> kinds;
  for (const SessionInfo& s : data.sessions) {
    if (s.quest) {
      p_thresholds.insert(s.quest->p_threshold);
      gammas.insert(s.quest->gamma);
      deltas.insert(s.quest->delta);
    }
    kinds.insert(s.observer_kind.empty() ? "unknown" : s.observer_kind);
    if (s.torn_tail) out.notes.push_back(s.log_file + ": last line torn (an unanswered trial); ignored");
  }
  out.observer_kinds.assign(kinds.begin(), kinds.end());
  out.p_threshold = options.p_threshold ? *options.p_threshold : (p_thresholds.size() == 1 ? *p_thresholds.begin() : 0.82);
  out.guess = options.guess ? *options.guess : (gammas.size() == 1 ? *gammas.begin() : 0.5);
  out.quest_delta = deltas.size() == 1 ? *deltas.begin() : 0.01;
  if (p_thresholds.size() > 1 || gammas.size() > 1 || deltas.size() > 1)
    out.notes.push_back("sessions use different QUEST parameters; the criterion uses pThreshold " + num(out.p_threshold) + ", gamma " +
                        num(out.guess) + ", delta " + num(out.quest_delta));
  out.criterion_f = psychometric::criterion_f(out.p_threshold, out.guess, out.quest_delta);
  if (!(out.criterion_f > 0 && out.criterion_f < 1))
    throw std::invalid_argument("--p-threshold " + num(out.p_threshold) + ": expected a proportion correct above the guess rate " +
                                num(out.guess));

  ModelSpec base;
  base.family = options.family;
  base.guess = out.guess;
  base.p_threshold = out.p_threshold;
  base.criterion_lapse = psychometric::quest_lapse(out.quest_delta, out.guess);  // thresholds on F, as QUEST's
  base.lapse = options.lapse;

  // One cell per technique and patch, in the order the logs first show them.
  std::vector<std::pair<std::string, std::string>> order;
  std::map<std::pair<std::string, std::string>, Cell> cells;
  for (const Trial& t : data.trials) {
    const auto key = std::make_pair(t.row.technique, t.row.staircase);
    if (!cells.count(key)) order.push_back(key);
    Cell& c = cells[key];
    c.rows.push_back({model_x(options.family, t.row.intensity), static_cast<double>(t.row.correct), 1.0});
    c.participants.insert(t.row.participant);
    ++c.trials;
    ++out.trials;
  }
  if (cells.empty()) throw std::runtime_error("no trials to fit (only practice rows)");
  std::vector<std::string> techniques;
  for (const auto& [technique, patch] : order)
    if (std::find(techniques.begin(), techniques.end(), technique) == techniques.end()) techniques.push_back(technique);
  std::vector<const Cell*> all;
  for (const auto& key : order) {
    out.patches.push_back(fit_cells(base, {&cells[key]}, options.level, key.first, key.second));
    all.push_back(&cells[key]);
  }
  for (const std::string& technique : techniques) {
    std::vector<const Cell*> own;
    for (const auto& key : order)
      if (key.first == technique) own.push_back(&cells[key]);
    out.techniques.push_back(fit_cells(base, own, options.level, technique, ""));
  }
  out.pooled = fit_cells(base, all, options.level, "", "");
  return out;
}

nlohmann::json frame_report_json(const FrameStudyFit& fit, const std::vector<std::string>& inputs, const std::string& created_utc) {
  nlohmann::json patches = nlohmann::json::array(), techniques = nlohmann::json::array();
  for (const FrameThreshold& t : fit.patches) patches.push_back(threshold_json(t));
  for (const FrameThreshold& t : fit.techniques) techniques.push_back(threshold_json(t));
  return {{"kind", "frame study"},
          {"created_utc", created_utc},
          {"inputs", inputs},
          {"threshold", {{"definition", "k* = 10^-u*, u = log10(1 / k): the multiple of the rule's c at which its frames are told "
                                        "from the reference with 2AFC probability p_threshold"},
                         {"p_threshold", fit.p_threshold},
                         {"guess", fit.guess},
                         {"quest_delta", fit.quest_delta},
                         {"criterion_f", fit.criterion_f},
                         {"interval", "95 % profile likelihood"}}},
          {"sessions", fit.sessions},
          {"trials", fit.trials},
          {"practice_rows_excluded", fit.practice_rows_excluded},
          {"observer_kinds", fit.observer_kinds},
          {"notes", fit.notes},
          {"patches", patches},
          {"techniques", techniques},
          {"pooled", threshold_json(fit.pooled)}};
}

std::string frame_summary_text(const FrameStudyFit& fit) {
  std::string s;
  s += "frame study: " + std::to_string(fit.sessions) + " session" + (fit.sessions == 1 ? "" : "s") + ", " + std::to_string(fit.trials) +
       " trials (" + std::to_string(fit.practice_rows_excluded) + " practice rows left out); observers:";
  for (const std::string& k : fit.observer_kinds) s += " " + k;
  s += "\nk* = the multiple of the rule's c at which its frames are told from the reference at " + num(fit.p_threshold * 100) +
       " % correct (F* " + num(fit.criterion_f, "%.4f") + "); 95 % profile-likelihood intervals\n";
  auto line = [&](const FrameThreshold& t, const std::string& label) {
    char b[300];
    std::snprintf(b, sizeof b, "  %-24s k* %-7s %-20s beta %-6s %5d trials, %d participant%s%s\n", label.c_str(), num(t.k).c_str(),
                  interval_text(t).c_str(), num(t.beta).c_str(), t.trials, t.participants, t.participants == 1 ? "" : "s",
                  t.usable ? "" : "  (not usable: an open interval, a bound, or no convergence)");
    s += b;
  };
  s += "per patch:\n";
  for (const FrameThreshold& t : fit.patches) line(t, t.technique + " " + t.patch);
  s += "per technique (its patches pooled):\n";
  for (const FrameThreshold& t : fit.techniques) line(t, t.technique);
  s += "pooled:\n";
  line(fit.pooled, "all");
  // The rule promises its frames at k = 1 are at the criterion (c is a threshold), so k* is 1 where
  // the constant measured on edges holds for these scenes.
  if (fit.pooled.usable && fit.pooled.k_profile.hi < 1)
    s += "k* below 1 (its interval too): the product's constant is wrong for these scenes: the rule's frames at c are told from the "
         "reference less often than the criterion, so c is larger than they need (memory nobody sees)\n";
  else if (fit.pooled.usable && fit.pooled.k_profile.lo > 1)
    s += "k* above 1 (its interval too): the product's constant is wrong for these scenes: the rule's frames at c are told from the "
         "reference more often than the criterion, so c is too small for them\n";
  else if (fit.pooled.usable)
    s += "k* = 1 lies inside the interval: the rule's frames at its own c are at the criterion, as the constant promises\n";
  for (const std::string& n : fit.notes) s += "note: " + n + "\n";
  return s;
}

}  // namespace penumbra::analysis
