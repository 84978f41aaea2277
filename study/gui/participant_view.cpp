#include "gui/participant_view.h"

#include <epoxy/gl.h>
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <imgui.h>

#include <sstream>
#include <stdexcept>

#include "gui/gui_window.h"

namespace penumbra::study_gui {

namespace {

constexpr const char* kLeftArrow = "\xe2\x86\x90";   // U+2190
constexpr const char* kRightArrow = "\xe2\x86\x92";  // U+2192
constexpr int kQuestionGapPx = 48, kButtonGapPx = 36, kButtonHeightPx = 54, kMarginPx = 24;

float gray(int v) { return static_cast<float>(v) / 255.0f; }

// Text centred horizontally at ImGui y `y`.
void centred_text(const std::string& text, float y) {
  const float width = ImGui::GetIO().DisplaySize.x;
  std::istringstream lines(text);
  std::string line;
  while (std::getline(lines, line)) {
    const ImVec2 size = ImGui::CalcTextSize(line.c_str());
    ImGui::SetCursorPos({0.5f * (width - size.x), y});
    ImGui::TextUnformatted(line.c_str());
    y += ImGui::GetTextLineHeightWithSpacing();
  }
}

}  // namespace

StimulusLayout stimulus_layout(int framebuffer_width, int framebuffer_height, int size_px, int count) {
  if (count != 1 && count != 2) throw std::invalid_argument("stimulus_layout: 1 or 2 stimuli");
  StimulusLayout l;
  l.size_px = size_px;
  l.count = count;
  const int gap = size_px / 2;
  const int total_w = count * size_px + (count - 1) * gap;
  // Room above for the question and below for the buttons and the progress line.
  const int total_h = size_px + 2 * (kQuestionGapPx + kButtonGapPx + kButtonHeightPx + kMarginPx);
  if (total_w + 2 * kMarginPx > framebuffer_width || total_h > framebuffer_height)
    throw std::runtime_error("the participant screen (" + std::to_string(framebuffer_width) + "x" +
                             std::to_string(framebuffer_height) + " px) is too small for " + std::to_string(count) +
                             " stimuli of " + std::to_string(size_px) + " px with the question and buttons");
  l.x_px[0] = (framebuffer_width - total_w) / 2;
  l.x_px[1] = l.x_px[0] + size_px + gap;
  l.y_px = (framebuffer_height - size_px) / 2;
  return l;
}

Answer answer_for_key(int key) {
  if (key == GLFW_KEY_LEFT || key == GLFW_KEY_F) return Answer::first;
  if (key == GLFW_KEY_RIGHT || key == GLFW_KEY_J) return Answer::second;
  return Answer::none;
}

std::string response_for(Answer answer, const std::string& task) {
  if (answer == Answer::none) throw std::invalid_argument("response_for: no answer");
  if (task == "2afc") return answer == Answer::first ? "left" : "right";
  return answer == Answer::first ? "yes" : "no";
}

ParticipantView::ParticipantView(std::string task) : task_(std::move(task)) {
  ImGuiStyle& style = ImGui::GetStyle();
  style.FrameRounding = 6;
  style.FramePadding = {16, 10};
  style.WindowBorderSize = 0;
  ImVec4* c = style.Colors;
  c[ImGuiCol_Text] = {gray(236), gray(236), gray(236), 1};
  c[ImGuiCol_TextDisabled] = {gray(176), gray(176), gray(176), 1};
  c[ImGuiCol_Button] = {gray(96), gray(96), gray(96), 1};
  c[ImGuiCol_ButtonHovered] = {gray(108), gray(108), gray(108), 1};
  c[ImGuiCol_ButtonActive] = {gray(84), gray(84), gray(84), 1};
  c[ImGuiCol_Border] = {gray(150), gray(150), gray(150), 1};
}

void ParticipantView::set_stimuli(const std::vector<const io::Image8*>& images) {
  if (images.empty() || images.size() > 2) throw std::invalid_argument("ParticipantView: 1 or 2 stimuli");
  const int size = images[0]->width;
  if (size != size_px_) {
    for (int i = 0; i < 2; ++i) {
      textures_[i] = gl::Texture({GL_RGBA8, size, size, 1}, "participant stimulus");
      const gl::Framebuffer::Attachment a{&textures_[i], GL_COLOR_ATTACHMENT0};
      framebuffers_[i] = gl::Framebuffer({&a, 1}, "participant stimulus");
    }
    size_px_ = size;
  }
  std::vector<std::uint8_t> rgba(static_cast<std::size_t>(size) * size * 4);
  for (std::size_t i = 0; i < images.size(); ++i) {
    const io::Image8& img = *images[i];
    if (img.width != size || img.height != size || img.channels != 1)
      throw std::invalid_argument("ParticipantView: stimuli must be square one-channel images of the same size");
    // GL rows go bottom-up: flip here so the blit below copies without any transform.
    for (int y = 0; y < size; ++y)
      for (int x = 0; x < size; ++x) {
        const std::uint8_t v = img.at(x, size - 1 - y);
        std::uint8_t* p = &rgba[(static_cast<std::size_t>(y) * size + x) * 4];
        p[0] = p[1] = p[2] = v;
        p[3] = 255;
      }
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glTextureSubImage2D(textures_[i].id(), 0, 0, 0, size, size, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
  }
  count_ = static_cast<int>(images.size());
}

void ParticipantView::clear(GuiWindow& window) {
  int w = 0, h = 0;
  window.framebuffer_size(w, h);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  glDisable(GL_SCISSOR_TEST);
  glDisable(GL_FRAMEBUFFER_SRGB);
  glViewport(0, 0, w, h);
  glClearColor(gray(kBackgroundValue), gray(kBackgroundValue), gray(kBackgroundValue), 1);
  glClear(GL_COLOR_BUFFER_BIT);
}

void ParticipantView::begin_overlay(GuiWindow& window) {
  (void)window;
  ImGui::SetNextWindowPos({0, 0});
  ImGui::SetNextWindowSize(ImGui::GetIO().DisplaySize);
  ImGui::Begin("##participant", nullptr,
               ImGuiWindowFlags_NoDecoration | ImGuiWindowFlags_NoBackground | ImGuiWindowFlags_NoMove |
                   ImGuiWindowFlags_NoSavedSettings | ImGuiWindowFlags_NoBringToFrontOnFocus |
                   ImGuiWindowFlags_NoScrollWithMouse | ImGuiWindowFlags_NoFocusOnAppearing);
}

void ParticipantView::progress_line(GuiWindow& window, const std::string& progress) {
  ImGui::PushStyleColor(ImGuiCol_Text, ImGui::GetStyle().Colors[ImGuiCol_TextDisabled]);
  const float scale = window.framebuffer_scale();
  centred_text(progress, ImGui::GetIO().DisplaySize.y - (kMarginPx / scale) - ImGui::GetTextLineHeight());
  ImGui::PopStyleColor();
}

Answer ParticipantView::draw_trial(GuiWindow& window, const std::string& progress) {
  clear(window);
  int w = 0, h = 0;
  window.framebuffer_size(w, h);
  layout_ = stimulus_layout(w, h, size_px_, count_);
  for (int i = 0; i < count_; ++i) {
    // Same source and destination size: a pixel copy (GL_NEAREST only matters for scaling).
    const int x0 = layout_.x_px[i], y0 = h - layout_.y_px - size_px_;
    glBlitNamedFramebuffer(framebuffers_[i].id(), 0, 0, 0, size_px_, size_px_, x0, y0, x0 + size_px_, y0 + size_px_,
                           GL_COLOR_BUFFER_BIT, GL_NEAREST);
  }
  const float s = window.framebuffer_scale();
  begin_overlay(window);
  ImGui::PushFont(window.large_font() ? window.large_font() : window.body_font());
  const std::string question =
      task_ == "2afc" ? "Which shadow edge comes from a jagged original?" : "Was the original a straight line?";
  centred_text(question, (layout_.y_px - kQuestionGapPx) / s - ImGui::GetTextLineHeight());
  ImGui::PopFont();

  const std::string first = task_ == "2afc" ? std::string("Left   ") + kLeftArrow + " or F" : std::string("Yes   ") + kLeftArrow + " or F";
  const std::string second = task_ == "2afc" ? std::string("Right   ") + kRightArrow + " or J" : std::string("No   ") + kRightArrow + " or J";
  const float button_y = (layout_.y_px + size_px_ + kButtonGapPx) / s;
  const ImVec2 button_size{std::min(static_cast<float>(size_px_), 280.0f) / s, kButtonHeightPx / s};
  float x_first = 0, x_second = 0;
  if (count_ == 2) {
    x_first = (layout_.x_px[0] + 0.5f * size_px_) / s - 0.5f * button_size.x;
    x_second = (layout_.x_px[1] + 0.5f * size_px_) / s - 0.5f * button_size.x;
  } else {
    const float centre = (layout_.x_px[0] + 0.5f * size_px_) / s, gap = 24 / s;
    x_first = centre - gap / 2 - button_size.x;
    x_second = centre + gap / 2;
  }
  Answer clicked = Answer::none;
  ImGui::SetCursorPos({x_first, button_y});
  if (ImGui::Button(first.c_str(), button_size)) clicked = Answer::first;
  ImGui::SetCursorPos({x_second, button_y});
  if (ImGui::Button(second.c_str(), button_size)) clicked = Answer::second;
  progress_line(window, progress);
  ImGui::End();
  return clicked;
}

bool ParticipantView::draw_message(GuiWindow& window, const std::string& title, const std::string& body,
                                   const std::string& button, const std::string& progress) {
  clear(window);
  begin_overlay(window);
  const float height = ImGui::GetIO().DisplaySize.y;
  float y = 0.36f * height;
  ImGui::PushFont(window.large_font() ? window.large_font() : window.body_font());
  centred_text(title, y);
  y += 2.2f * ImGui::GetTextLineHeightWithSpacing();
  ImGui::PopFont();
  centred_text(body, y);
  std::size_t lines = 1;
  for (char ch : body) lines += ch == '\n';
  y += (static_cast<float>(lines) + 1.5f) * ImGui::GetTextLineHeightWithSpacing();
  bool clicked = false;
  if (!button.empty()) {
    const ImVec2 size{ImGui::CalcTextSize(button.c_str()).x + 64, kButtonHeightPx / window.framebuffer_scale()};
    ImGui::SetCursorPos({0.5f * (ImGui::GetIO().DisplaySize.x - size.x), y});
    clicked = ImGui::Button(button.c_str(), size);
  }
  progress_line(window, progress);
  ImGui::End();
  return clicked;
}

void ParticipantView::draw_blank(GuiWindow& window, const std::string& progress) {
  clear(window);
  begin_overlay(window);
  progress_line(window, progress);
  ImGui::End();
}

}  // namespace penumbra::study_gui
