#pragma once
// OpenGL 4.5 core contexts: headless through EGL, and the facts the renderer needs about them.
#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
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
// next `check_errors()`), in release builds they are printed once each, except GL_OUT_OF_MEMORY,
// which check_errors() reports as an OutOfMemory the allocation can explain (a "GL debug" line
// came before the error line).
void install_debug_output(bool throw_on_error);

// GL_OUT_OF_MEMORY: thrown by check_errors(), so that what allocated can say how large it was and
// what to lower.
class OutOfMemory : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};
// Throws std::runtime_error naming `where` if a GL error or a captured debug error is pending;
// OutOfMemory for GL_OUT_OF_MEMORY.
void check_errors(const char* where);

// Bytes this process may still map under its address-space limit (RLIMIT_AS, `ulimit -v`), or
// nothing when it has none. On software GL (llvmpipe) textures are this process's memory.
std::optional<std::uint64_t> address_space_left_bytes();

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
