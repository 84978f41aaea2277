#include "shadows/contract.h"

#include <stdexcept>
#include <string>

namespace penumbra::shadows {

void check_shadow_frame_block(const gl::Program& program, std::string_view what) {
  const GLuint index = glGetUniformBlockIndex(program.id(), "ShadowFrame");
  if (index == GL_INVALID_INDEX) return;
  GLint size = 0, binding = -1;
  glGetActiveUniformBlockiv(program.id(), index, GL_UNIFORM_BLOCK_DATA_SIZE, &size);
  glGetActiveUniformBlockiv(program.id(), index, GL_UNIFORM_BLOCK_BINDING, &binding);
  if (size != static_cast<GLint>(sizeof(contract::ShadowFrame)) || binding != contract::BLOCK_SHADOW_FRAME)
    throw std::runtime_error(std::string(what) + ": uniform block ShadowFrame is " + std::to_string(size) + " bytes at binding " +
                             std::to_string(binding) + ", the C++ side (shaders/shadow_contract.h) " +
                             std::to_string(sizeof(contract::ShadowFrame)) + " bytes at binding " +
                             std::to_string(contract::BLOCK_SHADOW_FRAME) + " (std140 layout broken?)");
}

}  // namespace penumbra::shadows
