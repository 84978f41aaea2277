#include "shadows/contract.h"

#include <stdexcept>
#include <string>

namespace penumbra::shadows {

namespace {

// Throws unless `program`'s block `name`, where it has one, is `bytes` bytes at `binding_point`.
void check_block(const gl::Program& program, std::string_view what, const char* name, const char* header, std::size_t bytes, int binding_point) {
  const GLuint index = glGetUniformBlockIndex(program.id(), name);
  if (index == GL_INVALID_INDEX) return;
  GLint size = 0, binding = -1;
  glGetActiveUniformBlockiv(program.id(), index, GL_UNIFORM_BLOCK_DATA_SIZE, &size);
  glGetActiveUniformBlockiv(program.id(), index, GL_UNIFORM_BLOCK_BINDING, &binding);
  if (size != static_cast<GLint>(bytes) || binding != binding_point)
    throw std::runtime_error(std::string(what) + ": uniform block " + name + " is " + std::to_string(size) + " bytes at binding " +
                             std::to_string(binding) + ", the C++ side (" + header + ") " + std::to_string(bytes) + " bytes at binding " +
                             std::to_string(binding_point) + " (std140 layout broken?)");
}

}  // namespace

void check_shadow_frame_block(const gl::Program& program, std::string_view what) {
  check_block(program, what, "ShadowFrame", "shaders/shadow_contract.h", sizeof(contract::ShadowFrame), contract::BLOCK_SHADOW_FRAME);
}

void check_virtual_frame_block(const gl::Program& program, std::string_view what) {
  check_block(program, what, "VirtualFrame", "shaders/virtual_mark_contract.h", sizeof(virtual_mark::VirtualFrame), contract::BLOCK_VIRTUAL_FRAME);
}

}  // namespace penumbra::shadows
