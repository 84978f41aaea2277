#pragma once
// The experimenter's view: session facts, pause / end-round / quit controls, the current round's
// staircases (QUEST estimate +- sd, trial counts) and one convergence plot per staircase
// (trial -> filter radius shown, log scale, with the current estimate). Drawn into the current
// ImGui window: the admin window's whole area, or a panel in the participant window.
#include <string>

#include "procedure/session.h"

namespace penumbra::study_gui {

struct AdminStatus {
  std::string screen;       // what the participant sees now, e.g. "trial on screen"
  bool paused = false;
  std::string last_answer;  // e.g. "trial 12: right (correct), 532 ms"
  // Frame timing of the trials answered since the window opened (trials.csv's timing columns).
  std::string last_timing;  // e.g. "trial 12: 41 frames, mean 16.7 ms, max 17.9 ms"
  double dropped_frame_ms = 0;  // an interval over this is a dropped frame; 0: refresh rate unknown
  int timed_trials = 0;
  int trials_with_drops = 0;
  int dropped_frames = 0;
};

struct AdminActions {
  bool toggle_pause = false;
  bool end_round = false;  // confirmed
  bool quit = false;       // confirmed
};

AdminActions draw_admin(const procedure::Session& session, const AdminStatus& status);

// One staircase's convergence plot into the current window, `size` in ImGui units.
void staircase_plot(const procedure::Staircase& staircase, double max_radius_px, int max_trials, float width,
                    float height);

}  // namespace penumbra::study_gui
