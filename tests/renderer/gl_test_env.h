#pragma once
// One headless OpenGL context per test binary, plus helpers shared by the GL tests.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "gl/context.h"
#include "io/image_io.h"

namespace penumbra::test {

class GlEnvironment : public ::testing::Environment {
 public:
  void SetUp() override { context_ = std::make_unique<gl::HeadlessContext>(); }
  void TearDown() override { context_.reset(); }
  static const gl::ContextInfo& info() { return context_->info(); }

 private:
  static inline std::unique_ptr<gl::HeadlessContext> context_;
};

// Every pixel finite and inside [lo, hi].
inline ::testing::AssertionResult all_finite_in(const io::ImageF& img, float lo, float hi) {
  for (std::size_t i = 0; i < img.pixels.size(); ++i) {
    const float v = img.pixels[i];
    if (!std::isfinite(v) || v < lo || v > hi)
      return ::testing::AssertionFailure() << "pixel " << i << " = " << v << " outside [" << lo << ", " << hi << "]";
  }
  return ::testing::AssertionSuccess();
}

}  // namespace penumbra::test
