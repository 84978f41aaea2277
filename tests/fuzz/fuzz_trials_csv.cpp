// Trial logs through trial_log::read and the fitter's loader with its integrity check
// (analysis::load_dataset: numbering, the procedure replayed from the fixed session.json of a real
// session, fixtures/session.json), as penumbra-fit and --resume read them.
#include "data/dataset.h"
#include "fuzz_target.h"
#include "log/trial_log.h"

PENUMBRA_FUZZ_TARGET(trials_csv) {
  static const std::filesystem::path dir = [] {
    const std::filesystem::path d = penumbra::fuzz::scratch() / "trials_csv";
    std::filesystem::create_directories(d);
    std::filesystem::copy_file(PENUMBRA_FUZZ_DIR "/fixtures/session.json", d / "session.json",
                               std::filesystem::copy_options::overwrite_existing);
    return d;
  }();
  penumbra::fuzz::write(dir / "trials.csv", input);
  penumbra::fuzz::expect_refusal_or_success([&] { penumbra::trial_log::read(dir / "trials.csv"); });
  penumbra::fuzz::expect_refusal_or_success([&] { penumbra::analysis::load_dataset({dir}); });
}
