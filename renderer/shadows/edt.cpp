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
  // Both passes see one image binding table: the column sites must sit where both shaders look.
  const GLuint column_site = columns_.binding("u_column_site");
  if (rows_.binding("u_column_site") != column_site) throw std::logic_error("EDT: edt_columns and edt_rows bind u_column_site differently");
  glBindImageTexture(columns_.binding("u_sites"), sites.id(), 0, GL_FALSE, 0, GL_READ_ONLY, GL_R8UI);
  glBindImageTexture(column_site, column_site_.id(), 0, GL_FALSE, 0, GL_READ_WRITE, GL_R32I);
  glBindImageTexture(rows_.binding("u_nearest"), nearest_.id(), 0, GL_FALSE, 0, GL_READ_WRITE, GL_RG32I);
  glBindImageTexture(rows_.binding("u_distance_sq"), distance_sq_.id(), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_R32I);
  columns_.dispatch_covering(in.width);  // one invocation per column
  glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
  rows_.dispatch_covering(in.height);  // one invocation per row
  glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT | GL_TEXTURE_UPDATE_BARRIER_BIT);
  gl::check_errors("EDT");
}

}  // namespace penumbra::shadows
