// penumbra-fit plan checked against a brute-force simulation it shares no simulation code with
// (issue 48; label slow, about 90 s of CPU; 7 min wall on the shared 2-core machine, most of it the
// sessions' fsynced log writes). The planner simulates with analysis/data/simulate.h
// (its own QUEST loop, the planted observer of study/observers, the rows handed to the fitter in
// memory). Here each study is run the way penumbra-study runs one: procedure::Session (the study's
// procedure, its round and staircase draws, the crash-safe log and session.json on disk), answered
// by an observer written out below from the log-Weibull formula with its own random stream, and
// fitted from the files through the fitter's validating reader (load_dataset, the integrity replay)
// and fit_study, as penumbra-fit fits them. A detection is the conditions' LR test below alpha,
// what the planner counts. The two powers must agree within their Monte Carlo error: the
// difference of two binomial proportions, se = sqrt(p (1 - p) (1 / n1 + 1 / n2)) with the pooled
// p, at 2.58 se (99 %).
#include <gtest/gtest.h>

#include <unistd.h>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "data/dataset.h"
#include "fit/plan.h"
#include "fit/study_fit.h"
#include "procedure/config.h"
#include "procedure/session.h"

namespace {

using namespace penumbra;
using namespace penumbra::analysis;
namespace fs = std::filesystem;

// The planner's design (plan.h's defaults where not set): conditions stair/1 (the worst, planted
// c (1 + difference)) and step/1 (planted c), artifact sizes 5, 10, 20 px, a fixed number of
// trials per staircase, QUEST as the default study config has it.
struct Design {
  int participants = 6;
  int trials = 20;
  double c = 3.0, difference = 0.15, sd_log10 = 0.0;
  double beta = 3.5, lapse = 0.02;
  double alpha = 0.05;
};

procedure::StudyConfig config_of(const Design& d) {
  const nlohmann::json j = {
      {"name", "plan-check"},
      {"task", "2afc"},
      {"artifact_px", {5, 10, 20}},
      {"rounds", {{{"pattern", "stair"}, {"contrast", 1.0}}, {{"pattern", "step"}, {"contrast", 1.0}}}},
      {"quest", {{"t_guess", -0.5}, {"t_guess_sd", 1.0}, {"p_threshold", 0.82}, {"beta", 3.5}, {"delta", 0.01}, {"gamma", 0.5},
                 {"grain", 0.01}}},
      {"intensity_bounds", {-2.0, 1.0}},
      {"stopping", {{"min_trials", d.trials}, {"max_trials", d.trials}, {"sd_below", 0.0}}},
      {"practice_trials", 0},
      {"break_every_trials", 0},
      {"round_order", "shuffled"},
      {"stimulus", {{"size_px", 320}, {"kernel", "disk"}}}};
  return procedure::parse_config(j, "plan-check config");
}

// The planted 2AFC observer, written from the formula rather than taken from study/observers:
// psi(x) = 0.5 + (0.5 - lapse) F(x), F = 1 - exp(-10^(beta (x - alpha))), x = log10(a / r), and
// F reaches QUEST's criterion F* = (0.82 - 0.5) / (0.5 (1 - 0.01)) at x = -log10(c).
bool answers_correctly(double c, double beta, double lapse, double artifact_px, double radius_px, std::mt19937_64& random) {
  const double f_star = (0.82 - 0.5) / (0.5 * (1 - 0.01));
  const double alpha = -std::log10(c) - std::log10(-std::log(1 - f_star)) / beta;
  const double x = std::log10(artifact_px / radius_px);
  const double f = 1 - std::exp(-std::pow(10.0, beta * (x - alpha)));
  const double psi = 0.5 + (0.5 - lapse) * f;
  return std::uniform_real_distribution<double>(0, 1)(random) < psi;
}

// One brute-force study: sessions written under `dir`, read back and fitted. Returns the LR p.
double brute_force_study(const Design& d, const procedure::StudyConfig& config, std::uint64_t seed, const fs::path& dir) {
  std::mt19937_64 random(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<fs::path> sessions;
  fs::create_directories(dir);
  for (int p = 0; p < d.participants; ++p) {
    char name[16];
    std::snprintf(name, sizeof name, "p%02d", p + 1);
    const double spread = std::pow(10.0, normal(random) * d.sd_log10);
    const double c_of[2] = {d.c * (1 + d.difference) * spread, d.c * spread};  // stair/1, step/1
    const fs::path session_dir = dir / name;
    procedure::Session session = procedure::Session::create(
        config, session_dir, name,
        {{"observer", "psychometric:c=" + std::to_string(d.c)}, {"observer_kind", "psychometric-simulation"}, {"observer_seed", seed}},
        seed * 100 + static_cast<std::uint64_t>(p));
    while (const auto plan = session.next()) {
      const bool stair = session.condition(plan->round) == "stair/1";
      const bool correct = answers_correctly(stair ? c_of[0] : c_of[1], d.beta, d.lapse, plan->stimulus.artifact_px,
                                             plan->stimulus.filter_radius_px, random);
      session.record(*plan, correct == (plan->target == "left") ? "left" : "right", 0.0);
    }
    sessions.push_back(session_dir);
  }
  StudyFitOptions fo;
  fo.bootstrap = 0;
  fo.threads = 1;
  const StudyFit f = fit_study(load_dataset(sessions), fo);
  fs::remove_all(dir);
  return f.worst.lr_p;
}

struct Power {
  int detected = 0, studies = 0;
  double rate() const { return double(detected) / studies; }
};

Power brute_force_power(const Design& d, int studies, std::uint64_t seed, const fs::path& root) {
  const procedure::StudyConfig config = config_of(d);
  std::vector<double> p(static_cast<std::size_t>(studies), 1.0);
  std::atomic<int> next{0};
  std::string failure[2];
  auto worker = [&](int t) {
    try {
      for (int i = next++; i < studies; i = next++)
        p[static_cast<std::size_t>(i)] =
            brute_force_study(d, config, seed + static_cast<std::uint64_t>(i), root / ("study" + std::to_string(i)));
    } catch (const std::exception& e) {
      failure[t] = e.what();
      next = studies;
    }
  };
  std::thread other(worker, 1);
  worker(0);
  other.join();
  EXPECT_EQ(failure[0] + failure[1], "");
  Power out;
  out.studies = studies;
  for (double v : p) out.detected += v < d.alpha ? 1 : 0;
  return out;
}

Power planner_power(const Design& d, int studies) {
  PlanOptions o;
  o.participants = d.participants;
  o.trials_per_staircase = d.trials;
  o.conditions = 2;
  o.c = d.c;
  o.difference = d.difference;
  o.sd_log10 = d.sd_log10;
  o.beta = d.beta;
  o.lapse = d.lapse;
  o.alpha = d.alpha;
  o.studies = studies;
  o.seed = 7;
  o.threads = 2;
  const PlanResult r = plan_study(o);
  Power out;
  out.studies = studies;
  out.detected = static_cast<int>(std::lround(r.power * studies));
  return out;
}

// A difference whose power lies between 0.2 and 0.6 (15 % with 6 participants who differ by 0.08
// log10 and 20 trials per staircase: the planner says about 0.35), where a wrong planner would
// show most. PENUMBRA_PLAN_CHECK_STUDIES sets the studies per side (default 60: se of the
// difference about 0.085, so 2.58 se is about 0.22).
TEST(PlanCheck, ThePlannersPowerMatchesABruteForceSimulationWithinItsMonteCarloError) {
  const int studies =
      std::getenv("PENUMBRA_PLAN_CHECK_STUDIES") ? std::atoi(std::getenv("PENUMBRA_PLAN_CHECK_STUDIES")) : 60;
  const fs::path root = fs::temp_directory_path() / ("penumbra-plan-check-" + std::to_string(::getpid()));
  fs::remove_all(root);
  fs::create_directories(root);
  Design d;
  d.sd_log10 = 0.08;
  const Power planned = planner_power(d, studies);
  const Power brute = brute_force_power(d, studies, 5000, root);
  const double pooled = double(planned.detected + brute.detected) / (planned.studies + brute.studies);
  const double se = std::sqrt(pooled * (1 - pooled) * (1.0 / planned.studies + 1.0 / brute.studies));
  std::printf("difference %.0f %%, sd %.2f log10, %d participants x %d trials: planner %d/%d = %.3f, brute force %d/%d = %.3f, "
              "difference %+.3f, se %.3f\n",
              100 * d.difference, d.sd_log10, d.participants, d.trials, planned.detected, planned.studies, planned.rate(), brute.detected,
              brute.studies, brute.rate(), planned.rate() - brute.rate(), se);
  // Neither power near 0 or 1, where agreement would say little.
  EXPECT_GT(brute.rate(), 0.1);
  EXPECT_LT(brute.rate(), 0.9);
  EXPECT_LE(std::abs(planned.rate() - brute.rate()), 2.58 * se);
  fs::remove_all(root);
}

}  // namespace
