#include "gl/objects.h"

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
  glCreateQueries(target, 1, &id);
  handle_ = Handle<detail::delete_query>(id);
}

}  // namespace penumbra::gl
