// penumbra-fit psychometric's input through analysis::read_level_data, in both formats (counts:
// level,n_correct,n_total; trials: level,correct).
#include "data/level_data.h"
#include "fuzz_target.h"

PENUMBRA_FUZZ_TARGET(counts_csv) {
  const std::filesystem::path path = penumbra::fuzz::scratch() / "data.csv";
  penumbra::fuzz::write(path, input);
  for (const auto format : {penumbra::analysis::LevelFormat::counts, penumbra::analysis::LevelFormat::trials})
    penumbra::fuzz::expect_refusal_or_success([&] { penumbra::analysis::read_level_data(path, format); });
}
