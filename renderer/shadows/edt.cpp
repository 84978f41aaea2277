#include "shadows/edt.h"

#include <stdexcept>
#include <string>

#include "gl/context.h"

namespace penumbra::shadows {

Edt::Edt(const gl::ShaderLibrary& shaders)
    : columns_(shaders.program({{GL_COMPUTE_SHADER, "edt_columns.comp"}})),
      rows_(shaders.program({{GL_COMPUTE_SHADER, "edt_rows.comp"}})) {}

void Edt::compute(const gl::Texture& sites) {
  const gl::TextureDesc& in = sites.desc();
  if (in.format != GL_R8UI) throw std::invalid_argument("EDT: the site texture must be R8UI");
  if (in.width > kMaxSize || in.height > kMaxSize)
    throw std::invalid_argument("EDT: " + std::to_string(in.width) + "x" + std::to_string(in.height) +
                                " exceeds the largest exact size " + std::to_string(kMaxSize) + " per side");
  if (nearest_.desc().width != in.width || nearest_.desc().height != in.height || !nearest_.id()) {
    column_site_ = gl::Texture({GL_R32I, in.width, in.height, 1}, "EDT column sites");
    nearest_ = gl::Texture({GL_RG32I, in.width, in.height, 1}, "EDT nearest site");
    distance_sq_ = gl::Texture({GL_R32I, in.width, in.height, 1}, "EDT squared distance");
  }
  constexpr GLuint kGroup = 64;  // local_size_x of both shaders
  glBindImageTexture(0, sites.id(), 0, GL_FALSE, 0, GL_READ_ONLY, GL_R8UI);
  glBindImageTexture(1, column_site_.id(), 0, GL_FALSE, 0, GL_READ_WRITE, GL_R32I);
  glBindImageTexture(2, nearest_.id(), 0, GL_FALSE, 0, GL_READ_WRITE, GL_RG32I);
  glBindImageTexture(3, distance_sq_.id(), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_R32I);
  columns_.use();
  glDispatchCompute((static_cast<GLuint>(in.width) + kGroup - 1) / kGroup, 1, 1);
  glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
  rows_.use();
  glDispatchCompute((static_cast<GLuint>(in.height) + kGroup - 1) / kGroup, 1, 1);
  glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT | GL_TEXTURE_UPDATE_BARRIER_BIT);
  gl::check_errors("EDT");
}

}  // namespace penumbra::shadows
