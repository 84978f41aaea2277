// session.json as --resume checks it (json_input::read_file with resume's bounds, then
// procedure::check_session_json and the log replayed against it) and as penumbra-fit reads it
// (analysis::load_dataset), beside a fixed log of a real session (fixtures/trials.csv).
#include "data/dataset.h"
#include "fuzz_target.h"
#include "json/json_input.h"
#include "procedure/session_record.h"

PENUMBRA_FUZZ_TARGET(session_json) {
  static const std::filesystem::path dir = [] {
    const std::filesystem::path d = penumbra::fuzz::scratch() / "session_json";
    std::filesystem::create_directories(d);
    std::filesystem::copy_file(PENUMBRA_FUZZ_DIR "/fixtures/trials.csv", d / "trials.csv",
                               std::filesystem::copy_options::overwrite_existing);
    return d;
  }();
  penumbra::fuzz::write(dir / "session.json", input);
  penumbra::fuzz::expect_refusal_or_success([&] {
    const nlohmann::json j = penumbra::json_input::read_file(dir / "session.json", {.max_bytes = 1 << 20, .max_depth = 8});
    const auto record = penumbra::procedure::check_session_json(j, "session.json");
    penumbra::procedure::replay_log(record, penumbra::trial_log::read(dir / "trials.csv").rows, "trials.csv");
  });
  penumbra::fuzz::expect_refusal_or_success([&] { penumbra::analysis::load_dataset({dir}, {.accept_inconsistent = true}); });
}
