// penumbra-fit-bench: the joint linear fit of a simulated study of 5,000 trials, and 1,000
// bootstrap resamples over its participants (run with --benchmark_min_time or as is).
#include <benchmark/benchmark.h>

#include <map>
#include <string>
#include <thread>

#include "data/dataset.h"
#include "data/simulate.h"
#include "fit/study_fit.h"
#include "published.h"

namespace {

using namespace penumbra::analysis;

// 25 participants x 5 sizes x 40 trials = 5,000 trials, planted c = the published c.
struct Study {
  ModelSpec spec;
  std::vector<std::vector<Group>> participants;
};

const Study& study() {
  static const Study s = [] {
    SimulatedStudy sim;
    sim.participants = 25;
    sim.artifact_px = {2, 5, 10, 15, 20};
    sim.conditions[0].planted.c_true = penumbra::kPublishedC;
    sim.conditions[0].planted.lapse = 0.02;
    sim.seed = 5000;
    Study out;
    for (const SimulatedSession& session : simulate_study(sim)) {
      std::map<double, Group> by_size;
      for (const auto& row : session.rows) by_size[row.artifact_px].rows.push_back({row.intensity, double(row.correct), 1});
      std::vector<Group> groups;
      for (auto& [a, g] : by_size) {
        groups.push_back(g);
        out.spec.groups.push_back(g);
      }
      out.participants.push_back(groups);
    }
    return out;
  }();
  return s;
}

void JointFit5000Trials(benchmark::State& state) {
  const Study& s = study();
  for (auto _ : state) {
    const FitResult f = fit(s.spec);
    benchmark::DoNotOptimize(f.params.u[0]);
  }
  state.counters["trials"] = fit(s.spec).trials;
}
BENCHMARK(JointFit5000Trials)->Unit(benchmark::kMillisecond);

void Bootstrap1000(benchmark::State& state) {
  const Study& s = study();
  const FitResult best = fit(s.spec);
  ModelSpec base = s.spec;
  base.u_min = best.u_min;
  base.u_max = best.u_max;
  for (auto _ : state) {
    const BootstrapSummary b =
        bootstrap_participants(base, s.participants, best.params, 1000, 1, static_cast<int>(state.range(0)), 0.95);
    benchmark::DoNotOptimize(b.c.lo);
  }
  state.counters["threads"] = static_cast<double>(state.range(0));
}
BENCHMARK(Bootstrap1000)->Arg(1)->Arg(2)->Unit(benchmark::kSecond)->Iterations(1)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
