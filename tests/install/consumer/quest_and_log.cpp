// Penumbra::psychometrics and Penumbra::study_log from the installed package: a QUEST staircase,
// and a trial log written and read back. Exit 0 when the numbers hold (tests/install).
//   quest_and_log DIR
#include <penumbra/log/trial_log.h>
#include <penumbra/quest/quest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>

using namespace penumbra;

int main(int argc, char** argv) {
  if (argc != 2) return 2;
  quest::QuestParams params;
  params.t_guess = -0.5;
  params.t_guess_sd = 0.5;
  quest::Quest q(params);
  q.update(-0.5, 1);
  q.update(-0.7, 0);
  if (q.trial_count() != 2 || !std::isfinite(q.mean()) || !(q.sd() < 0.5)) {
    std::fprintf(stderr, "quest_and_log: QUEST after 2 trials: mean %g, sd %g\n", q.mean(), q.sd());
    return 1;
  }

  const std::filesystem::path log = std::filesystem::path(argv[1]) / "trials.csv";
  std::filesystem::remove(log);
  {
    trial_log::Writer writer(log, /*create=*/true);
    for (int i = 0; i < 2; ++i) {
      trial_log::TrialRow row;
      row.session_id = "s";
      row.participant = "p01";
      row.utc_time = "2024-01-01T00:00:00Z";
      row.round_position = 1;
      row.trial = i;
      row.staircase = "a10";
      row.pattern = "step";
      row.artifact_px = 10;
      row.task = "2afc";
      row.intensity = q.intensities()[i];
      row.filter_radius_px = 10 / std::pow(10.0, row.intensity);
      row.kernel = "grid";
      row.target = "left";
      row.response = q.responses()[i] ? "left" : "right";
      row.correct = q.responses()[i];
      row.requested_filter_radius_px = row.filter_radius_px;
      writer.append(row);
    }
  }
  const trial_log::ReadResult read = trial_log::read(log);
  if (read.rows.size() != 2 || read.rows[1].correct != 0 || read.rows[0].intensity != -0.5) {
    std::fprintf(stderr, "quest_and_log: %s read back %zu rows\n", log.c_str(), read.rows.size());
    return 1;
  }
  std::printf("QUEST mean %.3f sd %.3f after 2 trials; %zu rows logged and read back\n", q.mean(), q.sd(), read.rows.size());
  return 0;
}
