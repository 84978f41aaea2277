#pragma once
// Exact Euclidean distance transform on the GPU: for every pixel, the nearest site and the
// squared distance to it, both exact integers (two compute passes: one invocation per column,
// then one per row; Meijster et al. 2000, the integer form of Felzenszwalb & Huttenlocher's
// lower envelope). Ties between equidistant sites go to the one with the smaller column, then the
// smaller row, but any equidistant site is a correct answer.
#include <penumbra/gl/objects.h>
#include <penumbra/gl/shader_library.h>

namespace penumbra::shadows {

class Edt {
 public:
  static constexpr int kMaxSize = 16384;  // per side; keeps every integer term below 2^31

  explicit Edt(const gl::ShaderLibrary& shaders);

  // `sites`: an R8UI texture whose non-zero texels are the sites. Fills nearest() and
  // distance_sq() at the same size (reallocated when the size changes). Throws
  // std::invalid_argument for a texture that is not R8UI or larger than kMaxSize.
  void compute(const gl::Texture& sites);

  // RG32I: (x, y) of the nearest site, (-1, -1) everywhere when the image has no site.
  const gl::Texture& nearest() const { return nearest_; }
  // R32I: squared distance to the nearest site in pixels², -1 when the image has no site.
  const gl::Texture& distance_sq() const { return distance_sq_; }

 private:
  gl::Program columns_, rows_;
  gl::Texture column_site_;  // R32I: row of the nearest site in the same column, -1: none
  gl::Texture nearest_, distance_sq_;
};

}  // namespace penumbra::shadows
