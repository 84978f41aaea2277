#include "gui/admin_view.h"

#include <imgui.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "published.h"

namespace penumbra::study_gui {

namespace {

std::string format(const char* f, auto... args) {
  char buf[256];
  std::snprintf(buf, sizeof buf, f, args...);
  return buf;
}

// Filter radius shown at threshold: r = a / 10^x.
double radius_at(double artifact_px, double intensity) { return artifact_px / std::pow(10.0, intensity); }

bool confirm(const char* id, const char* question) {
  bool yes = false;
  if (ImGui::BeginPopupModal(id, nullptr, ImGuiWindowFlags_AlwaysAutoResize)) {
    ImGui::TextUnformatted(question);
    if (ImGui::Button("Yes", {90, 0})) {
      yes = true;
      ImGui::CloseCurrentPopup();
    }
    ImGui::SameLine();
    if (ImGui::Button("Cancel", {90, 0})) ImGui::CloseCurrentPopup();
    ImGui::EndPopup();
  }
  return yes;
}

}  // namespace

void staircase_plot(const procedure::Staircase& sc, double max_radius_px, int max_trials, float width, float height) {
  ImDrawList* dl = ImGui::GetWindowDrawList();
  const ImVec2 origin = ImGui::GetCursorScreenPos();
  const float left = 44, bottom = 22, right = 8, top = 6;
  const ImVec2 p0{origin.x + left, origin.y + top}, p1{origin.x + width - right, origin.y + height - bottom};
  const double y_lo = 0.0, y_hi = std::log10(std::max(max_radius_px, 2.0));
  const int n_max = std::max({max_trials, static_cast<int>(sc.filter_radius_px.size()), 2});
  auto px = [&](double trial) { return p0.x + static_cast<float>(trial / (n_max - 1)) * (p1.x - p0.x); };
  auto py = [&](double radius) {
    const double t = (std::log10(std::clamp(radius, 1.0, max_radius_px)) - y_lo) / (y_hi - y_lo);
    return p1.y - static_cast<float>(t) * (p1.y - p0.y);
  };
  const ImU32 frame = IM_COL32(70, 74, 80, 255), grid = IM_COL32(58, 62, 68, 255), label = IM_COL32(170, 175, 182, 255);
  dl->AddRectFilled(p0, p1, IM_COL32(28, 30, 34, 255));
  for (double r : {1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0, 200.0, 500.0}) {
    if (r > max_radius_px * 1.001) break;
    const float y = py(r);
    dl->AddLine({p0.x, y}, {p1.x, y}, grid);
    const std::string t = format("%g", r);
    dl->AddText({p0.x - 6 - ImGui::CalcTextSize(t.c_str()).x, y - 0.5f * ImGui::GetTextLineHeight()}, label, t.c_str());
  }
  const int step = n_max > 30 ? 10 : 5;
  for (int t = 0; t < n_max; t += step) {
    const std::string s = format("%d", t + 1);
    dl->AddText({px(t) - 0.5f * ImGui::CalcTextSize(s.c_str()).x, p1.y + 3}, label, s.c_str());
  }
  dl->AddRect(p0, p1, frame);
  // The published rule r = c a (a faint reference line), and the current estimate with its +-1 sd band.
  const float y_pub = py(kPublishedC * sc.artifact_px);
  for (float x = p0.x; x < p1.x; x += 10)  // dashed
    dl->AddLine({x, y_pub}, {std::min(x + 5, p1.x), y_pub}, IM_COL32(200, 185, 100, 220), 1.5f);
  if (!sc.filter_radius_px.empty()) {
    const double m = sc.quest.mean(), sd = sc.quest.sd();
    const float y_est = py(radius_at(sc.artifact_px, m));
    dl->AddRectFilled({p0.x, py(radius_at(sc.artifact_px, m - sd))}, {p1.x, py(radius_at(sc.artifact_px, m + sd))},
                      IM_COL32(90, 150, 230, 40));
    dl->AddLine({p0.x, y_est}, {p1.x, y_est}, IM_COL32(90, 150, 230, 220), 1.5f);
  }
  const std::size_t n = sc.filter_radius_px.size();
  for (std::size_t i = 1; i < n; ++i)
    dl->AddLine({px(static_cast<double>(i - 1)), py(sc.filter_radius_px[i - 1])},
                {px(static_cast<double>(i)), py(sc.filter_radius_px[i])}, IM_COL32(200, 200, 200, 140), 1.0f);
  for (std::size_t i = 0; i < n; ++i) {
    const ImVec2 c{px(static_cast<double>(i)), py(sc.filter_radius_px[i])};
    if (sc.correct[i]) dl->AddCircleFilled(c, 3.5f, IM_COL32(120, 210, 130, 255));
    else dl->AddCircle(c, 3.5f, IM_COL32(235, 110, 100, 255), 0, 1.5f);
  }
  ImGui::Dummy({width, height});
}

AdminActions draw_admin(const procedure::Session& session, const AdminStatus& status) {
  AdminActions actions;
  const auto& config = session.config();
  const int round = session.current_round();
  const int n_rounds = static_cast<int>(session.rounds().size());

  ImGui::Text("Session %s   participant %s", session.session_id().c_str(),
              session.session_json().value("participant", std::string()).c_str());
  ImGui::TextDisabled("%s   task %s   seed %llu (%s)", session.dir().string().c_str(), config.task.c_str(),
                      static_cast<unsigned long long>(session.randomization().seed), session.randomization().seed_from.c_str());
  ImGui::Separator();
  if (round < n_rounds)
    ImGui::Text("Round %d of %d: %s    trials answered %d", session.round_position(round) + 1, n_rounds, session.condition(round).c_str(),
                session.trials_done());
  else
    ImGui::Text("All %d rounds finished    trials answered %d", n_rounds, session.trials_done());
  ImGui::Text("Participant sees: %s", status.screen.c_str());
  if (!status.last_answer.empty()) ImGui::TextDisabled("Last: %s", status.last_answer.c_str());
  if (status.trials_with_drops > 0)
    ImGui::TextColored({1.0f, 0.62f, 0.25f, 1.0f}, "Dropped frames: %d in %d of %d trials (intervals over %.1f ms)",
                       status.dropped_frames, status.trials_with_drops, status.timed_trials, status.dropped_frame_ms);
  else if (status.dropped_frame_ms <= 0)
    ImGui::TextColored({1.0f, 0.62f, 0.25f, 1.0f}, "Frame timing: refresh rate unknown, dropped frames not judged (--refresh-hz)");
  else if (status.timed_trials > 0)
    ImGui::TextDisabled("Frame timing: no dropped frames in %d trials", status.timed_trials);
  if (!status.last_timing.empty()) ImGui::TextDisabled("Last stimulus: %s", status.last_timing.c_str());

  if (ImGui::Button(status.paused ? "Resume" : "Pause")) actions.toggle_pause = true;
  ImGui::SameLine();
  ImGui::BeginDisabled(round >= n_rounds);
  if (ImGui::Button("End round")) ImGui::OpenPopup("End round?");
  ImGui::EndDisabled();
  ImGui::SameLine();
  if (ImGui::Button("Save and quit")) ImGui::OpenPopup("Quit?");
  actions.end_round = confirm("End round?", "End this round now? Its staircases keep their current estimates.");
  actions.quit = confirm("Quit?", "Stop the session? Every answered trial is saved; --resume continues it.");
  ImGui::Separator();

  const int shown_round = round < n_rounds ? round : session.randomization().round_order.back();  // finished: the last run
  const auto& staircases = session.rounds()[static_cast<std::size_t>(shown_round)];
  const double max_radius = 0.5 * config.stimulus_size_px;
  if (ImGui::BeginTable("staircases", 6, ImGuiTableFlags_RowBg | ImGuiTableFlags_BordersInnerH)) {
    for (const char* h : {"staircase", "artifact", "trials", "QUEST log10(a/r)", "threshold r", "state"})
      ImGui::TableSetupColumn(h);
    ImGui::TableHeadersRow();
    for (const auto& sc : staircases) {
      ImGui::TableNextRow();
      ImGui::TableNextColumn();
      ImGui::TextUnformatted(sc.name.c_str());
      ImGui::TableNextColumn();
      ImGui::Text("%g px (%.1f')", sc.artifact_px, config.display.arcmin(sc.artifact_px));
      ImGui::TableNextColumn();
      ImGui::Text("%zu / %d", sc.quest.trial_count(), config.max_trials);
      ImGui::TableNextColumn();
      ImGui::Text("%+.3f +- %.3f", sc.quest.mean(), sc.quest.sd());
      ImGui::TableNextColumn();
      const double r = radius_at(sc.artifact_px, sc.quest.mean());
      ImGui::Text("%.1f px  (r/a %.2f)", r, r / sc.artifact_px);
      ImGui::TableNextColumn();
      ImGui::TextUnformatted(sc.done ? "done" : sc.quest.trial_count() == 0 ? "not started" : "running");
    }
    ImGui::EndTable();
  }
  ImGui::Spacing();
  const int per_row = std::min<int>(3, static_cast<int>(staircases.size()));
  const float avail = ImGui::GetContentRegionAvail().x;
  const float spacing = ImGui::GetStyle().ItemSpacing.x;
  const float w = (avail - spacing * static_cast<float>(per_row - 1)) / static_cast<float>(per_row);
  // The plots take the height left, less the legend and the earlier-rounds header below them.
  const int plot_rows = (static_cast<int>(staircases.size()) + per_row - 1) / per_row;
  const float line = ImGui::GetFrameHeightWithSpacing();
  const float h = std::clamp((ImGui::GetContentRegionAvail().y - 2.5f * line) / static_cast<float>(plot_rows) - line,
                             150.0f, 420.0f);
  for (std::size_t i = 0; i < staircases.size(); ++i) {
    const auto& sc = staircases[i];
    if (i % static_cast<std::size_t>(per_row) != 0) ImGui::SameLine();
    ImGui::BeginGroup();
    ImGui::Text("%s: filter radius (px) per trial", sc.name.c_str());
    staircase_plot(sc, max_radius, config.max_trials, w, h);
    ImGui::EndGroup();
  }
  ImGui::TextDisabled("filled: correct   open: wrong   blue: QUEST estimate +- sd   dashed: published r = %g a", kPublishedC);

  if (shown_round > 0 && ImGui::CollapsingHeader("Earlier rounds")) {
    for (int r = 0; r < shown_round; ++r)
      for (const auto& sc : session.rounds()[static_cast<std::size_t>(r)])
        ImGui::Text("round %d %-10s %-4s %3zu trials  %+.3f +- %.3f  r/a %.2f", r + 1, session.condition(r).c_str(),
                    sc.name.c_str(), sc.quest.trial_count(), sc.quest.mean(), sc.quest.sd(),
                    std::pow(10.0, -sc.quest.mean()));
  }
  return actions;
}

}  // namespace penumbra::study_gui
