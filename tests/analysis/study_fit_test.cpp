// The study analysis on simulated studies (the study's procedure and planted observer, no GL):
// recovery of c, the linearity check and the power-law exponent, QUEST recomputed from the log,
// outlying participants, degenerate studies, the bootstrap, calibration.json read back by the
// renderer's reader, results independent of the thread count and the progress of each phase.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <numeric>
#include <set>
#include <string>
#include <unistd.h>
#include <vector>

#include "adaptive/resolution_rule.h"
#include "data/simulate.h"
#include "fit/study_fit.h"
#include "io/atomic_file.h"
#include "psychometric/psychometric.h"
#include "report/outputs.h"

namespace {

using namespace penumbra;
using namespace penumbra::analysis;

SimulatedStudy study_with(double c_true, std::uint64_t seed) {
  SimulatedStudy s;
  s.participants = 10;
  s.artifact_px = {5, 10, 20};
  s.trials_per_staircase = 40;
  s.conditions[0].planted.c_true = c_true;
  s.conditions[0].planted.lapse = 0.01;
  s.seed = seed;
  return s;
}

StudyFitOptions quick() {
  StudyFitOptions o;
  o.bootstrap = 0;
  o.threads = 2;
  return o;
}

// About 10 participants x 3 sizes x 40 trials: the fitted c is within 5 % of the planted one.
TEST(StudyFit, RecoversPlantedC) {
  for (double c_true : {2.0, 3.47, 5.0}) {
    const SimulatedStudy s = study_with(c_true, 100 + static_cast<std::uint64_t>(c_true * 100));
    const StudyFit f = fit_study(as_dataset(s, simulate_study(s)), quick());
    ASSERT_EQ(f.conditions.size(), 1u);
    const ConditionFit& c = f.conditions[0];
    EXPECT_EQ(c.trials, 1200);
    EXPECT_EQ(c.participant_count, 10);
    EXPECT_NEAR(c.c / c_true, 1.0, 0.05) << "planted " << c_true << " fitted " << c.c;
    EXPECT_LT(c.c_profile.lo, c.c);
    EXPECT_GT(c.c_profile.hi, c.c);
    EXPECT_LT(c.c_profile.hi / c.c_profile.lo, 1.2);  // about +-5 %: the interval is informative
    EXPECT_TRUE(std::isfinite(c.c_wald.lo));
    EXPECT_EQ(f.staircases.size(), 30u);
    for (const StaircaseFit& sf : f.staircases) {
      EXPECT_TRUE(sf.quest_recomputed);
      EXPECT_TRUE(sf.quest_matches_log) << sf.participant << " " << sf.staircase;
    }
  }
}

// Sizes and planted per-size c from r = k a^p with p = 0.7: the linear model is rejected and the
// exponent recovered; with p = 1 neither happens.
TEST(StudyFit, LinearityCheckAndPowerLawExponent) {
  for (double p : {0.7, 1.0}) {
    Dataset data;
    const double k = 3.0 * std::pow(10.0, 1.0 - p);  // r(10) = 30 px either way
    for (double a : {5.0, 10.0, 20.0}) {
      SimulatedStudy s = study_with(k * std::pow(a, p) / a, 7 + static_cast<std::uint64_t>(a));
      s.artifact_px = {a};
      s.trials_per_staircase = 60;
      const Dataset part = as_dataset(s, simulate_study(s));
      for (Trial t : part.trials) {
        t.session = data.sessions.size() + t.session;
        t.row.session_id += "-a" + std::to_string(int(a));
        data.trials.push_back(t);
      }
      for (SessionInfo info : part.sessions) {
        info.session_id += "-a" + std::to_string(int(a));
        data.sessions.push_back(info);
      }
    }
    const StudyFit f = fit_study(data, quick());
    const ConditionFit& c = f.conditions[0];
    ASSERT_TRUE(c.linearity_tested);
    ASSERT_EQ(c.sizes.size(), 3u);
    EXPECT_EQ(c.lr_linear_dof, 2);
    if (p < 1) {
      EXPECT_LT(c.lr_linear_p, 1e-3);
      EXPECT_LT(c.lr_power_p, 1e-3);
    } else {
      EXPECT_GT(c.lr_linear_p, 0.01);
    }
    EXPECT_NEAR(c.exponent, p, 3 * c.exponent_se) << "p = " << p;
    EXPECT_LT(c.exponent_se, 0.06);
    EXPECT_NEAR(c.k_px, k, 0.15 * k);
    // Per-size thresholds: r_k = c_k a against the planted r.
    for (const SizeThreshold& st : c.sizes)
      EXPECT_NEAR(st.c * st.artifact_px / (k * std::pow(st.artifact_px, p)), 1.0, 0.1) << st.artifact_px;
  }
}

TEST(StudyFit, FlagsAParticipantFarFromTheRest) {
  SimulatedStudy s = study_with(3.0, 42);
  std::vector<SimulatedSession> sessions = simulate_study(s);
  SimulatedStudy odd = s;
  odd.participants = 1;
  odd.conditions[0].planted.c_true = 8.0;
  odd.seed = 4242;
  SimulatedSession outlier = simulate_study(odd)[0];
  outlier.participant = "odd";
  for (auto& r : outlier.rows) {
    r.participant = "odd";
    r.session_id = "odd-sim";
  }
  sessions.push_back(outlier);
  const StudyFit f = fit_study(as_dataset(s, sessions), quick());
  int flagged = 0;
  for (const ParticipantFit& p : f.conditions[0].participants) {
    if (p.flags.has("far_from_rest")) {
      ++flagged;
      EXPECT_EQ(p.participant, "odd");
    }
  }
  EXPECT_EQ(flagged, 1);
  EXPECT_TRUE(f.conditions[0].flags.has("participant_far_from_rest"));
}

TEST(StudyFit, DegenerateStudiesNeverGiveANaNc) {
  SimulatedStudy s = study_with(3.0, 9);
  s.participants = 2;
  s.trials_per_staircase = 5;
  std::vector<SimulatedSession> sessions = simulate_study(s);
  for (auto mode : {0, 1, 2}) {
    std::vector<SimulatedSession> edited = sessions;
    for (auto& session : edited) {
      for (auto& r : session.rows) {
        r.correct = mode == 0 ? 1 : mode == 1 ? 0 : r.correct;  // all correct / all wrong / as simulated
        r.response = (r.correct == 1) == (r.target == "left") ? "left" : "right";
      }
      if (mode == 2) session.rows.resize(1);  // one trial per participant
    }
    const StudyFit f = fit_study(as_dataset(s, edited), quick());
    const ConditionFit& c = f.conditions[0];
    EXPECT_TRUE(std::isfinite(c.c) && c.c > 0) << mode;
    EXPECT_FALSE(c.flags.list.empty()) << mode;
    EXPECT_TRUE(std::isfinite(c.c_profile.lo) && std::isfinite(c.c_profile.hi)) << mode;
    for (const StaircaseFit& sf : f.staircases) EXPECT_TRUE(std::isfinite(sf.c)) << mode;
  }
}

TEST(StudyFit, BootstrapIsSeededAndIndependentOfThreads) {
  SimulatedStudy s = study_with(3.47, 77);
  s.participants = 6;
  s.trials_per_staircase = 20;
  const Dataset data = as_dataset(s, simulate_study(s));
  StudyFitOptions o = quick();
  o.bootstrap = 40;
  o.threads = 1;
  const StudyFit one = fit_study(data, o);
  o.threads = 3;
  const StudyFit three = fit_study(data, o);
  EXPECT_EQ(one.conditions[0].bootstrap.c_values, three.conditions[0].bootstrap.c_values);
  EXPECT_LT(one.conditions[0].bootstrap.c.lo, one.conditions[0].c);
  EXPECT_GT(one.conditions[0].bootstrap.c.hi, one.conditions[0].c);
  o.seed = 2;
  EXPECT_NE(fit_study(data, o).conditions[0].bootstrap.c_values, one.conditions[0].bootstrap.c_values);
}

// calibration.json as the renderer reads it (the renderer never links analysis; this test links both).
TEST(StudyFit, CalibrationRoundTripsThroughTheRenderersReader) {
  SimulatedStudy s = study_with(3.47, 5);
  s.conditions.push_back({"step", 1.0, s.conditions[0].planted});
  s.conditions[1].planted.c_true = 4.5;
  const Dataset d = as_dataset(s, simulate_study(s));
  const StudyFit f = fit_study(d, quick());
  ASSERT_EQ(f.conditions.size(), 2u);
  const CalibrationProvenance provenance = calibration_provenance(d);
  const auto dir = std::filesystem::temp_directory_path() / ("penumbra-cal-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const nlohmann::json j = calibration_json(f, std::nullopt, "2024-01-01T00:00:00Z", {"sim"}, provenance);
  io::write_file_atomic(dir / "calibration.json", j.dump(2));
  const adaptive::Calibration file = adaptive::load_calibration(dir / "calibration.json");
  EXPECT_EQ(file.schema_version, 2);
  ASSERT_EQ(file.entries.size(), 1u);
  const adaptive::CalibrationEntry& cal = file.entries[0];
  const ConditionFit& worst = f.conditions[1];
  EXPECT_EQ(cal.technique, "pcf");
  EXPECT_EQ(cal.kernel, "disk");
  EXPECT_EQ(cal.obtained_by, adaptive::CalibrationMethod::simulated);  // a psychometric observer answered
  EXPECT_EQ(cal.participants, static_cast<int>(d.sessions.size()));
  EXPECT_EQ(cal.trials, f.trials);
  EXPECT_EQ(cal.condition, "step/1");
  // Issue 48: the shrunken maximum (two conditions 30 % apart: barely shrunk), its ci95 the hull
  // of the condition's profile interval and the population's worst-case interval.
  EXPECT_EQ(f.worst.method, "shrunken maximum");
  EXPECT_DOUBLE_EQ(cal.c, f.worst.c);
  EXPECT_NEAR(cal.c, worst.c, 0.01 * worst.c);
  EXPECT_NEAR(cal.c, 4.5, 0.05 * 4.5);
  EXPECT_DOUBLE_EQ(cal.ci95_lo, std::min(f.worst.ci95.lo, f.worst.c));
  EXPECT_DOUBLE_EQ(cal.ci95_hi, std::max(f.worst.ci95.hi, f.worst.c));
  EXPECT_LE(cal.ci95_lo, worst.c_profile.lo);
  EXPECT_GE(cal.ci95_hi, worst.c_profile.hi);
  EXPECT_LE(cal.ci95_lo, f.worst.population.lo);
  EXPECT_GE(cal.ci95_hi, f.worst.population.hi);
  ASSERT_TRUE(j["entries"][0].contains("population"));
  EXPECT_EQ(j["entries"][0]["population"]["observer_percentile"], "90");
  // The renderer reads the population block as written and asks it for a percentile observer:
  // the fitted 90th percentile's own c and interval, and the median observer at the mean c.
  const nlohmann::json& population = j["entries"][0]["population"];
  ASSERT_TRUE(cal.population.has_value());
  EXPECT_EQ(cal.population->percentile, 90.0);
  EXPECT_DOUBLE_EQ(cal.population->mean_c, population["mean_c"].get<double>());
  EXPECT_DOUBLE_EQ(cal.population->sd_log10, population["sd_log10"].get<double>());
  const adaptive::CAtPercentile p90 = adaptive::c_at_observer_percentile(cal, 90);
  EXPECT_TRUE(p90.fitted);
  EXPECT_DOUBLE_EQ(p90.c, population["percentile_c"].get<double>());
  EXPECT_DOUBLE_EQ(p90.lo, population["percentile_c_ci95"][0].get<double>());
  EXPECT_DOUBLE_EQ(p90.hi, population["percentile_c_ci95"][1].get<double>());
  EXPECT_GE(p90.c, cal.population->mean_c);
  EXPECT_NEAR(adaptive::c_at_observer_percentile(cal, 50).c, cal.population->mean_c, 1e-12);
  EXPECT_EQ(j["entries"][0]["per_condition"].size(), 2u);
  const nlohmann::json stair = calibration_json(f, std::string("stair/1"), "2024-01-01T00:00:00Z", {"sim"}, provenance);
  io::write_file_atomic(dir / "stair.json", stair.dump(2));
  EXPECT_EQ(adaptive::load_calibration(dir / "stair.json").entries.at(0).condition, "stair/1");
  EXPECT_THROW(calibration_json(f, std::string("stair/0.5"), "", {}, provenance), std::invalid_argument);
  std::filesystem::remove_all(dir);
}

}  // namespace

namespace {

// Four conditions (stair and step at full and half contrast) of one planted observer.
SimulatedStudy four_equal_conditions(double c_true, int participants, std::uint64_t seed) {
  SimulatedStudy s;
  s.participants = participants;
  s.artifact_px = {5, 10, 20};
  s.trials_per_staircase = 40;
  s.conditions.clear();
  for (const auto& [pattern, contrast] : {std::pair{"stair", 1.0}, {"step", 1.0}, {"stair", 0.5}, {"step", 0.5}}) {
    SimulatedCondition c;
    c.pattern = pattern;
    c.contrast = contrast;
    c.planted.c_true = c_true;
    c.planted.lapse = 0.02;
    s.conditions.push_back(c);
  }
  s.seed = seed;
  return s;
}

}  // namespace

// Issue 29: a threshold is defined on F, lapse free, as QUEST's: the fitted c does not move with
// the observer's lapse (defined on psi it fell by up to 6 % as the fitted lapse went 0 -> 0.06),
// and is within its interval of the planted one, for several slopes.
TEST(StudyFit, TheThresholdIsOnFAndDoesNotMoveWithTheLapse) {
  for (double beta : {2.0, 3.5, 6.0}) {
    std::vector<double> log_ratio;
    for (double lapse : {0.0, 0.02, 0.04}) {
      SimulatedStudy s = study_with(3.0, 4000 + static_cast<std::uint64_t>(beta * 10));  // the same answers' randomness
      s.participants = 12;
      s.conditions[0].planted.slope = beta;
      s.conditions[0].planted.lapse = lapse;
      StudyFitOptions o = quick();
      o.lapse.max = 0.06;
      const StudyFit f = fit_study(as_dataset(s, simulate_study(s)), o);
      const ConditionFit& c = f.conditions[0];
      EXPECT_NEAR(f.criterion_f, 0.6464646464646464, 1e-12);
      EXPECT_LE(c.c_profile.lo, 3.0 * 1.02) << "beta " << beta << " lapse " << lapse;
      EXPECT_GE(c.c_profile.hi, 3.0 / 1.02) << "beta " << beta << " lapse " << lapse;
      log_ratio.push_back(std::log10(c.c / 3.0));
    }
    // From lapse 0 to 0.04 the fitted c moves less than 3 % (on psi the definition itself moved it
    // by 1-6 % whatever the data).
    EXPECT_LT(std::abs(log_ratio.back() - log_ratio.front()), std::log10(1.03)) << "beta " << beta;
  }
}

// Issue 29: c at another detection probability follows the fitted slope: the entry's c at F 0.1
// and 0.9 (adaptive::c_at_visibility on calibration.json's threshold block) brackets the planted
// function's, within the interval propagated from c's and the slope's.
TEST(StudyFit, CAtAnotherVisibilityMatchesThePlantedFunction) {
  SimulatedStudy s = study_with(3.0, 77);
  s.participants = 16;
  s.conditions[0].planted.slope = 3.5;
  const Dataset d = as_dataset(s, simulate_study(s));
  StudyFitOptions o = quick();
  o.bootstrap = 100;
  const StudyFit f = fit_study(d, o);
  const nlohmann::json j = calibration_json(f, std::nullopt, "2024-01-01T00:00:00Z", {"sim"}, calibration_provenance(d));
  const auto dir = std::filesystem::temp_directory_path() / ("penumbra-visibility-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  io::write_file_atomic(dir / "calibration.json", j.dump(2));
  const adaptive::CalibrationEntry e = adaptive::load_calibration(dir / "calibration.json").entries[0];
  ASSERT_TRUE(e.threshold.has_value());
  EXPECT_NEAR(e.threshold->criterion_f, 0.6464646464646464, 1e-12);
  EXPECT_FALSE(e.threshold->beta_assumed);
  for (double visibility : {0.1, 0.9}) {
    const double planted = adaptive::c_at_visibility(3.0, psychometric::criterion_f(0.82, 0.5, 0.01), visibility, 3.5);
    const adaptive::CAtVisibility fitted = adaptive::c_at_visibility(e, visibility);
    EXPECT_LE(fitted.lo, planted) << visibility;
    EXPECT_GE(fitted.hi, planted) << visibility;
    EXPECT_NEAR(fitted.c / planted, 1.0, 0.15) << visibility;
  }
  // The direction and size the issue states: 55 % correct in 2AFC (F 0.10) takes about 1.9 c with slope 3.5.
  EXPECT_NEAR(adaptive::c_at_visibility(1.0, psychometric::criterion_f(0.82, 0.5, 0.01), (0.55 - 0.5) / (0.5 * 0.99), 3.5), 1.92, 0.01);
  std::filesystem::remove_all(dir);
}

// Issue 48: far from the criterion, c(F) is the family's as much as the data's. The same study
// refitted with the normal and the logistic (the Weibull on a / r is the log-Weibull on log10 of
// it) gives c(0.1) values that the log-Weibull entry's interval at F 0.1 must hold, as
// adaptive::c_at_visibility's family hull promises; at the criterion the families agree on c.
TEST(StudyFit, CFarFromTheCriterionHoldsTheOtherFamiliesRefits) {
  SimulatedStudy s = study_with(3.0, 78);
  s.participants = 12;
  s.conditions[0].planted.slope = 3.5;
  const Dataset d = as_dataset(s, simulate_study(s));
  const auto dir = std::filesystem::temp_directory_path() / ("penumbra-families-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const auto entry_for = [&](psychometric::Model family) {
    StudyFitOptions o = quick();
    o.family = family;
    const StudyFit f = fit_study(d, o);
    const nlohmann::json j = calibration_json(f, std::nullopt, "2024-01-01T00:00:00Z", {"sim"}, calibration_provenance(d));
    io::write_file_atomic(dir / "calibration.json", j.dump(2));
    return adaptive::load_calibration(dir / "calibration.json").entries[0];
  };
  const adaptive::CalibrationEntry lw = entry_for(psychometric::Model::log_weibull);
  ASSERT_TRUE(lw.threshold.has_value());
  for (const auto model : {psychometric::Model::normal, psychometric::Model::logistic}) {
    const adaptive::CalibrationEntry other = entry_for(model);
    ASSERT_TRUE(other.threshold.has_value());
    EXPECT_EQ(other.threshold->family, psychometric::model_name(model));
    EXPECT_NEAR(other.c / lw.c, 1.0, 0.03) << psychometric::model_name(model);
    for (const double visibility : {0.1, 0.3}) {
      const adaptive::CAtVisibility range = adaptive::c_at_visibility(lw, visibility);
      const double refit = adaptive::c_at_visibility(other, visibility).c;
      std::printf("F %.2f: log-weibull c %.3f [%.3f, %.3f] (family alone [%.3f, %.3f]); %s refit %.3f\n", visibility, range.c, range.lo,
                  range.hi, range.family_lo, range.family_hi, std::string(psychometric::model_name(model)).c_str(), refit);
      EXPECT_LE(range.lo, refit) << psychometric::model_name(model) << " at F " << visibility;
      EXPECT_GE(range.hi, refit) << psychometric::model_name(model) << " at F " << visibility;
    }
  }
  std::filesystem::remove_all(dir);
}

// Issue 29: with conditions of equal c, the largest of their estimates was the entry's c (biased
// up 3-4 %, the documented 3.19 for a planted 3.0). The entry's c is now unbiased: over 10 studies
// of four equal conditions, the mean log ratio to the planted c is within 1.5 %. Issue 48: no test
// decides; the shrinkage finds no difference (tau 0, the pooled c) in most of them.
TEST(StudyFit, TheEntrysCHasNoSelectionBias) {
  double sum_entry = 0, sum_max = 0;
  int pooled = 0;
  constexpr int kStudies = 10;
  for (int i = 0; i < kStudies; ++i) {
    const SimulatedStudy s = four_equal_conditions(3.0, 6 + i % 5, 7000 + static_cast<std::uint64_t>(i));
    const StudyFit f = fit_study(as_dataset(s, simulate_study(s)), quick());
    sum_entry += std::log10(f.worst.c / 3.0);
    sum_max += std::log10(f.worst.max_c / 3.0);
    pooled += f.worst.method == "pooled" ? 1 : 0;
  }
  const double entry = std::pow(10.0, sum_entry / kStudies) - 1, largest = std::pow(10.0, sum_max / kStudies) - 1;
  std::printf("entry c %+.2f %%, largest condition %+.2f %% against the planted 3.0 (%d/%d pooled)\n", 100 * entry, 100 * largest, pooled,
              kStudies);
  EXPECT_LT(std::abs(entry), 0.015);
  EXPECT_GT(largest, 0.02) << "the plain maximum is biased: the test must tell";
  EXPECT_GE(pooled, kStudies * 3 / 4);
}

// Issue 29: the thesis's own estimate (mean QUEST radius per size, a line through the origin)
// recovers a planted c from simulated QUEST runs.
TEST(StudyFit, TheThesisStyleEstimateRecoversAPlantedC) {
  for (double c_true : {2.0, 3.47}) {
    SimulatedStudy s = study_with(c_true, 515 + static_cast<std::uint64_t>(c_true * 10));
    const StudyFit f = fit_study(as_dataset(s, simulate_study(s)), quick());
    ASSERT_EQ(f.thesis.size(), 1u);
    EXPECT_EQ(f.thesis[0].staircases, 30);
    EXPECT_EQ(f.thesis[0].artifact_px, (std::vector<double>{5, 10, 20}));
    EXPECT_NEAR(f.thesis[0].c / c_true, 1.0, 0.08) << c_true;
  }
}

// Issue 44: every phase runs its fits on the threads (conditions, profile ends, bootstrap resamples,
// the worst case's fits, staircases), and nothing they compute depends on how many: report.json and
// calibration.json come out the same text with 1, 2 and 3 threads, for equal conditions and for a
// shrunken maximum over conditions that differ.
TEST(StudyFit, TheWholeFitIsIndependentOfTheThreadCount) {
  SimulatedStudy equal = four_equal_conditions(3.0, 5, 4401);
  SimulatedStudy differ = four_equal_conditions(3.0, 5, 4402);
  differ.conditions[1].planted.c_true = 6.0;
  std::set<std::string> methods;
  for (const SimulatedStudy& s : {equal, differ}) {
    const Dataset d = as_dataset(s, simulate_study(s));
    const CalibrationProvenance provenance = calibration_provenance(d);
    StudyFitOptions o = quick();
    o.bootstrap = 12;
    std::string report_1, calibration_1;
    for (int threads : {1, 2, 3}) {
      o.threads = threads;
      const StudyFit f = fit_study(d, o);
      const std::string report = report_json(f, nullptr, {"sim"}, "2024-01-01T00:00:00Z", provenance).dump();
      const std::string calibration = calibration_json(f, std::nullopt, "2024-01-01T00:00:00Z", {"sim"}, provenance).dump();
      if (threads == 1) {
        report_1 = report;
        calibration_1 = calibration;
        methods.insert(f.worst.method);
        EXPECT_EQ(f.worst.resamples, 12);
        continue;
      }
      EXPECT_EQ(report, report_1) << threads << " threads";
      EXPECT_EQ(calibration, calibration_1) << threads << " threads";
    }
  }
  EXPECT_TRUE(methods.count("shrunken maximum")) << "the conditions that differ are not pooled";
}

// Issue 44: each long phase reports its progress, in order, from 0 up to its total one at a time
// (the callback is called from worker threads, never two at once).
TEST(StudyFit, ReportsTheProgressOfEveryPhase) {
  const SimulatedStudy s = four_equal_conditions(3.0, 5, 4403);
  StudyFitOptions o = quick();
  o.bootstrap = 10;
  o.threads = 2;
  std::vector<std::pair<std::string, std::vector<int>>> phases;  // each phase's done values, in call order
  std::map<std::string, int> totals;
  std::atomic<int> inside{0};
  bool overlapped = false;
  o.progress = [&](const std::string& phase, int done, int total) {
    if (++inside > 1) overlapped = true;
    if (phases.empty() || phases.back().first != phase) phases.push_back({phase, {}});
    phases.back().second.push_back(done);
    EXPECT_TRUE(totals.emplace(phase, total).first->second == total) << phase << ": the total changed";
    --inside;
  };
  const StudyFit f = fit_study(as_dataset(s, simulate_study(s)), o);
  EXPECT_FALSE(overlapped);
  ASSERT_EQ(phases.size(), 3u);
  EXPECT_EQ(phases[0].first, "conditions");
  EXPECT_EQ(phases[1].first, "bootstrap");
  EXPECT_EQ(phases[2].first, "staircases");
  EXPECT_EQ(totals["conditions"], 4 * 4) << "four steps of four conditions";
  EXPECT_EQ(totals["bootstrap"], 5 * 10) << "four conditions' bootstraps and the worst case's";
  EXPECT_EQ(totals["staircases"], static_cast<int>(f.staircases.size()));
  EXPECT_EQ(f.staircases.size(), 5u * 4 * 3);
  for (const auto& [phase, done] : phases) {
    std::vector<int> expected(static_cast<std::size_t>(totals[phase]) + 1);
    std::iota(expected.begin(), expected.end(), 0);
    EXPECT_EQ(done, expected) << phase;
  }
}
