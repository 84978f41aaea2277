#pragma once
// Brackets one pass of a frame: records its name in the frame's pass list and times it.
#include <string>
#include <vector>

#include <penumbra/gl/timer.h>

namespace penumbra::shadows {

class ScopedPass {
 public:
  ScopedPass(gl::PassTimer* timer, const char* name, std::vector<std::string>& passes) : timer_(timer) {
    passes.emplace_back(name);
    if (timer_) timer_->begin(name);
  }
  ~ScopedPass() {
    if (timer_) timer_->end();
  }
  ScopedPass(const ScopedPass&) = delete;
  ScopedPass& operator=(const ScopedPass&) = delete;

 private:
  gl::PassTimer* timer_;
};

}  // namespace penumbra::shadows
