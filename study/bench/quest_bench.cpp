// Cost of one QUEST trial's bookkeeping: update the posterior with a response, then place the
// next trial at the quantile. Table size is the argument (dim 500 = Psychtoolbox's default,
// 10,000 = range 100 at grain 0.01 as in PsychoPy's reference staircase).

#include <benchmark/benchmark.h>

#include "quest/quest.h"

namespace {

void BM_QuestUpdateQuantile(benchmark::State& state) {
  penumbra::quest::QuestParams params;
  params.t_guess = 0.0;
  params.t_guess_sd = 2.0;
  params.grain = 0.01;
  params.range = static_cast<double>(state.range(0)) * params.grain;
  penumbra::quest::Quest quest(params);
  double intensity = quest.quantile();
  int response = 1;
  for (auto _ : state) {
    quest.update(intensity, response);
    intensity = quest.quantile();
    benchmark::DoNotOptimize(intensity);
    response = 1 - response;  // alternate so the posterior stays broad and the placement moves
  }
  state.counters["dim"] = static_cast<double>(quest.dim());
}

}  // namespace

BENCHMARK(BM_QuestUpdateQuantile)->Arg(500)->Arg(10000)->Unit(benchmark::kMicrosecond);
BENCHMARK_MAIN();
