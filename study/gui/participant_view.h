#pragma once
// What the participant sees: a neutral grey screen, the stimuli copied 1:1 into physical
// framebuffer pixels (no scaling, no filtering: a framebuffer blit of exactly the stimulus size
// at integer positions), the question, two answer buttons, a quiet progress line, and the
// welcome / break / pause / end screens. Nothing else.
#include <string>
#include <vector>

#include "gl/objects.h"
#include "io/image_io.h"
#include "procedure/session_flow.h"

namespace penumbra::gl {
class Window;
}

namespace penumbra::study_gui {

// Where the stimuli go, in framebuffer pixels (origin top-left): centred, side by side with a
// gap of half a stimulus for 2afc, one in the middle for yesno.
// A frame study's 2afc adds the sample (the reference) centred above the two, half a stimulus apart.
struct StimulusLayout {
  int size_px = 0;
  int count = 0;
  int x_px[2] = {0, 0};  // left edges
  int y_px = 0;          // top edge
  bool sample = false;
  int sample_x_px = 0, sample_y_px = 0;
  int top_px() const { return sample ? sample_y_px : y_px; }  // the question goes above this
};
// Throws when the framebuffer cannot hold the stimuli with room for the question and buttons.
StimulusLayout stimulus_layout(int framebuffer_width, int framebuffer_height, int size_px, int count, bool sample = false);

using procedure::Answer;
// Left arrow or F -> first; right arrow or J -> second (GLFW key codes).
Answer answer_for_key(int key);

// Display value of the background (8-bit, the same on all channels).
inline constexpr int kBackgroundValue = 128;

// What a trial screen says: the question above the stimuli and the two answer buttons, or, after a
// practice answer, the feedback in their place.
struct TrialText {
  std::string question, first, second;
  std::string feedback;   // non-empty: shown instead of the question, no buttons
  bool feedback_correct = false;
};

// An instruction screen: title, body, the examples (a jagged and a straight edge, labelled), the
// round line ("Round 2 of 4") and the button.
struct Instructions {
  std::string title, body, jagged_label, straight_label, round_line, button;
  bool examples = true;
};

enum class ConsentChoice { none, agree, decline };

class ParticipantView {
 public:
  // Needs the participant window's contexts current (sets that ImGui context's style).
  explicit ParticipantView(std::string task);

  // The trial's images (8-bit grey or RGB, top row first, all the same square size), left to right,
  // and a frame study's sample shown above them (null: none).
  void set_stimuli(const std::vector<const io::Image8*>& images, const io::Image8* sample = nullptr);
  // The instruction screens' examples (8-bit grey, square, the same size).
  void set_examples(const io::Image8& jagged, const io::Image8& straight);

  // One frame's content (between gl::Window::begin_frame and end_frame). The background is
  // cleared by each. Returns the answer clicked with a button, if any.
  Answer draw_trial(gl::Window& window, const TrialText& text, const std::string& progress);
  // Title, body and one button (or none when `button` is empty); true when the button is clicked.
  bool draw_message(gl::Window& window, const std::string& title, const std::string& body, const std::string& button,
                    const std::string& progress);
  // True when the button is clicked (an empty button: none). The examples shrink to fit the screen
  // (they are not measured; the trial's stimuli always show 1:1).
  bool draw_instructions(gl::Window& window, const Instructions& in, const std::string& progress);
  // The experimenter's start screen: the participant id typed into `id`; true when Enter or the
  // button confirms it. `problem` (red) says why the last id was refused.
  bool draw_intake(gl::Window& window, std::string& id, const std::string& study, const std::string& problem);
  // The consent text with its agree and decline buttons.
  ConsentChoice draw_consent(gl::Window& window, const std::string& title, const std::string& text, const std::string& agree,
                             const std::string& decline);
  // Only the background and the progress line (between trials).
  void draw_blank(gl::Window& window, const std::string& progress);

  const StimulusLayout& layout() const { return layout_; }

 private:
  void clear(gl::Window& window);
  void begin_overlay(gl::Window& window);
  void progress_line(gl::Window& window, const std::string& progress);

  std::string task_;
  gl::Texture textures_[3];  // left, right, the sample
  gl::Framebuffer framebuffers_[3];
  bool sample_ = false;
  gl::Texture examples_[2];  // jagged, straight
  int count_ = 0, size_px_ = 0, example_px_ = 0;
  StimulusLayout layout_;
};

}  // namespace penumbra::study_gui
