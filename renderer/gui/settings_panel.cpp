#include "gui/settings_panel.h"

#include <functional>
#include <stdexcept>
#include <string>

#include <imgui.h>

#include "shadows/frame_plan.h"

namespace penumbra::gui {

template <class P>
bool settings_panel(const char* id, P& params) {
  bool changed = false;
  ImGui::PushID(id);
  for (const auto& row : shadows::settings_table(&params)) {
    const std::string label(row.key);
    const double value = row.get(params);
    switch (row.type) {
      case shadows::SettingType::boolean: {
        bool v = value != 0.0;
        if (ImGui::Checkbox(label.c_str(), &v)) row.set(params, v ? 1 : 0), changed = true;
        break;
      }
      case shadows::SettingType::choice: {
        int v = static_cast<int>(value);
        const std::string current(row.choices[static_cast<std::size_t>(v)]);
        if (ImGui::BeginCombo(label.c_str(), current.c_str())) {
          for (std::size_t i = 0; i < row.choices.size(); ++i) {
            const std::string name(row.choices[i]);
            if (ImGui::Selectable(name.c_str(), static_cast<int>(i) == v)) row.set(params, static_cast<double>(i)), changed = true;
          }
          ImGui::EndCombo();
        }
        break;
      }
      case shadows::SettingType::integer: {
        int v = static_cast<int>(value);
        if (ImGui::DragInt(label.c_str(), &v, 1.0f, static_cast<int>(row.min), static_cast<int>(row.max), "%d", ImGuiSliderFlags_AlwaysClamp))
          row.set(params, v), changed = true;
        break;
      }
      case shadows::SettingType::real: {
        float v = static_cast<float>(value);
        const float speed = std::max(0.001f, std::abs(v) * 0.01f);
        if (ImGui::DragFloat(label.c_str(), &v, speed, static_cast<float>(row.min), static_cast<float>(row.max), "%.4g",
                             ImGuiSliderFlags_AlwaysClamp)) {
          // A row that is 0 or at least min_positive (adaptive.visibility) refuses what lies between:
          // a drag up from 0 lands on min_positive, a drag down below it on 0.
          if (row.min_positive > 0 && v > 0 && v < row.min_positive) v = v > value ? static_cast<float>(row.min_positive) : 0.0f;
          row.set(params, v), changed = true;
        }
        break;
      }
    }
    if (ImGui::IsItemHovered()) {
      const std::string tip = std::string(row.help) + (row.unit.empty() ? "" : " [" + std::string(row.unit) + "]");
      ImGui::SetTooltip("%s", tip.c_str());
    }
  }
  ImGui::PopID();
  return changed;
}

template bool settings_panel<shadows::ShadowMapParams>(const char*, shadows::ShadowMapParams&);
template bool settings_panel<shadows::AdaptiveParams>(const char*, shadows::AdaptiveParams&);
#define PENUMBRA_INSTANTIATE_PANEL(name, P) template bool settings_panel<shadows::P>(const char*, shadows::P&);
PENUMBRA_TECHNIQUES(PENUMBRA_INSTANTIATE_PANEL)
#undef PENUMBRA_INSTANTIATE_PANEL

std::string SettingsUndo::render(shadows::ShadowSettings& settings, const std::function<void(shadows::ShadowSettings&)>& draw) {
  if (!last_good_) last_good_ = settings;
  try {
    draw(settings);
    last_good_ = settings;
    return "";
  } catch (const std::runtime_error& e) {  // PoolTooSmall, a visibility's c out of range (CLI::ValidationError)
    refused_ = e.what();
  } catch (const std::invalid_argument& e) {
    refused_ = e.what();
  }
  settings = *last_good_;
  draw(settings);  // what drew last frame; its own failure ends the app as before
  return refused_;
}

void SettingsUndo::line() const {
  if (!refused_.empty()) ImGui::TextColored({1.0f, 0.45f, 0.35f, 1.0f}, "undone: %s", refused_.c_str());
}

bool shadow_settings_panel(shadows::ShadowSettings& s) {
  bool changed = false;
  int t = static_cast<int>(s.technique);
  const auto names = shadows::technique_names();
  const std::string current(names[static_cast<std::size_t>(t)]);
  if (ImGui::BeginCombo("technique", current.c_str())) {
    for (std::size_t i = 0; i < names.size(); ++i) {
      const std::string name(names[i]);
      if (ImGui::Selectable(name.c_str(), static_cast<int>(i) == t)) s.technique = static_cast<shadows::Technique>(i), changed = true;
    }
    ImGui::EndCombo();
  }
  shadows::visit_technique_section(s, [&](std::string_view section, auto& params) {
    changed |= settings_panel(std::string(section).c_str(), params);
  });
  if (ImGui::CollapsingHeader("shadow map and bias", ImGuiTreeNodeFlags_DefaultOpen)) changed |= settings_panel("map", s.map);
  if (ImGui::CollapsingHeader("adaptive resolution")) changed |= settings_panel("adaptive", s.adaptive);
  return changed;
}

shadows::ShadowSettings drawable_settings(const shadows::ShadowSettings& settings, const scene::Scene& scene) {
  shadows::ShadowSettings s = settings;
  if (s.map.virtual_pages != shadows::VirtualPages::off && !shadows::virtual_pages_refusal(s, scene).empty())
    s.map.virtual_pages = shadows::VirtualPages::off;
  return s;
}

void virtual_pages_line(const shadows::ShadowSettings& settings, const scene::Scene& scene, const shadows::FrameInfo& info) {
  if (settings.map.virtual_pages == shadows::VirtualPages::off) return;
  if (const std::string why = shadows::virtual_pages_refusal(settings, scene); !why.empty()) {
    ImGui::TextWrapped("virtual pages: %s; drawing maps", why.c_str());
  } else if (info.virtual_map) {
    const auto& v = *info.virtual_map;
    ImGui::Text("virtual pages: %d marked, %d drawn, %d resident (%.1f MB)", v.pages.requested, v.pages.drawn, v.pages.resident,
                static_cast<double>(v.resident_bytes + v.table_bytes) / (1 << 20));
    if (v.coarser + v.none > 0)
      ImGui::Text("pool full: %llu pixels on a coarser level, %llu without a page", static_cast<unsigned long long>(v.coarser),
                  static_cast<unsigned long long>(v.none));
  }
}

bool light_size_control(scene::Light& light) {
  return ImGui::DragFloat(light.type == scene::Light::Type::spot ? "light width [world]" : "light angle [deg]", &light.size,
                          0.02f, 0.0f, 45.0f);
}

}  // namespace penumbra::gui
