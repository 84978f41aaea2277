#include "gl/objects.h"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "gl/context.h"

namespace penumbra::gl {

Texture::Texture(const TextureDesc& desc, const char* label) : desc_(desc) {
  if (desc.width < 1 || desc.height < 1) {
    throw std::runtime_error(std::string(label) + ": texture size " + std::to_string(desc.width) + "x" +
                             std::to_string(desc.height) + " is not positive");
  }
  GLint max_size = 0;
  glGetIntegerv(GL_MAX_TEXTURE_SIZE, &max_size);
  if (desc.width > max_size || desc.height > max_size) {
    throw std::runtime_error(std::string(label) + ": texture size " + std::to_string(desc.width) + "x" +
                             std::to_string(desc.height) + " exceeds GL_MAX_TEXTURE_SIZE " +
                             std::to_string(max_size));
  }
  GLuint id = 0;
  glCreateTextures(GL_TEXTURE_2D, 1, &id);
  handle_ = Handle<detail::delete_texture>(id);
  glTextureStorage2D(id, desc.levels, desc.format, desc.width, desc.height);
  glObjectLabel(GL_TEXTURE, id, -1, label);
  check_errors(label);
}

Sampler::Sampler(const SamplerDesc& desc) {
  GLuint id = 0;
  glCreateSamplers(1, &id);
  handle_ = Handle<detail::delete_sampler>(id);
  glSamplerParameteri(id, GL_TEXTURE_MIN_FILTER, static_cast<GLint>(desc.min_filter));
  glSamplerParameteri(id, GL_TEXTURE_MAG_FILTER, static_cast<GLint>(desc.mag_filter));
  glSamplerParameteri(id, GL_TEXTURE_WRAP_S, static_cast<GLint>(desc.wrap));
  glSamplerParameteri(id, GL_TEXTURE_WRAP_T, static_cast<GLint>(desc.wrap));
  glSamplerParameterfv(id, GL_TEXTURE_BORDER_COLOR, desc.border);
  if (desc.depth_compare) {
    glSamplerParameteri(id, GL_TEXTURE_COMPARE_MODE, GL_COMPARE_REF_TO_TEXTURE);
    glSamplerParameteri(id, GL_TEXTURE_COMPARE_FUNC, GL_LEQUAL);
  }
}

Framebuffer::Framebuffer(std::span<const Attachment> attachments, const char* label) {
  GLuint id = 0;
  glCreateFramebuffers(1, &id);
  handle_ = Handle<detail::delete_framebuffer>(id);
  GLenum draw_buffers[8];
  GLsizei n_draw = 0;
  for (const auto& a : attachments) {
    glNamedFramebufferTexture(id, a.point, a.texture->id(), 0);
    if (a.point >= GL_COLOR_ATTACHMENT0 && a.point < GL_COLOR_ATTACHMENT0 + 8) draw_buffers[n_draw++] = a.point;
  }
  if (n_draw == 0) {
    glNamedFramebufferDrawBuffer(id, GL_NONE);
    glNamedFramebufferReadBuffer(id, GL_NONE);
  } else {
    glNamedFramebufferDrawBuffers(id, n_draw, draw_buffers);
  }
  glObjectLabel(GL_FRAMEBUFFER, id, -1, label);
  const GLenum status = glCheckNamedFramebufferStatus(id, GL_FRAMEBUFFER);
  if (status != GL_FRAMEBUFFER_COMPLETE) {
    throw std::runtime_error(std::string(label) + ": framebuffer incomplete (status 0x" +
                             [&] {
                               char buf[16];
                               std::snprintf(buf, sizeof buf, "%04x", status);
                               return std::string(buf);
                             }() +
                             ")");
  }
}

Buffer::Buffer(std::size_t bytes, const void* data, GLbitfield flags) : bytes_(bytes) {
  GLuint id = 0;
  glCreateBuffers(1, &id);
  handle_ = Handle<detail::delete_buffer>(id);
  glNamedBufferStorage(id, static_cast<GLsizeiptr>(bytes == 0 ? 1 : bytes), data, flags);
}

VertexArray::VertexArray() {
  GLuint id = 0;
  glCreateVertexArrays(1, &id);
  handle_ = Handle<detail::delete_vertex_array>(id);
}

Query::Query(GLenum target) {
  GLuint id = 0;
  // Mesa 22's glCreateQueries refuses the pipeline-statistics targets (GL_INVALID_ENUM for
  // GL_PRIMITIVES_SUBMITTED); a name from glGenQueries takes its target at its first glBeginQuery.
  const bool statistics =  // ARB_pipeline_statistics_query's targets, 0x82EE to 0x82F7, and the geometry shader's
      (target >= GL_VERTICES_SUBMITTED_ARB && target <= GL_CLIPPING_OUTPUT_PRIMITIVES_ARB) || target == GL_GEOMETRY_SHADER_INVOCATIONS;
  if (statistics) {
    glGenQueries(1, &id);
  } else {
    glCreateQueries(target, 1, &id);
  }
  handle_ = Handle<detail::delete_query>(id);
}

Program::Program(GLuint id) : handle_(id) {
  if (!id) return;
  GLint count = 0;
  glGetProgramInterfaceiv(id, GL_UNIFORM, GL_ACTIVE_RESOURCES, &count);
  const GLenum props[] = {GL_NAME_LENGTH, GL_LOCATION};
  std::string name;
  for (GLint i = 0; i < count; ++i) {
    GLint values[2] = {0, -1};
    glGetProgramResourceiv(id, GL_UNIFORM, static_cast<GLuint>(i), 2, props, 2, nullptr, values);
    if (values[1] < 0) continue;  // in a uniform block: set through its buffer
    name.resize(static_cast<std::size_t>(std::max(values[0], 1)));
    glGetProgramResourceName(id, GL_UNIFORM, static_cast<GLuint>(i), values[0], nullptr, name.data());
    name.resize(name.find('\0') == std::string::npos ? name.size() : name.find('\0'));
    locations_.emplace(name, values[1]);
    // An array is listed once, as "u_x[0]": every element i is at location + i.
    if (name.size() > 3 && name.ends_with("[0]")) {
      const std::string base = name.substr(0, name.size() - 3);
      GLint size = 1;
      const GLenum array_size = GL_ARRAY_SIZE;
      glGetProgramResourceiv(id, GL_UNIFORM, static_cast<GLuint>(i), 1, &array_size, 1, nullptr, &size);
      locations_.emplace(base, values[1]);
      for (GLint k = 1; k < size; ++k) locations_.emplace(base + "[" + std::to_string(k) + "]", values[1] + k);
    }
  }
}

GLint Program::location(std::string_view name) const {
  const auto it = locations_.find(name);
  return it == locations_.end() ? -1 : it->second;
}

GLuint Program::binding(std::string_view name) const {
  const GLint loc = location(name);
  if (loc < 0) throw std::logic_error("program " + std::to_string(id()) + " has no sampler or image uniform '" + std::string(name) + "'");
  GLint unit = -1;
  glGetUniformiv(id(), loc, &unit);
  if (unit < 0) throw std::logic_error("uniform '" + std::string(name) + "' has no binding");
  return static_cast<GLuint>(unit);
}

glm::uvec3 Program::work_group_size() const {
  GLint size[3] = {0, 0, 0};
  glGetProgramiv(id(), GL_COMPUTE_WORK_GROUP_SIZE, size);
  if (size[0] <= 0) throw std::logic_error("program " + std::to_string(id()) + " is not a compute program");
  return {static_cast<unsigned>(size[0]), static_cast<unsigned>(size[1]), static_cast<unsigned>(size[2])};
}

void Program::dispatch_covering(int width, int height, int depth) const {
  const glm::uvec3 group = work_group_size();
  const auto groups = [](int n, unsigned g) { return (static_cast<GLuint>(std::max(n, 0)) + g - 1) / g; };
  use();
  glDispatchCompute(groups(width, group.x), groups(height, group.y), groups(depth, group.z));
}

}  // namespace penumbra::gl
