#pragma once
// OpenGL 4.5 core contexts: headless through EGL, and the facts the renderer needs about them.
#include <memory>
#include <string>

namespace penumbra::gl {

struct ContextInfo {
  std::string vendor;
  std::string renderer;
  std::string version;
  std::string platform;        // "egl-surfaceless", "egl-device", "glfw"
  bool software = false;       // llvmpipe/softpipe/swrast: timer queries are meaningless there
  int max_texture_size = 0;
};

// Reads vendor/renderer/limits from the current context.
ContextInfo query_context_info(std::string platform);

// Installs a KHR_debug callback; in debug builds GL errors become exceptions (thrown from the
// next `check_errors()`), in release builds they are printed once each.
void install_debug_output(bool throw_on_error);
// Throws std::runtime_error naming `where` if a GL error or a captured debug error is pending.
void check_errors(const char* where);

// A headless OpenGL 4.5 core context. Tries the EGL surfaceless platform (Mesa) first and the
// EGL device platform (NVIDIA) second. Throws with one clear message if neither works.
class HeadlessContext {
 public:
  HeadlessContext();
  ~HeadlessContext();
  HeadlessContext(const HeadlessContext&) = delete;
  HeadlessContext& operator=(const HeadlessContext&) = delete;

  const ContextInfo& info() const { return info_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  ContextInfo info_;
};

}  // namespace penumbra::gl
