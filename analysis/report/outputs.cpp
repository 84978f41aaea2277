#include "report/outputs.h"

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>

#include "published.h"
#include "json/json_input.h"

namespace penumbra::analysis {

namespace fs = std::filesystem;
using Json = nlohmann::json;

Json number(double v) { return std::isfinite(v) ? Json(v) : Json(nullptr); }

std::string utc_now() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}


namespace {

Json interval(const Interval& i) {
  return {{"lo", number(i.lo)}, {"hi", number(i.hi)}, {"lo_open", i.lo_open}, {"hi_open", i.hi_open}};
}

std::string fmt(const char* format, double v) {
  if (!std::isfinite(v)) return "-";
  char b[64];
  std::snprintf(b, sizeof b, format, v);
  return b;
}

std::string join(const std::vector<std::string>& v, const char* sep = ",") {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : sep) + x;
  return s;
}

}  // namespace

// The fitted psychometric function sampled for plotting (scripts/plot_fit.py draws it and computes
// nothing): proportion correct at 121 filter radii per artifact size r / a from 0.05 to 50, evenly
// in log, with the staircase's own lapse.
Json psychometric_curve(const ModelSpec& spec, const StaircaseFit& s) {
  const double beta = std::exp(s.fit.params.log_beta);
  const psychometric::Params<double> p{alpha_of(spec, s.fit.params.u[0], beta), beta, spec.guess, s.fit.params.lambda};
  Json ratio = Json::array(), correct = Json::array();
  for (int i = 0; i <= 120; ++i) {
    const double r_over_a = 0.05 * std::pow(10.0, 3.0 * i / 120.0);
    const double u = -std::log10(r_over_a);  // intensity log10(a / r)
    ratio.push_back(number(r_over_a));
    correct.push_back(number(psychometric::probability(spec.family, spec.family == psychometric::Model::weibull ? std::pow(10.0, u) : u, p)));
  }
  return {{"r_over_a", ratio}, {"p_correct", correct}};
}

// Hand-written: non-finite numbers as null, derived values (beta, standard errors) and the model spec's fields.
Json to_json(const FitResult& f, const ModelSpec& spec) {
  Json u = Json::array(), se_u = Json::array();
  for (std::size_t i = 0; i < f.params.u.size(); ++i) {
    u.push_back(number(f.params.u[i]));
    se_u.push_back(number(f.se(static_cast<int>(i))));
  }
  const double beta = std::exp(f.params.log_beta);
  Json j = {{"family", psychometric::model_name(spec.family)},
            {"guess", spec.guess},
            {"p_threshold", spec.p_threshold},
            {"lapse", spec.lapse.fixed ? Json{{"fixed", *spec.lapse.fixed}} : Json{{"max", spec.lapse.max}}},
            {"u", u},
            {"se_u", se_u},
            {"beta", number(beta)},
            {"se_beta", number(beta * f.se(f.index_log_beta()))},
            {"lambda", number(f.params.lambda)},
            {"se_lambda", number(f.se(f.index_lambda()))},
            {"corr_u0_log_beta", number(f.correlation(0, f.index_log_beta()))},
            {"nll", number(f.nll)},
            {"deviance", number(f.deviance)},
            {"trials", f.trials},
            {"converged", f.converged},
            {"iterations", f.iterations},
            {"u_bounds", {number(f.u_min), number(f.u_max)}},
            {"flags", f.flags.list}};
  if (spec.power_law) {
    j["s"] = number(f.params.s);
    j["se_s"] = number(f.se(f.index_s()));
  }
  return j;
}

const ConditionFit& calibration_condition(const StudyFit& fit, const std::optional<std::string>& wanted) {
  if (fit.conditions.empty()) throw std::invalid_argument("no conditions were fitted");
  if (wanted) {
    std::vector<std::string> names;
    for (const ConditionFit& c : fit.conditions) {
      if (c.condition == *wanted) return c;
      names.push_back(c.condition);
    }
    throw std::invalid_argument("--condition '" + json_input::printable(*wanted) + "': not in the data (" + join(names, ", ") + ")");
  }
  const ConditionFit* worst = &fit.conditions.front();
  for (const ConditionFit& c : fit.conditions)
    if (c.c > worst->c) worst = &c;
  return *worst;
}

CalibrationProvenance calibration_provenance(const Dataset& data, bool pool_observers) {
  // The technique that drew a session's stimuli (session.json's config.stimulus.technique); the
  // study's own filter shader (earlier logs) measured PCF's kernels.
  const auto technique_of = [](const SessionInfo& s) -> std::string {
    const auto it = s.setup.find("stimulus.technique");
    return it == s.setup.end() ? "pcf" : it->second;
  };
  // session.json's observer_kind -> calibration.json's obtained_by, and in words.
  const auto method_of = [](const std::string& kind) -> std::string {
    return kind == "person" ? "study" : kind == "psychometric-simulation" ? "simulated" : "image-observer";
  };
  const auto words = [](const std::string& kind, int count) -> std::string {
    if (kind == "person") return count == 1 ? "a person" : "people";
    return kind == "psychometric-simulation" ? "psychometric simulation" : "image observer";
  };
  CalibrationProvenance p;
  std::set<std::string> participants;
  std::map<std::string, int> sessions_of_kind;
  std::size_t first = data.sessions.size();  // the session p was taken from
  for (const Trial& t : data.trials) {
    const SessionInfo& s = data.sessions[t.session];
    if (s.observer_kind.empty())
      throw std::runtime_error(s.log_file + ": no session.json beside it: who answered (a person, a psychometric simulation or the "
                                            "image observer) is not recorded; fit the session directory");
    if (first == data.sessions.size()) {
      first = t.session;
      p.kernel = t.row.kernel;
      // Drawn by the renderer: the technique's own kernel setting, "" for a technique without one
      // (the entry then serves it whatever it runs; calibration.h).
      if (const auto it = s.setup.find("stimulus.technique"); it != s.setup.end()) {
        const auto kernel = s.setup.find("stimulus.settings." + it->second + ".kernel");
        p.kernel = kernel == s.setup.end() ? "" : kernel->second;
      }
      p.obtained_by = method_of(s.observer_kind);
      p.technique = technique_of(s);
    }
    const SessionInfo& f = data.sessions[first];
    if (technique_of(s) != p.technique)
      throw std::runtime_error(s.log_file + ": stimuli drawn by '" + technique_of(s) + "' where " + f.log_file + " has '" +
                               p.technique + "': a c per technique needs one fit per technique (fit them separately)");
    if (t.row.kernel != data.trials[0].row.kernel)
      throw std::runtime_error(s.log_file + ": kernel '" + t.row.kernel + "' where " + f.log_file + " has '" + data.trials[0].row.kernel +
                               "': a c per kernel needs one fit per kernel (fit the sessions of each kernel separately)");
    if (s.observer_kind != f.observer_kind && !pool_observers)
      throw std::runtime_error(s.log_file + ": answered by " + words(s.observer_kind, 1) + " (session.json observer_kind) where " +
                               f.log_file + " was answered by " + words(f.observer_kind, 1) +
                               ": people and simulated observers are not pooled (fit them separately, or --pool-observers)");
    participants.insert(s.participant);
  }
  for (const SessionInfo& s : data.sessions) ++sessions_of_kind[s.observer_kind];
  p.participants = static_cast<int>(participants.size());
  p.observers = words(data.sessions[first].observer_kind, p.participants);
  if (sessions_of_kind.size() > 1) {
    p.obtained_by = "mixed";
    p.observers.clear();
    for (const auto& [kind, n] : sessions_of_kind) {
      p.pooled_kinds.push_back(kind + " (" + std::to_string(n) + (n == 1 ? " session)" : " sessions)"));
      p.observers += (p.observers.empty() ? "" : " + ") + words(kind, n);
    }
    p.observers = "pooled: " + p.observers;
  }
  return p;
}

WorstCase entry_choice(const StudyFit& fit, const std::optional<std::string>& wanted) {
  if (!wanted) {
    if (fit.conditions.empty()) throw std::invalid_argument("no conditions were fitted");
    return fit.worst;
  }
  const ConditionFit& c = calibration_condition(fit, wanted);
  WorstCase w;
  w.method = "chosen (--condition)";
  w.condition = c.condition;
  w.c = c.c;
  w.profile = c.c_profile;
  w.bootstrap = c.bootstrap.c;
  w.resamples = c.bootstrap.resamples;
  const bool boot = std::isfinite(w.bootstrap.lo) && std::isfinite(w.bootstrap.hi);
  w.ci95 = boot && std::isfinite(w.profile.lo) && std::isfinite(w.profile.hi)
               ? Interval{std::min(w.profile.lo, w.bootstrap.lo), std::max(w.profile.hi, w.bootstrap.hi), w.profile.lo_open, w.profile.hi_open}
               : w.profile;
  w.beta = c.beta;
  w.beta_wald = c.beta_wald;
  w.lapse = c.linear.params.lambda;
  w.flags = c.flags;
  return w;
}

std::vector<std::string> unusable_because(const WorstCase& c) {
  std::vector<std::string> why;
  for (const char* flag : {"not_converged", "threshold_at_bound", "slope_at_upper_bound", "interval_open"})
    if (c.flags.has(flag)) why.push_back(flag);
  if (!(std::isfinite(c.profile.lo) && std::isfinite(c.profile.hi) && c.profile.lo > 0)) why.push_back("interval_not_finite");
  if (!(c.c >= kPlausibleCMin && c.c <= kPlausibleCMax)) {
    char b[96];
    std::snprintf(b, sizeof b, "c_outside_%g_%g", kPlausibleCMin, kPlausibleCMax);
    why.push_back(b);
  }
  return why;
}

Json population_json(const StudyFit& fit, const std::optional<std::string>& wanted) {
  const MultilevelFit& m = fit.population;
  if (!m.fitted) return nullptr;
  const auto pair = [](const MultilevelInterval& i) { return Json{number(i.lo), number(i.hi)}; };
  // The condition it speaks for: --condition's, else the population's worst (the largest mean), whose
  // interval is the largest of the simultaneous ones (it covers the worst true mean whatever the
  // differences between the conditions, with no test of them).
  std::size_t k = static_cast<std::size_t>(m.worst);
  bool chosen = false;
  if (wanted)
    for (std::size_t i = 0; i < fit.conditions.size(); ++i)
      if (fit.conditions[i].condition == *wanted) k = i, chosen = true;
  const MultilevelFit::Condition& c = m.conditions[k];
  const bool worst_over_several = !chosen && m.conditions.size() > 1;
  Json per = Json::array();
  for (std::size_t i = 0; i < m.conditions.size(); ++i) {
    const MultilevelFit::Condition& x = m.conditions[i];
    per.push_back({{"condition", fit.conditions[i].condition},
                   {"mean_c", number(x.mean_c)},
                   {"mean_c_ci95", pair(x.mean_c_ci)},
                   {"percentile_c", number(x.percentile_c)},
                   {"percentile_c_ci95", pair(x.percentile_c_ci)}});
  }
  char pct[32];
  std::snprintf(pct, sizeof pct, "%g", 100.0 * m.percentile);
  return {{"method", "multilevel: log10 c = condition mean (fixed) + participant offset (random, normal, the same in every condition), "
                     "integrated out by quadrature on 121 normal deviates; slope and lapse held at each condition's joint fit"},
          {"interval", "profile likelihood; means and percentiles with the squared Student t quantile (participants - 1 dof) as "
                       "cut-off, sd with chi2(1)"},
          {"participants", m.participants},
          {"condition", worst_over_several ? "the worst condition (" + fit.conditions[k].condition + ")" : fit.conditions[k].condition},
          {"mean_c", number(c.mean_c)},
          {"mean_c_ci95", pair(worst_over_several ? m.worst_mean_c_ci : c.mean_c_ci)},
          {"sd_log10", number(m.sd_log10)},
          {"sd_log10_ci95", {number(m.sd_ci.lo), number(m.sd_ci.hi)}},
          {"observer_percentile", std::string(pct)},
          {"percentile_c", number(c.percentile_c)},
          {"percentile_c_ci95", pair(worst_over_several ? m.worst_percentile_c_ci : c.percentile_c_ci)},
          {"worst_interval", worst_over_several ? "the largest of the conditions' simultaneous (Bonferroni) intervals" : "the condition's own"},
          {"converged", m.converged},
          {"flags", m.flags.list},
          {"per_condition", per}};
}

Json calibration_json(const StudyFit& fit, const std::optional<std::string>& condition, const std::string& created_utc,
                      const std::vector<std::string>& inputs, const CalibrationProvenance& provenance) {
  const WorstCase chosen = entry_choice(fit, condition);
  Json per = Json::array();
  for (const ConditionFit& c : fit.conditions) {
    per.push_back({{"condition", c.condition},
                   {"pattern", c.pattern},
                   {"contrast", c.contrast},
                   {"c", number(c.c)},
                   {"ci95", {number(std::min(c.c_profile.lo, c.c)), number(std::max(c.c_profile.hi, c.c))}},
                   {"ci95_bootstrap", {number(c.bootstrap.c.lo), number(c.bootstrap.c.hi)}},
                   {"beta", number(c.beta)},
                   {"beta_ci95", {number(c.beta_wald.lo), number(c.beta_wald.hi)}},
                   {"trials", c.trials},
                   {"participants", c.participant_count},
                   {"flags", c.flags.list}});
  }
  std::ostringstream source;
  source << "penumbra-fit: joint maximum-likelihood fit of r = c a (" << psychometric::model_name(fit.options.family)
         << "; c is the radius at detection probability F = " << fmt("%.4g", fit.criterion_f) << ", QUEST's criterion for "
         << fit.p_threshold << " correct, lapse free) to " << fit.trials << " trials from " << fit.sessions << " sessions; "
         << (condition ? "condition chosen by --condition"
                       : chosen.method == "pooled" ? "the conditions' c shrunk toward their mean show no difference (tau 0): one c for all, no maximum"
                                                   : chosen.method == "shrunken maximum"
                                                         ? "the worst condition: the largest of the conditions' c shrunk toward their mean (no significance gate)"
                                                         : "one condition")
         << "; ci95 holds the profile-likelihood, the participant-bootstrap and the multilevel population intervals; inputs: "
         << join(inputs, " ");
  Json threshold = {{"task", fit.task},
                    {"guess", fit.guess},
                    {"criterion_f", fit.criterion_f},
                    {"p_correct_at_criterion", fit.p_threshold},
                    {"quest_delta", fit.quest_delta},
                    {"family", std::string(psychometric::model_name(fit.options.family))},
                    {"beta", number(chosen.beta)},
                    {"lapse", number(chosen.lapse)}};
  if (std::isfinite(chosen.beta_wald.lo) && std::isfinite(chosen.beta_wald.hi) && chosen.beta_wald.lo > 0)
    threshold["beta_ci95"] = {std::min(chosen.beta_wald.lo, chosen.beta), std::max(chosen.beta_wald.hi, chosen.beta)};
  Json entry = {{"technique", provenance.technique},
                {"kernel", provenance.kernel},
                {"c", number(chosen.c)},
                {"condition", chosen.condition},
                {"obtained_by", provenance.obtained_by},
                {"observers", provenance.observers},
                {"participants", provenance.participants},
                {"trials", fit.trials},
                {"threshold", threshold},
                {"worst_case", {{"method", chosen.method},
                                {"conditions_differ_lr", number(chosen.lr_stat)},
                                {"conditions_differ_dof", chosen.lr_dof},
                                {"conditions_differ_p", number(chosen.lr_p)},
                                {"largest_c", number(chosen.max_c)},
                                {"bias_log10", number(chosen.bias_log10)},
                                {"tau_log10", number(chosen.tau_log10)},
                                {"resamples", chosen.resamples}}},
                {"per_condition", per},
                {"flags", chosen.flags.list}};
  if (Json population = population_json(fit, condition); !population.is_null()) entry["population"] = std::move(population);
  // An interval that is not finite is left out (the renderer reads a present one as numbers).
  auto finite = [](const Interval& i) { return std::isfinite(i.lo) && std::isfinite(i.hi) && i.lo > 0; };
  if (finite(chosen.ci95)) entry["ci95"] = {std::min(chosen.ci95.lo, chosen.c), std::max(chosen.ci95.hi, chosen.c)};
  if (finite(chosen.profile)) entry["ci95_profile"] = {std::min(chosen.profile.lo, chosen.c), std::max(chosen.profile.hi, chosen.c)};
  if (finite(chosen.bootstrap)) entry["ci95_bootstrap"] = {chosen.bootstrap.lo, chosen.bootstrap.hi};
  if (!provenance.pooled_kinds.empty()) entry["pooled_observer_kinds"] = provenance.pooled_kinds;
  if (const std::vector<std::string> why = unusable_because(chosen); !why.empty()) {
    entry["usable"] = false;
    entry["unusable_because"] = why;
  }
  return {{"schema_version", 2}, {"created_utc", created_utc}, {"source", source.str()}, {"entries", Json::array({entry})}};
}

Json report_json(const StudyFit& fit, const ReferenceTable* reference, const std::vector<std::string>& inputs,
                 const std::string& created_utc, const CalibrationProvenance& provenance) {
  Json conditions = Json::array();
  for (const ConditionFit& c : fit.conditions) {
    Json sizes = Json::array();
    for (std::size_t i = 0; i < c.artifact_px.size(); ++i) {
      const double a = c.artifact_px[i];
      Json s = {{"artifact_px", a}, {"r_linear_px", number(c.c * a)}};
      if (c.linearity_tested) {
        const SizeThreshold& t = c.sizes[i];
        s["trials"] = t.trials;
        s["c"] = number(t.c);
        s["c_wald"] = {number(t.c_lo), number(t.c_hi)};
        s["r_threshold_px"] = number(t.c * a);
        s["r_threshold_wald_px"] = {number(t.c_lo * a), number(t.c_hi * a)};
      }
      if (reference) {
        const ReferenceEntry* e = reference->find(c.pattern, c.contrast, a);
        s["reference_filter_radius_px"] = e && e->reference_px ? Json(*e->reference_px) : Json(nullptr);
        if (e && !e->reference_px) s["reference_note"] = "images still differ at r_max = " + fmt("%g", e->r_max_px) + " px";
        if (!e) s["reference_note"] = "not in the reference file";
      }
      sizes.push_back(s);
    }
    Json participants = Json::array();
    for (const ParticipantFit& p : c.participants) {
      participants.push_back({{"participant", p.participant},
                              {"c", number(p.c)},
                              {"c_wald", {number(p.c_lo), number(p.c_hi)}},
                              {"robust_z", number(p.robust_z)},
                              {"beta", number(std::exp(p.fit.params.log_beta))},
                              {"lambda", number(p.fit.params.lambda)},
                              {"trials", p.fit.trials},
                              {"flags", p.flags.list}});
    }
    Json j = {{"condition", c.condition},
              {"pattern", c.pattern},
              {"contrast", c.contrast},
              {"beta", number(c.beta)},
              {"beta_wald95", {number(c.beta_wald.lo), number(c.beta_wald.hi)}},
              {"trials", c.trials},
              {"participants", c.participant_count},
              {"artifact_px", c.artifact_px},
              {"c", number(c.c)},
              {"ci95_profile", interval(c.c_profile)},
              {"ci95_wald", interval(c.c_wald)},
              {"bootstrap", {{"resamples", c.bootstrap.resamples},
                             {"flagged", c.bootstrap.flagged},
                             {"ci95", interval(c.bootstrap.c)},
                             {"sd_log10_c", number(c.bootstrap.sd_log10_c)},
                             {"c_values", c.bootstrap.c_values}}},
              {"linear_fit", to_json(c.linear, c.spec)},
              {"sizes", sizes},
              {"participant_fits", participants},
              {"flags", c.flags.list}};
    if (c.linearity_tested) {
      ModelSpec per_size = c.spec;
      per_size.thresholds = static_cast<int>(c.artifact_px.size());
      j["linearity"] = {{"per_size_fit", to_json(c.per_size, per_size)},
                        {"lr_statistic", number(c.lr_linear_stat)},
                        {"dof", c.lr_linear_dof},
                        {"p_value", number(c.lr_linear_p)}};
    }
    if (c.power_law_tested) {
      ModelSpec power = c.spec;
      power.power_law = true;
      j["power_law"] = {{"model", "r = k a^p, fitted as u = u0 + s log10(a / a_ref), p = 1 - s"},
                        {"a_ref_px", number(c.a_ref_px)},
                        {"exponent", number(c.exponent)},
                        {"exponent_se", number(c.exponent_se)},
                        {"exponent_wald95", {number(c.exponent_wald.lo), number(c.exponent_wald.hi)}},
                        {"k_px", number(c.k_px)},
                        {"lr_statistic_vs_linear", number(c.lr_power_stat)},
                        {"p_value_vs_linear", number(c.lr_power_p)},
                        {"fit", to_json(c.power, power)}};
    }
    conditions.push_back(j);
  }
  Json staircases = Json::array();
  for (const StaircaseFit& s : fit.staircases) {
    Json track = Json::array();
    for (const TrackPoint& t : s.track)
      track.push_back({t.trial, t.intensity, t.filter_radius_px, t.correct, t.clamped ? 1 : 0});
    ModelSpec spec;
    spec.family = fit.options.family;
    spec.guess = fit.guess;
    spec.p_threshold = fit.p_threshold;
    spec.lapse.fixed = s.fit.params.lambda;
    Json j = {{"participant", s.participant},
              {"session_id", s.session_id},
              {"condition", s.condition},
              {"round", s.round},
              {"staircase", s.staircase},
              {"artifact_px", s.artifact_px},
              {"c", number(s.c)},
              {"c_wald", {number(s.c_lo), number(s.c_hi)}},
              {"r_threshold_px", number(s.c * s.artifact_px)},
              {"alpha", number(alpha_of(spec, s.fit.params.u[0], std::exp(s.fit.params.log_beta)))},
              {"fit", to_json(s.fit, spec)},
              {"curve", psychometric_curve(spec, s)},
              {"quest", {{"recomputed", s.quest_recomputed},
                         {"mean", number(s.quest_mean)},
                         {"sd", number(s.quest_sd)},
                         {"logged_mean", number(s.logged_quest_mean)},
                         {"logged_sd", number(s.logged_quest_sd)},
                         {"matches_log", s.quest_matches_log},
                         {"c_from_mean", number(std::pow(10.0, -(s.quest_recomputed ? s.quest_mean : s.logged_quest_mean)))}}},
              {"converged", s.converged},
              {"flags", s.flags.list},
              {"track_columns", {"trial", "intensity", "filter_radius_px", "correct", "clamped"}},
              {"track", track}};
    staircases.push_back(j);
  }
  Json reference_info = nullptr;
  if (reference) reference_info = {{"file", reference->file}, {"entries", reference->entries.size()}};
  // participant → pixels per degree of the display their session recorded (radii in visual angle).
  Json ppd = Json::object();
  for (const auto& [participant, value] : fit.pixels_per_degree) ppd[participant] = number(value);
  Json inconsistent = Json::array();
  for (const Inconsistency& i : fit.inconsistencies)
    inconsistent.push_back({{"file", i.file}, {"line", i.line}, {"trial", i.trial}, {"problem", i.problem}});
  return {{"tool", "penumbra-fit"},
          {"created_utc", created_utc},
          {"inputs", inputs},
          {"intensity", "u = log10(artifact_px / filter_radius_px); c = 10^-u; r_threshold = c * artifact_px"},
          {"options", {{"family", psychometric::model_name(fit.options.family)},
                       {"guess", fit.guess},
                       {"p_threshold", fit.p_threshold},
                       {"lapse", fit.options.lapse.fixed ? Json{{"fixed", *fit.options.lapse.fixed}}
                                                         : Json{{"max", fit.options.lapse.max}}},
                       {"bootstrap", fit.options.bootstrap},
                       {"seed", fit.options.seed},
                       {"accept_inconsistent", fit.options.accept_inconsistent},
                       {"pool", fit.options.pool}}},
          {"inconsistent_logs", inconsistent},
          {"pooled_differences", fit.pooled_differences},
          {"observers", {{"obtained_by", provenance.obtained_by},
                         {"in_words", provenance.observers},
                         {"participants", provenance.participants},
                         {"pooled_kinds", provenance.pooled_kinds}}},
          {"sessions", fit.sessions},
          {"pixels_per_degree", ppd},
          {"trials", fit.trials},
          {"practice_rows_excluded", fit.practice_rows_excluded},
          {"notes", fit.notes},
          {"published_c", kPublishedC},
          {"criterion", {{"detection_probability_f", fit.criterion_f},
                         {"p_correct", fit.p_threshold},
                         {"task", fit.task},
                         {"guess", fit.guess},
                         {"quest_delta", fit.quest_delta},
                         {"false_alarms", [&] {
                            // yes/no: each participant's catch trials and the guess rate their detections were fitted with
                            Json by = Json::object();
                            for (const auto& [participant, fa] : fit.false_alarms)
                              by[participant] = {{"catch_trials", fa.catch_trials}, {"false_alarms", fa.false_alarms},
                                                 {"guess", number(fa.rate)}};
                            return by;
                          }()},
                         {"meaning", "c is the filter radius per artifact at which the staircase is still detected with probability F "
                                     "(lapse free); a lower F needs a larger c"}}},
          {"worst_case", {{"method", fit.worst.method},
                          {"condition", fit.worst.condition},
                          {"c", number(fit.worst.c)},
                          {"ci95", interval(fit.worst.ci95)},
                          {"ci95_profile", interval(fit.worst.profile)},
                          {"ci95_bootstrap", interval(fit.worst.bootstrap)},
                          {"conditions_differ_lr", number(fit.worst.lr_stat)},
                          {"conditions_differ_dof", fit.worst.lr_dof},
                          {"conditions_differ_p", number(fit.worst.lr_p)},
                          {"ci95_population", interval(fit.worst.population)},
                          {"largest_c", number(fit.worst.max_c)},
                          {"bias_log10", number(fit.worst.bias_log10)},
                          {"tau_log10", number(fit.worst.tau_log10)},
                          {"resamples", fit.worst.resamples},
                          {"beta", number(fit.worst.beta)}}},
          {"population", population_json(fit, std::nullopt)},
          {"thesis_estimate", [&] {
             Json list = Json::array();
             for (const ThesisEstimate& t : fit.thesis) {
               double model_c = NAN;
               for (const ConditionFit& k : fit.conditions)
                 if (k.condition == t.condition) model_c = k.c;
               list.push_back({{"condition", t.condition},
                               {"method", "per participant and artifact size the radius of QUEST's final estimate; their mean per "
                                          "size; a line through the origin r = c a (least squares)"},
                               {"reading", "our reading of Kreuzer 2017 sec. 4.4, 5.1, which says only 'mean filter radii' computed "
                                           "from the data and a fitted linear function (not per participant, QUEST's final mean or "
                                           "through the origin); on the published design it lies about 18 % below a planted c "
                                           "(docs/fit.md)"},
                               {"c", number(t.c)},
                               {"model_c", number(model_c)},
                               {"relative_difference", number(t.c / model_c - 1.0)},
                               {"artifact_px", t.artifact_px},
                               {"mean_radius_px", t.mean_radius_px},
                               {"staircases", t.staircases}});
             }
             return list;
           }()},
          {"reference", reference_info},
          {"conditions", conditions},
          {"staircases", staircases}};
}

std::string summary_text(const StudyFit& fit, const ReferenceTable* reference,
                         const std::optional<std::string>& wanted, const CalibrationProvenance& provenance) {
  std::ostringstream o;
  o << "penumbra-fit: " << fit.trials << " trials (" << fit.practice_rows_excluded << " practice rows excluded) from "
    << fit.sessions << " sessions answered by " << provenance.observers << " (" << provenance.participants
    << (provenance.participants == 1 ? " participant" : " participants") << "); " << psychometric::model_name(fit.options.family) << ", threshold at "
    << fit.p_threshold << " correct, guess " << fit.guess << ", lapse "
    << (fit.options.lapse.fixed ? "fixed " + fmt("%g", *fit.options.lapse.fixed) : "in [0, " + fmt("%g", fit.options.lapse.max) + "]")
    << "\n";
  if (!provenance.pooled_kinds.empty()) {
    o << "OBSERVER KINDS POOLED (--pool-observers):";
    for (const std::string& k : provenance.pooled_kinds) o << " " << k;
    o << "\n";
  }
  if (!fit.pooled_differences.empty()) {
    o << "SESSIONS POOLED ALTHOUGH MEASURED DIFFERENTLY (--pool): " << fit.pooled_differences.size() << " field(s)\n";
    for (const std::string& d : fit.pooled_differences) o << "  " << d << "\n";
  }
  if (!fit.inconsistencies.empty()) {
    o << "INCONSISTENT LOGS FITTED (--accept-inconsistent): " << fit.inconsistencies.size()
      << " logs the study could not have written as they stand; first problem of each:\n";
    for (const Inconsistency& i : fit.inconsistencies) o << "  " << i.problem << "\n";
  }
  o << "\n";
  char line[512];
  std::snprintf(line, sizeof line, "%-10s %6s %5s %7s %17s %17s %6s %6s %9s %14s  %s\n", "condition", "trials",
                "ppl", "c", "95% profile", "95% bootstrap", "beta", "lapse", "lin. p", "exponent p", "flags");
  o << line;
  for (const ConditionFit& c : fit.conditions) {
    const std::string profile = "[" + fmt("%.3f", c.c_profile.lo) + ", " + fmt("%.3f", c.c_profile.hi) + "]";
    const std::string boot = c.bootstrap.resamples ? "[" + fmt("%.3f", c.bootstrap.c.lo) + ", " + fmt("%.3f", c.bootstrap.c.hi) + "]" : "-";
    const std::string exponent = c.power_law_tested ? fmt("%.3f", c.exponent) + " +- " + fmt("%.3f", c.exponent_se) : "-";
    std::snprintf(line, sizeof line, "%-10s %6d %5d %7.3f %17s %17s %6s %6s %9s %14s  %s\n", c.condition.c_str(),
                  c.trials, c.participant_count, c.c, profile.c_str(), boot.c_str(),
                  fmt("%.2f", std::exp(c.linear.params.log_beta)).c_str(), fmt("%.3f", c.linear.params.lambda).c_str(),
                  c.linearity_tested ? fmt("%.3g", c.lr_linear_p).c_str() : "-", exponent.c_str(),
                  join(c.flags.list).c_str());
    o << line;
  }
  o << "\nthreshold filter radius per artifact size (free per-size thresholds, Wald 95 %)";
  if (reference) o << " and reference filter size";
  o << "\n";
  std::snprintf(line, sizeof line, "%-10s %6s %6s %9s %21s %9s %11s\n", "condition", "a_px", "trials", "r_px",
                "95% Wald", "c*a_px", "reference");
  o << line;
  for (const ConditionFit& c : fit.conditions) {
    for (std::size_t i = 0; i < c.artifact_px.size(); ++i) {
      const double a = c.artifact_px[i];
      std::string ref = "-";
      if (reference) {
        const ReferenceEntry* e = reference->find(c.pattern, c.contrast, a);
        ref = !e ? "n/a" : e->reference_px ? fmt("%.2f", *e->reference_px) : "> " + fmt("%g", e->r_max_px);
      }
      if (c.linearity_tested) {
        const SizeThreshold& t = c.sizes[i];
        const std::string wald = "[" + fmt("%.2f", t.c_lo * a) + ", " + fmt("%.2f", t.c_hi * a) + "]";
        std::snprintf(line, sizeof line, "%-10s %6g %6d %9.2f %21s %9.2f %11s\n", c.condition.c_str(), a, t.trials,
                      t.c * a, wald.c_str(), c.c * a, ref.c_str());
      } else {
        std::snprintf(line, sizeof line, "%-10s %6g %6s %9s %21s %9.2f %11s\n", c.condition.c_str(), a, "-", "-", "-",
                      c.c * a, ref.c_str());
      }
      o << line;
    }
  }
  o << "\nper participant c (joint linear fit of the participant's trials, Wald 95 %)\n";
  for (const ConditionFit& c : fit.conditions) {
    for (const ParticipantFit& p : c.participants) {
      std::snprintf(line, sizeof line, "%-10s %-12s c %7.3f [%s, %s]  z %6s  %s\n", c.condition.c_str(),
                    p.participant.c_str(), p.c, fmt("%.3f", p.c_lo).c_str(), fmt("%.3f", p.c_hi).c_str(),
                    fmt("%+.2f", p.robust_z).c_str(), join(p.flags.list).c_str());
      o << line;
    }
  }
  int not_converged = 0, differs = 0;
  for (const StaircaseFit& s : fit.staircases) {
    not_converged += s.converged ? 0 : 1;
    differs += s.quest_matches_log ? 0 : 1;
  }
  o << "\nstaircases: " << fit.staircases.size() << ", not converged: " << not_converged
    << ", QUEST replay differing from the log: " << differs << "\n";
  for (const StaircaseFit& s : fit.staircases) {
    if (s.converged && s.quest_matches_log) continue;
    std::snprintf(line, sizeof line, "  %-12s %-10s %-6s c %7.3f  QUEST sd %s  %s\n", s.participant.c_str(),
                  s.condition.c_str(), s.staircase.c_str(), s.c,
                  fmt("%.3f", s.quest_recomputed ? s.quest_sd : s.logged_quest_sd).c_str(), join(s.flags.list).c_str());
    o << line;
  }
  for (const std::string& n : fit.notes) o << "note: " << n << "\n";
  const WorstCase chosen = entry_choice(fit, wanted);
  o << "\nc is the radius at which the staircase is still detected with probability F = " << fmt("%.4g", fit.criterion_f)
    << " (QUEST's criterion, " << fit.p_threshold << " correct in " << fit.task << "), not hidden; lower F needs a larger c\n";
  for (const ConditionFit& c : fit.conditions)
    o << "  " << c.condition << ": slope beta " << fmt("%.2f", c.beta) << " [" << fmt("%.2f", c.beta_wald.lo) << ", "
      << fmt("%.2f", c.beta_wald.hi) << "], lapse " << fmt("%.3f", c.linear.params.lambda) << "\n";
  if (fit.conditions.size() > 1)
    o << "conditions differ? LR " << fmt("%.2f", chosen.lr_stat) << " on " << chosen.lr_dof << " dof, p " << fmt("%.3g", chosen.lr_p)
      << (wanted ? "" : " (decides nothing); the conditions' c shrunk toward their mean (tau " + fmt("%.3f", chosen.tau_log10) + " log10): " +
                            (chosen.method == "pooled" ? std::string("no difference left, one c for all (no maximum, no selection bias)")
                                                       : "the largest, " + chosen.condition + " (plain maximum " + fmt("%.3f", chosen.max_c) + ")"))
      << "\n";
  o << "\ncalibration: c = " << fmt("%.3f", chosen.c) << " [" << fmt("%.3f", chosen.ci95.lo) << ", " << fmt("%.3f", chosen.ci95.hi)
    << "] (profile, participant bootstrap and population; profile alone [" << fmt("%.3f", chosen.profile.lo) << ", "
    << fmt("%.3f", chosen.profile.hi) << "]) from " << chosen.condition << " (" << chosen.method << "), " << provenance.observers
    << "; published c = " << fmt("%g", kPublishedC) << "\n";
  if (const Json p = population_json(fit, wanted); !p.is_null()) {
    const auto v = [](const Json& x) { return x.is_number() ? fmt("%.3f", x.get<double>()) : std::string("n/a"); };
    o << "population (multilevel, participants as random effects): mean c = " << v(p["mean_c"]) << " [" << v(p["mean_c_ci95"][0])
      << ", " << v(p["mean_c_ci95"][1]) << "], sd " << v(p["sd_log10"]) << " log10 [" << v(p["sd_log10_ci95"][0]) << ", "
      << v(p["sd_log10_ci95"][1]) << "], " << p["observer_percentile"].get<std::string>() << "th-percentile observer c = "
      << v(p["percentile_c"]) << " [" << v(p["percentile_c_ci95"][0]) << ", " << v(p["percentile_c_ci95"][1]) << "] ("
      << p["condition"].get<std::string>() << ", " << fit.population.participants << " participants)\n";
  }
  for (const ThesisEstimate& t : fit.thesis) {
    const ConditionFit* c = nullptr;
    for (const ConditionFit& k : fit.conditions)
      if (k.condition == t.condition) c = &k;
    o << "thesis-style estimate (our reading: mean QUEST radius per size, a line through the origin): " << t.condition << " c = "
      << fmt("%.3f", t.c);
    if (c) o << " against the model's " << fmt("%.3f", c->c) << " (" << fmt("%+.1f", 100.0 * (t.c / c->c - 1.0)) << " %)";
    o << "\n";
  }
  if (const std::vector<std::string> why = unusable_because(chosen); !why.empty())
    o << "NOT USABLE as a calibration: " << join(why, ", ") << " (c is trusted in [" << fmt("%g", kPlausibleCMin) << ", "
      << fmt("%g", kPlausibleCMax) << "] from a converged fit with a closed interval); penumbra-fit writes it only with "
         "--allow-unusable, marked \"usable\": false\n";
  return o.str();
}

}  // namespace penumbra::analysis
