#pragma once
// Keyboard input for Dear ImGui spread over frames so that none is lost. ImGui 1.86 (Debian's)
// keeps one down/up state per key and reads it once per frame, and its text field handles one key
// per frame (an else-if chain: BackSpace then Enter in one frame drops the Enter) after all of the
// frame's typed characters. Input that arrives in one glfwPollEvents (a short tap during a slow
// frame, a fast typist, xdotool on a loaded machine: CI lost an Enter this way) would lose
// presses and reorder text and keys. ImGui 1.87 added an input queue that trickles such input
// over frames; this is that queue for 1.86: events keep their order, and a frame takes them
// until the next one would be
//   - a second change of a key already changed in the frame (a press and its release),
//   - a second press of a non-modifier key (the text field handles one),
//   - a key after typed text, or typed text after a non-modifier key (keeping their order).
// Modifier keys ride along with the key they modify. GL-free so that it is tested without a window.
#include <algorithm>
#include <cstddef>
#include <vector>

namespace penumbra::gl {

class InputTrickle {
 public:
  struct Event {
    bool is_char = false;
    int key = -1;            // GLFW_KEY_*; a key event
    bool pressed = false;    // press (true) or release (false)
    unsigned int ch = 0;     // a typed character (is_char)
  };
  // GLFW's key codes of the modifier keys (shift, control, alt, super; left and right).
  static bool is_modifier(int key) { return key >= 340 && key <= 347; }

  void key(int key, bool pressed) { queue_.push_back({false, key, pressed, 0}); }
  void character(unsigned int ch) { queue_.push_back({true, -1, false, ch}); }

  // The events the frame about to start takes, oldest first; the rest wait for later frames.
  // A backlog beyond kMaxQueued (a window not drawn for a long time) is taken at once.
  std::vector<Event> frame_starting() {
    std::size_t n = queue_.size();
    if (n <= kMaxQueued) {
      std::vector<int> changed;
      bool text = false, key_pressed = false, key_changed = false;
      for (n = 0; n < queue_.size(); ++n) {
        const Event& e = queue_[n];
        if (e.is_char) {
          if (key_changed) break;
          text = true;
          continue;
        }
        const bool modifier = is_modifier(e.key);
        if (text || std::find(changed.begin(), changed.end(), e.key) != changed.end()) break;
        if (e.pressed && !modifier && key_pressed) break;
        changed.push_back(e.key);
        key_pressed |= e.pressed && !modifier;
        key_changed |= !modifier;
      }
    }
    std::vector<Event> taken(queue_.begin(), queue_.begin() + static_cast<std::ptrdiff_t>(n));
    queue_.erase(queue_.begin(), queue_.begin() + static_cast<std::ptrdiff_t>(n));
    return taken;
  }
  bool empty() const { return queue_.empty(); }

  static constexpr std::size_t kMaxQueued = 256;

 private:
  std::vector<Event> queue_;
};

}  // namespace penumbra::gl
