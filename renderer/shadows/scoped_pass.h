#pragma once
// Brackets one pass (or one step of a pass) of a frame: records its name in the frame's pass list,
// times it and counts its work (pass_work.h), each when given.
#include <string>
#include <vector>

#include <penumbra/gl/timer.h>
#include <penumbra/shadows/pass_work.h>

namespace penumbra::shadows {

// Where a frame's passes report: its timer and work counter (either may be null) and its pass list.
struct PassReport {
  gl::PassTimer* timer = nullptr;
  WorkCounter* work = nullptr;
  std::vector<std::string>* passes = nullptr;  // required
};

class ScopedPass {
 public:
  ScopedPass(const PassReport& report, const std::string& name) : timer_(report.timer), work_(report.work) {
    report.passes->push_back(name);
    if (timer_) timer_->begin(name);
    if (work_) work_->begin(name);
  }
  ~ScopedPass() {
    if (work_) work_->end();
    if (timer_) timer_->end();
  }
  ScopedPass(const ScopedPass&) = delete;
  ScopedPass& operator=(const ScopedPass&) = delete;

 private:
  gl::PassTimer* timer_;
  WorkCounter* work_;
};

}  // namespace penumbra::shadows
