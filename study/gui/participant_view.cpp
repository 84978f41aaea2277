#include "gui/participant_view.h"

#include <epoxy/gl.h>
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <imgui.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <sstream>
#include <stdexcept>

#include "gl/window.h"

namespace penumbra::study_gui {

namespace {

constexpr int kQuestionGapPx = 48, kButtonGapPx = 36, kButtonHeightPx = 54, kMarginPx = 24;

float gray(int v) { return static_cast<float>(v) / 255.0f; }

// The lines of `text` in the current font, each broken at spaces to fit `max_width` (a texts entry
// from a config, in any language, must not run off the screen).
std::vector<std::string> wrapped(const std::string& text, float max_width) {
  std::vector<std::string> out;
  std::istringstream lines(text);
  std::string line;
  while (std::getline(lines, line)) {
    std::string current;
    std::size_t pos = 0;
    while (pos <= line.size()) {
      std::size_t end = line.find(' ', pos);
      if (end == std::string::npos) end = line.size();
      const std::string word = line.substr(pos, end - pos);
      const std::string candidate = current.empty() ? word : current + " " + word;
      if (!current.empty() && ImGui::CalcTextSize(candidate.c_str()).x > max_width) {
        out.push_back(current);
        current = word;
      } else {
        current = candidate;
      }
      pos = end + 1;
    }
    out.push_back(current);
  }
  return out;
}

float text_width_limit() { return 0.9f * ImGui::GetIO().DisplaySize.x; }

// Lines centred horizontally from ImGui y `y`; returns the y below them.
float centred_lines(const std::vector<std::string>& lines, float y) {
  const float width = ImGui::GetIO().DisplaySize.x;
  for (const std::string& line : lines) {
    const ImVec2 size = ImGui::CalcTextSize(line.c_str());
    ImGui::SetCursorPos({std::floor(0.5f * (width - size.x)), y});
    ImGui::TextUnformatted(line.c_str());
    y += ImGui::GetTextLineHeightWithSpacing();
  }
  return y;
}

// Text centred horizontally at ImGui y `y`, wrapped to the screen.
float centred_text(const std::string& text, float y) { return centred_lines(wrapped(text, text_width_limit()), y); }

// A grey (or RGB: a frame study's patches) image into an RGBA8 texture, rows flipped (GL rows go
// bottom-up), so a blit or a quad with flipped v copies it without any other transform.
void upload_grey(const gl::Texture& texture, const io::Image8& img) {
  const int size = img.width;
  std::vector<std::uint8_t> rgba(static_cast<std::size_t>(size) * size * 4);
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      std::uint8_t* p = &rgba[(static_cast<std::size_t>(y) * size + x) * 4];
      for (int c = 0; c < 3; ++c) p[c] = img.at(x, size - 1 - y, img.channels >= 3 ? c : 0);
      p[3] = 255;
    }
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glTextureSubImage2D(texture.id(), 0, 0, 0, size, size, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
}

void check_square(const io::Image8& img, int size) {
  if (img.width != size || img.height != size || (img.channels != 1 && img.channels != 3))
    throw std::invalid_argument("ParticipantView: stimuli must be square grey or RGB images of the same size");
}

// A button of at least `min_width` centred on x, at y; true when clicked.
bool button_at(const std::string& label, float centre_x, float y, float min_width, float height) {
  const ImVec2 size{std::max(min_width, ImGui::CalcTextSize(label.c_str()).x + 64), height};
  ImGui::SetCursorPos({std::floor(centre_x - 0.5f * size.x), y});
  return ImGui::Button(label.c_str(), size);
}

}  // namespace

StimulusLayout stimulus_layout(int framebuffer_width, int framebuffer_height, int size_px, int count, bool sample) {
  if (count != 1 && count != 2) throw std::invalid_argument("stimulus_layout: 1 or 2 stimuli");
  StimulusLayout l;
  l.size_px = size_px;
  l.count = count;
  l.sample = sample;
  const int gap = size_px / 2;
  const int total_w = count * size_px + (count - 1) * gap;
  // Room above for the question and below for the buttons and the progress line (and the sample's row).
  const int rows_h = sample ? 2 * size_px + gap : size_px;
  const int total_h = rows_h + 2 * (kQuestionGapPx + kButtonGapPx + kButtonHeightPx + kMarginPx);
  if (total_w + 2 * kMarginPx > framebuffer_width || total_h > framebuffer_height)
    throw std::runtime_error("the participant screen (" + std::to_string(framebuffer_width) + "x" +
                             std::to_string(framebuffer_height) + " px) is too small for " + std::to_string(count) +
                             " stimuli of " + std::to_string(size_px) + " px with the question and buttons");
  l.x_px[0] = (framebuffer_width - total_w) / 2;
  l.x_px[1] = l.x_px[0] + size_px + gap;
  l.y_px = (framebuffer_height - rows_h) / 2 + (sample ? size_px + gap : 0);
  l.sample_x_px = (framebuffer_width - size_px) / 2;
  l.sample_y_px = l.y_px - size_px - gap;
  return l;
}

Answer answer_for_key(int key) {
  if (key == GLFW_KEY_LEFT || key == GLFW_KEY_F) return Answer::first;
  if (key == GLFW_KEY_RIGHT || key == GLFW_KEY_J) return Answer::second;
  return Answer::none;
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

void ParticipantView::set_stimuli(const std::vector<const io::Image8*>& images, const io::Image8* sample) {
  if (images.empty() || images.size() > 2) throw std::invalid_argument("ParticipantView: 1 or 2 stimuli");
  const int size = images[0]->width;
  if (size != size_px_) {
    for (int i = 0; i < 3; ++i) {
      textures_[i] = gl::Texture({GL_RGBA8, size, size, 1}, "participant stimulus");
      const gl::Framebuffer::Attachment a{&textures_[i], GL_COLOR_ATTACHMENT0};
      framebuffers_[i] = gl::Framebuffer({&a, 1}, "participant stimulus");
    }
    size_px_ = size;
  }
  for (std::size_t i = 0; i < images.size(); ++i) {
    check_square(*images[i], size);
    upload_grey(textures_[i], *images[i]);
  }
  count_ = static_cast<int>(images.size());
  sample_ = sample != nullptr;
  if (sample) {
    check_square(*sample, size);
    upload_grey(textures_[2], *sample);
  }
}

void ParticipantView::set_examples(const io::Image8& jagged, const io::Image8& straight) {
  const int size = jagged.width;
  check_square(jagged, size);
  check_square(straight, size);
  if (size != example_px_) {
    for (auto& t : examples_) {
      t = gl::Texture({GL_RGBA8, size, size, 1}, "instruction example");
      // Drawn by ImGui, shrunk when the screen is small: nearest keeps the steps sharp.
      glTextureParameteri(t.id(), GL_TEXTURE_MIN_FILTER, GL_NEAREST);
      glTextureParameteri(t.id(), GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    }
    example_px_ = size;
  }
  upload_grey(examples_[0], jagged);
  upload_grey(examples_[1], straight);
}

void ParticipantView::clear(gl::Window& window) {
  int w = 0, h = 0;
  window.framebuffer_size(w, h);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  glDisable(GL_SCISSOR_TEST);
  glDisable(GL_FRAMEBUFFER_SRGB);
  glViewport(0, 0, w, h);
  glClearColor(gray(kBackgroundValue), gray(kBackgroundValue), gray(kBackgroundValue), 1);
  glClear(GL_COLOR_BUFFER_BIT);
}

void ParticipantView::begin_overlay(gl::Window& window) {
  (void)window;
  ImGui::SetNextWindowPos({0, 0});
  ImGui::SetNextWindowSize(ImGui::GetIO().DisplaySize);
  ImGui::Begin("##participant", nullptr,
               ImGuiWindowFlags_NoDecoration | ImGuiWindowFlags_NoBackground | ImGuiWindowFlags_NoMove |
                   ImGuiWindowFlags_NoSavedSettings | ImGuiWindowFlags_NoBringToFrontOnFocus |
                   ImGuiWindowFlags_NoScrollWithMouse | ImGuiWindowFlags_NoFocusOnAppearing);
}

void ParticipantView::progress_line(gl::Window& window, const std::string& progress) {
  ImGui::PushStyleColor(ImGuiCol_Text, ImGui::GetStyle().Colors[ImGuiCol_TextDisabled]);
  const float scale = window.framebuffer_scale();
  centred_text(progress, ImGui::GetIO().DisplaySize.y - (kMarginPx / scale) - ImGui::GetTextLineHeight());
  ImGui::PopStyleColor();
}

Answer ParticipantView::draw_trial(gl::Window& window, const TrialText& text, const std::string& progress) {
  clear(window);
  int w = 0, h = 0;
  window.framebuffer_size(w, h);
  layout_ = stimulus_layout(w, h, size_px_, count_, sample_);
  for (int i = 0; i < count_ + (sample_ ? 1 : 0); ++i) {
    // Same source and destination size: a pixel copy (GL_NEAREST only matters for scaling).
    const bool above = i == count_;  // the sample
    const int x0 = above ? layout_.sample_x_px : layout_.x_px[i], y0 = h - (above ? layout_.sample_y_px : layout_.y_px) - size_px_;
    glBlitNamedFramebuffer(framebuffers_[above ? 2 : i].id(), 0, 0, 0, size_px_, size_px_, x0, y0, x0 + size_px_, y0 + size_px_,
                           GL_COLOR_BUFFER_BIT, GL_NEAREST);
  }
  const float s = window.framebuffer_scale();
  begin_overlay(window);
  ImGui::PushFont(window.large_font() ? window.large_font() : window.body_font());
  const bool feedback = !text.feedback.empty();
  if (feedback)
    ImGui::PushStyleColor(ImGuiCol_Text, text.feedback_correct ? ImVec4{0.55f, 0.90f, 0.55f, 1} : ImVec4{1.0f, 0.62f, 0.55f, 1});
  const auto question = wrapped(feedback ? text.feedback : text.question, text_width_limit());
  centred_lines(question, (layout_.top_px() - kQuestionGapPx) / s - ImGui::GetTextLineHeight() -
                              static_cast<float>(question.size() - 1) * ImGui::GetTextLineHeightWithSpacing());
  if (feedback) ImGui::PopStyleColor();
  ImGui::PopFont();
  if (feedback) {  // no answer to give: the stimuli stay for a look, the buttons go
    progress_line(window, progress);
    ImGui::End();
    return Answer::none;
  }

  const std::string& first = text.first;  // the keys are named in the config's texts (translated with the words)
  const std::string& second = text.second;
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

bool ParticipantView::draw_message(gl::Window& window, const std::string& title, const std::string& body,
                                   const std::string& button, const std::string& progress) {
  clear(window);
  begin_overlay(window);
  const float height = ImGui::GetIO().DisplaySize.y;
  float y = 0.36f * height;
  ImGui::PushFont(window.large_font() ? window.large_font() : window.body_font());
  y = centred_text(title, y) + 1.2f * ImGui::GetTextLineHeightWithSpacing();
  ImGui::PopFont();
  y = centred_text(body, y) + 1.5f * ImGui::GetTextLineHeightWithSpacing();
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

bool ParticipantView::draw_instructions(gl::Window& window, const Instructions& in, const std::string& progress) {
  clear(window);
  begin_overlay(window);
  const ImVec2 display = ImGui::GetIO().DisplaySize;
  const float s = window.framebuffer_scale();
  ImFont* large = window.large_font() ? window.large_font() : window.body_font();
  ImGui::PushFont(large);
  const float large_line = ImGui::GetTextLineHeightWithSpacing();
  const auto title = wrapped(in.title, text_width_limit()), round_line = wrapped(in.round_line, text_width_limit());
  ImGui::PopFont();
  const float line = ImGui::GetTextLineHeightWithSpacing(), gap = 0.8f * line;
  const auto body = wrapped(in.body, text_width_limit());
  const float button_h = in.button.empty() ? 0 : kButtonHeightPx / s;
  const float bottom = 2 * line + kMarginPx / s;  // the progress line
  const float fixed = static_cast<float>(title.size() + round_line.size()) * large_line + static_cast<float>(body.size()) * line +
                      3 * gap + button_h;
  float image = 0;
  if (in.examples && example_px_ > 0) {
    // 1:1 where the screen has room, else shrunk (a label and a gap go with it).
    const float room = display.y - bottom - 2 * gap - fixed - (line + gap);
    image = std::floor(std::min({example_px_ / s, room, 0.9f * display.x / 2.5f}));
    if (image < 24) image = 0;
  }
  const float total = fixed + (image > 0 ? image + line + gap : 0);
  float y = std::floor(std::max(gap, 0.5f * (display.y - bottom - total)));
  ImGui::PushFont(large);
  y = centred_lines(title, y) + gap;
  ImGui::PopFont();
  y = centred_lines(body, y) + gap;
  if (image > 0) {  // the jagged one left, the straight one right, labelled
    const float between = std::floor(image / 2), x0 = std::floor(0.5f * (display.x - 2 * image - between));
    const std::string* labels[2] = {&in.jagged_label, &in.straight_label};
    for (int i = 0; i < 2; ++i) {
      const float x = x0 + static_cast<float>(i) * (image + between);
      ImGui::SetCursorPos({x, y});
      // The textures hold the rows bottom-up: v runs from 1 at the top to 0.
      ImGui::Image(reinterpret_cast<ImTextureID>(static_cast<std::intptr_t>(examples_[i].id())), {image, image}, {0, 1}, {1, 0});
      const float w = ImGui::CalcTextSize(labels[i]->c_str()).x;
      ImGui::SetCursorPos({std::floor(x + 0.5f * (image - w)), y + image + 0.3f * line});
      ImGui::TextUnformatted(labels[i]->c_str());
    }
    y += image + line + gap;
  }
  ImGui::PushFont(large);
  y = centred_lines(round_line, y) + gap;
  ImGui::PopFont();
  bool clicked = false;
  if (!in.button.empty()) clicked = button_at(in.button, 0.5f * display.x, y, 0, button_h);
  progress_line(window, progress);
  ImGui::End();
  return clicked;
}

bool ParticipantView::draw_intake(gl::Window& window, std::string& id, const std::string& study, const std::string& problem) {
  clear(window);
  begin_overlay(window);
  const ImVec2 display = ImGui::GetIO().DisplaySize;
  const float s = window.framebuffer_scale();
  float y = std::floor(0.28f * display.y);
  ImGui::PushFont(window.large_font() ? window.large_font() : window.body_font());
  y = centred_text("New session", y) + ImGui::GetTextLineHeight();
  ImGui::PopFont();
  y = centred_text("Study: " + study + "\nType the participant id, then press Enter.", y) + 0.5f * ImGui::GetTextLineHeight();
  const float width = std::min(420 / s, 0.8f * display.x);
  ImGui::SetCursorPos({std::floor(0.5f * (display.x - width)), y});
  ImGui::SetNextItemWidth(width);
  char buffer[256] = {};
  id.copy(buffer, sizeof buffer - 1);
  if (!ImGui::IsAnyItemActive()) ImGui::SetKeyboardFocusHere();  // typing goes into the field at once
  bool confirmed = ImGui::InputText("##participant", buffer, sizeof buffer, ImGuiInputTextFlags_EnterReturnsTrue);
  id = buffer;
  y += ImGui::GetFrameHeightWithSpacing() + 0.5f * ImGui::GetTextLineHeight();
  confirmed |= button_at("Continue   (Enter)", 0.5f * display.x, y, 0, kButtonHeightPx / s);
  y += kButtonHeightPx / s + ImGui::GetTextLineHeight();
  if (!problem.empty()) {
    ImGui::PushStyleColor(ImGuiCol_Text, ImVec4{1.0f, 0.62f, 0.55f, 1});
    centred_text(problem, y);
    ImGui::PopStyleColor();
  }
  progress_line(window, "Escape: quit without writing anything");
  ImGui::End();
  return confirmed;
}

ConsentChoice ParticipantView::draw_consent(gl::Window& window, const std::string& title, const std::string& text,
                                            const std::string& agree, const std::string& decline) {
  clear(window);
  begin_overlay(window);
  const ImVec2 display = ImGui::GetIO().DisplaySize;
  const float s = window.framebuffer_scale();
  ImGui::PushFont(window.large_font() ? window.large_font() : window.body_font());
  const auto title_lines = wrapped(title, text_width_limit());
  const float large_line = ImGui::GetTextLineHeightWithSpacing();
  ImGui::PopFont();
  const auto lines = wrapped(text, text_width_limit());
  const float line = ImGui::GetTextLineHeightWithSpacing();
  const float total = static_cast<float>(title_lines.size()) * large_line + static_cast<float>(lines.size() + 2) * line + kButtonHeightPx / s;
  float y = std::floor(std::max(line, 0.5f * (display.y - total)));
  ImGui::PushFont(window.large_font() ? window.large_font() : window.body_font());
  y = centred_lines(title_lines, y) + line;
  ImGui::PopFont();
  y = centred_lines(lines, y) + line;
  ConsentChoice choice = ConsentChoice::none;
  const float width = std::max(ImGui::CalcTextSize(agree.c_str()).x, ImGui::CalcTextSize(decline.c_str()).x) + 64;
  if (button_at(agree, 0.5f * display.x - 0.5f * width - 12 / s, y, width, kButtonHeightPx / s)) choice = ConsentChoice::agree;
  if (button_at(decline, 0.5f * display.x + 0.5f * width + 12 / s, y, width, kButtonHeightPx / s)) choice = ConsentChoice::decline;
  ImGui::End();
  return choice;
}

void ParticipantView::draw_blank(gl::Window& window, const std::string& progress) {
  clear(window);
  begin_overlay(window);
  progress_line(window, progress);
  ImGui::End();
}

}  // namespace penumbra::study_gui
