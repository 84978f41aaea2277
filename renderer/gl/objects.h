#pragma once
// One GL name per object, owned with RAII and created from a small descriptor (GL 4.5 DSA).
#include <epoxy/gl.h>

#include <glm/glm.hpp>

#include <cstddef>
#include <functional>
#include <string_view>
#include <unordered_map>
#include <span>
#include <string>
#include <utility>

namespace penumbra::gl {

// Heterogeneous lookup of std::string keys by std::string_view.
struct StringHash {
  using is_transparent = void;
  std::size_t operator()(std::string_view s) const { return std::hash<std::string_view>{}(s); }
};

// Move-only owner of one GL name; `Deleter` frees it.
template <void (*Deleter)(GLuint)>
class Handle {
 public:
  Handle() = default;
  explicit Handle(GLuint id) : id_(id) {}
  ~Handle() { reset(); }
  Handle(Handle&& o) noexcept : id_(std::exchange(o.id_, 0)) {}
  Handle& operator=(Handle&& o) noexcept {
    if (this != &o) {
      reset();
      id_ = std::exchange(o.id_, 0);
    }
    return *this;
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;

  GLuint id() const { return id_; }
  explicit operator bool() const { return id_ != 0; }
  void reset() {
    if (id_) Deleter(id_);
    id_ = 0;
  }

 private:
  GLuint id_ = 0;
};

namespace detail {
inline void delete_texture(GLuint id) { glDeleteTextures(1, &id); }
inline void delete_sampler(GLuint id) { glDeleteSamplers(1, &id); }
inline void delete_framebuffer(GLuint id) { glDeleteFramebuffers(1, &id); }
inline void delete_buffer(GLuint id) { glDeleteBuffers(1, &id); }
inline void delete_vertex_array(GLuint id) { glDeleteVertexArrays(1, &id); }
inline void delete_query(GLuint id) { glDeleteQueries(1, &id); }
inline void delete_program(GLuint id) { glDeleteProgram(id); }
}  // namespace detail

struct TextureDesc {
  GLenum format = GL_RGBA8;  // sized internal format
  int width = 1;
  int height = 1;
  int levels = 1;
};

// Immutable-storage 2D texture. Sampling state lives in `Sampler` objects.
class Texture {
 public:
  Texture() = default;
  // Throws if the driver cannot allocate it (e.g. out of memory), naming `label`.
  Texture(const TextureDesc& desc, const char* label);
  GLuint id() const { return handle_.id(); }
  const TextureDesc& desc() const { return desc_; }
  void bind(GLuint unit) const { glBindTextureUnit(unit, id()); }

 private:
  Handle<detail::delete_texture> handle_;
  TextureDesc desc_;
};

struct SamplerDesc {
  GLenum min_filter = GL_LINEAR;
  GLenum mag_filter = GL_LINEAR;
  GLenum wrap = GL_CLAMP_TO_BORDER;
  float border[4] = {1, 1, 1, 1};
  bool depth_compare = false;  // GL_COMPARE_REF_TO_TEXTURE with GL_LEQUAL
};

class Sampler {
 public:
  Sampler() = default;
  explicit Sampler(const SamplerDesc& desc);
  GLuint id() const { return handle_.id(); }
  void bind(GLuint unit) const { glBindSampler(unit, id()); }

 private:
  Handle<detail::delete_sampler> handle_;
};

class Framebuffer {
 public:
  struct Attachment {
    const Texture* texture;
    GLenum point;  // GL_COLOR_ATTACHMENT0.., GL_DEPTH_ATTACHMENT
  };
  Framebuffer() = default;
  // Throws naming `label` if the result is incomplete.
  Framebuffer(std::span<const Attachment> attachments, const char* label);
  GLuint id() const { return handle_.id(); }
  void bind() const { glBindFramebuffer(GL_FRAMEBUFFER, id()); }

 private:
  Handle<detail::delete_framebuffer> handle_;
};

class Buffer {
 public:
  Buffer() = default;
  // Immutable storage of `bytes` bytes; `data` may be null. `flags` as for glNamedBufferStorage.
  Buffer(std::size_t bytes, const void* data, GLbitfield flags = 0);
  GLuint id() const { return handle_.id(); }
  std::size_t size() const { return bytes_; }

 private:
  Handle<detail::delete_buffer> handle_;
  std::size_t bytes_ = 0;
};

class VertexArray {
 public:
  VertexArray();
  GLuint id() const { return handle_.id(); }
  void bind() const { glBindVertexArray(id()); }

 private:
  Handle<detail::delete_vertex_array> handle_;
};

class Query {
 public:
  explicit Query(GLenum target);
  GLuint id() const { return handle_.id(); }

 private:
  Handle<detail::delete_query> handle_;
};

// A linked GLSL program. Build it with `ShaderLibrary::program`.
// A linked program. Its active uniforms' locations are resolved once, when it is wrapped (after
// linking), so setting a uniform by name costs a hash lookup, not a GL query; names the program
// lacks (optimized out, or not used by this variant) are ignored, as GL ignores location -1.
class Program {
 public:
  Program() = default;
  explicit Program(GLuint id);
  GLuint id() const { return handle_.id(); }
  void use() const { glUseProgram(id()); }
  // -1 when the program has no active uniform `name` (arrays: "u_x[2]" and "u_x" for element 0).
  GLint location(std::string_view name) const;

  void set(std::string_view name, float v) const { glProgramUniform1f(id(), location(name), v); }
  void set(std::string_view name, int v) const { glProgramUniform1i(id(), location(name), v); }
  void set(std::string_view name, bool v) const { glProgramUniform1i(id(), location(name), v ? 1 : 0); }
  void set(std::string_view name, const glm::vec2& v) const { glProgramUniform2fv(id(), location(name), 1, &v.x); }
  void set(std::string_view name, const glm::ivec2& v) const { glProgramUniform2iv(id(), location(name), 1, &v.x); }
  void set(std::string_view name, const glm::vec3& v) const { glProgramUniform3fv(id(), location(name), 1, &v.x); }
  void set(std::string_view name, const glm::vec4& v) const { glProgramUniform4fv(id(), location(name), 1, &v.x); }
  void set(std::string_view name, const glm::mat3& m) const { glProgramUniformMatrix3fv(id(), location(name), 1, GL_FALSE, &m[0][0]); }
  void set(std::string_view name, const glm::mat4& m) const { glProgramUniformMatrix4fv(id(), location(name), 1, GL_FALSE, &m[0][0]); }
  void set(std::string_view name, std::span<const glm::vec2> v) const {
    if (!v.empty()) glProgramUniform2fv(id(), location(name), static_cast<GLsizei>(v.size()), &v[0].x);
  }
  void set(std::string_view name, std::span<const glm::ivec4> v) const {
    if (!v.empty()) glProgramUniform4iv(id(), location(name), static_cast<GLsizei>(v.size()), &v[0].x);
  }

  // The unit the shader gave a sampler or image uniform (layout(binding = N)): C++ binds there
  // instead of repeating the number. Throws std::logic_error when the program has no such uniform.
  GLuint binding(std::string_view name) const;
  // A compute program's work-group size, from its layout(local_size_x = ...).
  glm::uvec3 work_group_size() const;
  // Uses the program and dispatches as many work groups as cover width × height × depth invocations.
  void dispatch_covering(int width, int height = 1, int depth = 1) const;

 private:
  Handle<detail::delete_program> handle_;
  std::unordered_map<std::string, GLint, StringHash, std::equal_to<>> locations_;
};

}  // namespace penumbra::gl
