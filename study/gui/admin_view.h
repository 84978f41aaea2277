#pragma once
// The experimenter's view: session facts, pause / end-round / quit controls, the current round's
// staircases (QUEST estimate +- sd, trial counts) and one convergence plot per staircase
// (trial -> filter radius shown, log scale, with the current estimate). Drawn into the current
// ImGui window: the admin window's whole area, or a panel in the participant window.
#include <string>

#include "procedure/session.h"
#include "procedure/session_flow.h"

namespace penumbra::study_gui {

using AdminStatus = procedure::FlowStatus;

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
