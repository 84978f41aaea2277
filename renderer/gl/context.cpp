#include "gl/context.h"

#include <epoxy/egl.h>
#include <epoxy/gl.h>

#include <cstdio>
#include <cstring>
#include <mutex>
#include <set>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include <sys/resource.h>
#include <unistd.h>

namespace penumbra::gl {
namespace {

std::string gl_string(GLenum name) {
  const auto* s = reinterpret_cast<const char*>(glGetString(name));
  return s ? s : "";
}

bool contains(const std::string& haystack, const char* needle) {
  return haystack.find(needle) != std::string::npos;
}

struct DebugState {
  std::mutex mutex;
  bool throw_on_error = false;
  std::string pending;           // first error message since the last check
  std::set<GLuint> reported_ids;  // release builds print each message id once
};
DebugState& debug_state() {
  static DebugState state;
  return state;
}

void GLAPIENTRY on_debug_message(GLenum source, GLenum type, GLuint id, GLenum severity, GLsizei,
                                 const GLchar* message, const void*) {
  // Compile and link failures are reported, with file and line, by the shader library.
  if (source == GL_DEBUG_SOURCE_SHADER_COMPILER) return;
  if (type != GL_DEBUG_TYPE_ERROR && severity != GL_DEBUG_SEVERITY_HIGH) return;
  auto& state = debug_state();
  std::lock_guard lock(state.mutex);
  if (state.throw_on_error) {
    if (state.pending.empty()) state.pending = message;
  } else if (std::string_view(message).find("OUT_OF_MEMORY") != std::string_view::npos) {
    // glGetError() still holds it: check_errors() throws OutOfMemory at the allocation.
  } else if (state.reported_ids.insert(id).second) {
    std::fprintf(stderr, "GL debug: %s\n", message);
  }
}

}  // namespace

ContextInfo query_context_info(std::string platform) {
  ContextInfo info;
  info.vendor = gl_string(GL_VENDOR);
  info.renderer = gl_string(GL_RENDERER);
  info.version = gl_string(GL_VERSION);
  info.platform = std::move(platform);
  info.software = contains(info.renderer, "llvmpipe") || contains(info.renderer, "softpipe") ||
                  contains(info.renderer, "SWR") || contains(info.renderer, "swrast");
  glGetIntegerv(GL_MAX_TEXTURE_SIZE, &info.max_texture_size);
  return info;
}

void install_debug_output(bool throw_on_error) {
  if (!epoxy_has_gl_extension("GL_KHR_debug") && epoxy_gl_version() < 43) return;
  debug_state().throw_on_error = throw_on_error;
  glEnable(GL_DEBUG_OUTPUT);
  glEnable(GL_DEBUG_OUTPUT_SYNCHRONOUS);
  glDebugMessageCallback(on_debug_message, nullptr);
}

void check_errors(const char* where) {
  std::string message;
  {
    auto& state = debug_state();
    std::lock_guard lock(state.mutex);
    message.swap(state.pending);
  }
  GLenum err = glGetError();
  if (message.empty() && err == GL_NO_ERROR) return;
  if (message.empty()) {
    message = err == GL_OUT_OF_MEMORY ? "out of GPU memory" : "GL error 0x" + [&] {
      char buf[16];
      std::snprintf(buf, sizeof buf, "%04x", err);
      return std::string(buf);
    }();
  }
  while (glGetError() != GL_NO_ERROR) {
  }
  if (err == GL_OUT_OF_MEMORY) throw OutOfMemory(std::string(where) + ": out of GPU memory");
  throw std::runtime_error(std::string(where) + ": " + message);
}

std::optional<std::uint64_t> address_space_left_bytes() {
  rlimit limit{};
  if (getrlimit(RLIMIT_AS, &limit) != 0 || limit.rlim_cur == RLIM_INFINITY) return std::nullopt;
  unsigned long pages = 0;  // the first field of /proc/self/statm: the whole mapped size, in pages
  if (std::FILE* f = std::fopen("/proc/self/statm", "r")) {
    if (std::fscanf(f, "%lu", &pages) != 1) pages = 0;
    std::fclose(f);
  }
  const std::uint64_t used = static_cast<std::uint64_t>(pages) * static_cast<std::uint64_t>(sysconf(_SC_PAGESIZE));
  return used >= limit.rlim_cur ? 0 : limit.rlim_cur - used;
}

// ---------------------------------------------------------------------------------------------

struct HeadlessContext::Impl {
  EGLDisplay display = EGL_NO_DISPLAY;
  EGLContext context = EGL_NO_CONTEXT;
  ~Impl() {
    if (display == EGL_NO_DISPLAY) return;
    eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    if (context != EGL_NO_CONTEXT) eglDestroyContext(display, context);
    eglTerminate(display);
  }
};

namespace {

bool has_egl_client_extension(const char* name) {
  const char* exts = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  return exts && std::strstr(exts, name) != nullptr;
}

// Creates a 4.5 core context on `display`; returns EGL_NO_CONTEXT on failure.
EGLContext create_core_context(EGLDisplay display) {
  EGLint major = 0, minor = 0;
  if (!eglInitialize(display, &major, &minor)) return EGL_NO_CONTEXT;
  if (!eglBindAPI(EGL_OPENGL_API)) return EGL_NO_CONTEXT;
  const EGLint config_attribs[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
  EGLConfig config = nullptr;
  EGLint count = 0;
  eglChooseConfig(display, config_attribs, &config, 1, &count);
  if (count < 1) config = nullptr;  // EGL_KHR_no_config_context
#ifndef NDEBUG
  const EGLint debug_flag = EGL_CONTEXT_OPENGL_DEBUG_BIT_KHR;
#else
  const EGLint debug_flag = 0;
#endif
  const EGLint context_attribs[] = {EGL_CONTEXT_MAJOR_VERSION, 4,
                                    EGL_CONTEXT_MINOR_VERSION, 5,
                                    EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                    EGL_CONTEXT_FLAGS_KHR, debug_flag,
                                    EGL_NONE};
  EGLContext ctx = eglCreateContext(display, config, EGL_NO_CONTEXT, context_attribs);
  if (ctx == EGL_NO_CONTEXT) return EGL_NO_CONTEXT;
  if (!eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, ctx)) {
    eglDestroyContext(display, ctx);
    return EGL_NO_CONTEXT;
  }
  return ctx;
}

}  // namespace

HeadlessContext::HeadlessContext() : impl_(std::make_unique<Impl>()) {
  std::string platform;
  std::string tried;
  if (has_egl_client_extension("EGL_MESA_platform_surfaceless")) {
    impl_->display = eglGetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
    if (impl_->display != EGL_NO_DISPLAY) impl_->context = create_core_context(impl_->display);
    if (impl_->context != EGL_NO_CONTEXT) platform = "egl-surfaceless";
    tried += "surfaceless";
    if (impl_->context == EGL_NO_CONTEXT && impl_->display != EGL_NO_DISPLAY) {
      eglTerminate(impl_->display);
      impl_->display = EGL_NO_DISPLAY;
    }
  }
  if (impl_->context == EGL_NO_CONTEXT && has_egl_client_extension("EGL_EXT_platform_device")) {
    EGLDeviceEXT devices[16];
    EGLint n = 0;
    eglQueryDevicesEXT(16, devices, &n);
    for (EGLint i = 0; i < n && impl_->context == EGL_NO_CONTEXT; ++i) {
      impl_->display = eglGetPlatformDisplayEXT(EGL_PLATFORM_DEVICE_EXT, devices[i], nullptr);
      if (impl_->display == EGL_NO_DISPLAY) continue;
      impl_->context = create_core_context(impl_->display);
      if (impl_->context == EGL_NO_CONTEXT) {
        eglTerminate(impl_->display);
        impl_->display = EGL_NO_DISPLAY;
      }
    }
    if (impl_->context != EGL_NO_CONTEXT) platform = "egl-device";
    tried += tried.empty() ? "device" : ", device";
  }
  if (impl_->context == EGL_NO_CONTEXT) {
    throw std::runtime_error("cannot create a headless OpenGL 4.5 core context through EGL (tried: " +
                             (tried.empty() ? std::string("no EGL platform extension available") : tried) +
                             "); install libegl1-mesa-dev and libgl1-mesa-dri (scripts/setup.sh)");
  }
  if (epoxy_gl_version() < 45) {
    throw std::runtime_error("the EGL context reports OpenGL " + std::to_string(epoxy_gl_version()) +
                             "; Penumbra needs 4.5 core");
  }
#ifndef NDEBUG
  install_debug_output(true);
#else
  install_debug_output(false);
#endif
  info_ = query_context_info(platform);
}

HeadlessContext::~HeadlessContext() = default;

}  // namespace penumbra::gl
