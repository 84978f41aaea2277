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

// A step of 1, 2 or 5 times a power of ten giving at most `max_ticks` ticks over `span`.
int tick_step(int span, int max_ticks) {
  for (int decade = 1;; decade *= 10)
    for (int m : {1, 2, 5})
      if (span / (m * decade) < max_ticks) return m * decade;
}

void staircase_plot(const procedure::Staircase& sc, double max_radius_px, int max_trials, float width, float height) {
  ImDrawList* dl = ImGui::GetWindowDrawList();
  const ImVec2 origin = ImGui::GetCursorScreenPos();
  const float line = ImGui::GetTextLineHeight();
  // Outside the frame: tick labels and the axis names; inside it a margin, so that points on the
  // range's ends (trial 1, the largest radius) are drawn whole.
  const float left = 44, bottom = 2 * line + 8, right = 10, top = line + 6, margin = 7;
  const ImVec2 p0{origin.x + left, origin.y + top}, p1{origin.x + width - right, origin.y + height - bottom};
  const ImVec2 d0{p0.x + margin, p0.y + margin}, d1{p1.x - margin, p1.y - margin};
  const double y_lo = 0.0, y_hi = std::log10(std::max(max_radius_px, 2.0));
  const int n_max = std::max({max_trials, static_cast<int>(sc.filter_radius_px.size()), 2});
  auto px = [&](int trial) { return d0.x + static_cast<float>(trial - 1) / static_cast<float>(n_max - 1) * (d1.x - d0.x); };
  auto py = [&](double radius) {
    const double t = (std::log10(std::clamp(radius, 1.0, max_radius_px)) - y_lo) / (y_hi - y_lo);
    return d1.y - static_cast<float>(t) * (d1.y - d0.y);
  };
  const ImU32 frame = IM_COL32(70, 74, 80, 255), grid = IM_COL32(52, 56, 62, 255), label = IM_COL32(170, 175, 182, 255);
  dl->AddRectFilled(p0, p1, IM_COL32(28, 30, 34, 255));
  for (double r : {1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0, 200.0, 500.0, 1000.0}) {
    if (r > max_radius_px * 1.001) break;
    const float y = py(r);
    dl->AddLine({p0.x, y}, {p1.x, y}, grid);
    const std::string t = format("%g", r);
    dl->AddText({p0.x - 6 - ImGui::CalcTextSize(t.c_str()).x, y - 0.5f * line}, label, t.c_str());
  }
  // Trial ticks: 1, then multiples of a 1-2-5 step, each label clear of the one before.
  const int step = tick_step(n_max - 1, 7);
  float last_label_end = -1e9f;
  for (int t = 1; t <= n_max; t = (t == 1 && step > 1) ? step : t + step) {
    const float x = px(t);
    const std::string s = format("%d", t);
    const float w = ImGui::CalcTextSize(s.c_str()).x;
    if (x - 0.5f * w < last_label_end + 6) continue;
    last_label_end = x + 0.5f * w;
    dl->AddLine({x, p0.y}, {x, p1.y}, grid);
    dl->AddLine({x, p1.y}, {x, p1.y + 4}, frame);
    dl->AddText({x - 0.5f * w, p1.y + 5}, label, s.c_str());
  }
  const char* x_name = "trial";
  dl->AddText({0.5f * (p0.x + p1.x) - 0.5f * ImGui::CalcTextSize(x_name).x, p1.y + 6 + line}, label, x_name);
  const char* y_name = "filter radius (px)";
  dl->AddText({origin.x, origin.y}, label, y_name);
  dl->AddRect(p0, p1, frame);

  // A value outside the plotted range: its value and a triangle pointing the way it lies, right-
  // aligned beside the edge it lies beyond (the line above the plot, or the axis-name line below
  // it), never over the data.
  float right_above = p1.x, right_below = p1.x;
  const float x_name_end = 0.5f * (p0.x + p1.x) + 0.5f * ImGui::CalcTextSize(x_name).x;
  auto beyond = [&](const char* what, double radius_px, ImU32 colour) {
    const bool above = radius_px > max_radius_px;
    float& free_end = above ? right_above : right_below;
    const float y = above ? origin.y : p1.y + 6 + line;
    const std::string t = format(radius_px < 10 ? "%s %.2g px" : "%s %.0f px", what, radius_px);
    const float tw = ImGui::CalcTextSize(t.c_str()).x;
    const float room_from = above ? origin.x + ImGui::CalcTextSize(y_name).x : x_name_end;
    if (free_end - tw - 14 < room_from + 8) return;  // a plot too narrow for it: the table has the value
    dl->AddText({free_end - tw, y}, colour, t.c_str());
    const float x = free_end - tw - 9, mid = y + 0.5f * line;
    if (above) dl->AddTriangleFilled({x - 5, mid + 4}, {x + 5, mid + 4}, {x, mid - 5}, colour);
    else dl->AddTriangleFilled({x - 5, mid - 4}, {x + 5, mid - 4}, {x, mid + 5}, colour);
    free_end -= tw + 26;
  };
  auto in_range = [&](double radius_px) { return radius_px >= 1.0 && radius_px <= max_radius_px; };
  // The current estimate with its +-1 sd band (clipped to the plot).
  if (!sc.filter_radius_px.empty()) {
    const double m = sc.quest.mean(), sd = sc.quest.sd();
    const ImU32 estimate = IM_COL32(90, 150, 230, 230);
    dl->AddRectFilled({p0.x, py(radius_at(sc.artifact_px, m - sd))}, {p1.x, py(radius_at(sc.artifact_px, m + sd))},
                      IM_COL32(90, 150, 230, 40));
    const double r_est = radius_at(sc.artifact_px, m);
    if (in_range(r_est)) dl->AddLine({p0.x, py(r_est)}, {p1.x, py(r_est)}, estimate, 1.5f);
    else beyond("estimate", r_est, estimate);
  }
  // The published rule r = c a (a faint dashed reference line).
  const ImU32 published = IM_COL32(200, 185, 100, 230);
  const double r_pub = kPublishedC * sc.artifact_px;
  if (in_range(r_pub)) {
    const float y_pub = py(r_pub);
    for (float x = p0.x; x < p1.x; x += 10) dl->AddLine({x, y_pub}, {std::min(x + 5, p1.x), y_pub}, published, 1.5f);
  } else {
    beyond("published", r_pub, published);
  }
  const int n = static_cast<int>(sc.filter_radius_px.size());
  for (int i = 1; i < n; ++i)
    dl->AddLine({px(i), py(sc.filter_radius_px[static_cast<std::size_t>(i - 1)])},
                {px(i + 1), py(sc.filter_radius_px[static_cast<std::size_t>(i)])}, IM_COL32(200, 200, 200, 140), 1.0f);
  for (int i = 0; i < n; ++i) {
    const ImVec2 c{px(i + 1), py(sc.filter_radius_px[static_cast<std::size_t>(i)])};
    if (sc.correct[static_cast<std::size_t>(i)]) dl->AddCircleFilled(c, 3.5f, IM_COL32(120, 210, 130, 255));
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

  const std::vector<int>& order = session.randomization().round_order;
  const int shown_round = round < n_rounds ? round : order.back();  // finished: the last one run
  const int shown_position = session.round_position(shown_round);
  if (round >= n_rounds)
    ImGui::TextColored({0.55f, 0.75f, 1.0f, 1.0f}, "Session finished: the plots show the last round run, round %d of %d (%s)",
                       shown_position + 1, n_rounds, session.condition(shown_round).c_str());
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
    ImGui::Text("%s, round %d of %d (%s)", sc.name.c_str(), shown_position + 1, n_rounds, session.condition(shown_round).c_str());
    staircase_plot(sc, max_radius, config.max_trials, w, h);
    ImGui::EndGroup();
  }
  ImGui::TextDisabled("filled: correct   open: wrong   blue: QUEST estimate +- sd   dashed: published r = %g a   "
                      "triangle: beyond the plotted range", kPublishedC);

  // The rounds run before the one shown, in the order they ran (numbered as the header numbers them).
  if (shown_position > 0 && ImGui::CollapsingHeader("Earlier rounds")) {
    for (int position = 0; position < shown_position; ++position) {
      const int r = order[static_cast<std::size_t>(position)];
      for (const auto& sc : session.rounds()[static_cast<std::size_t>(r)])
        ImGui::Text("round %d %-10s %-4s %3zu trials  %+.3f +- %.3f  r/a %.2f", position + 1, session.condition(r).c_str(),
                    sc.name.c_str(), sc.quest.trial_count(), sc.quest.mean(), sc.quest.sd(),
                    std::pow(10.0, -sc.quest.mean()));
    }
  }
  return actions;
}

}  // namespace penumbra::study_gui
