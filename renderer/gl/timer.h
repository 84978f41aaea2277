#pragma once
// Per-pass timing, one method per timer. On software GL (llvmpipe, whose timer queries mean
// nothing) wall clock around glFinish (`wall_finish`); on a real GPU GL_TIME_ELAPSED queries
// (`gpu_timer`) in a ring read a few frames late, with no glFinish, which would serialise the frame
// being measured (a whole frame's wall time is the caller's, around one glFinish). Every number is
// reported with the method that produced it.
#include <chrono>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <penumbra/gl/objects.h>

namespace penumbra::gl {

enum class TimingMethod { wall_finish, gpu_timer };
const char* to_string(TimingMethod m);

struct PassStats {
  std::string pass;
  TimingMethod method;
  double median_ms = 0;
  double min_ms = 0;
  double max_ms = 0;
  int samples = 0;
};

class PassTimer {
 public:
  explicit PassTimer(bool use_gpu_queries);
  ~PassTimer();

  // Brackets one pass of the current frame (`use_gpu_queries`: a timer query, else glFinish and
  // the wall clock). Passes may not nest.
  void begin(const std::string& pass);
  void end();
  // Collects GPU query results that are ready (all of them when `wait` is set).
  void poll(bool wait);
  void clear();

  bool gpu_queries() const { return use_gpu_; }
  // Median/min/max per pass and method, in first-seen pass order.
  std::vector<PassStats> stats() const;

 private:
  struct Pending;
  bool use_gpu_;
  std::string current_;
  std::chrono::steady_clock::time_point t0_;
  std::vector<std::string> order_;
  std::map<std::string, std::vector<double>> wall_ms_;
  std::map<std::string, std::vector<double>> gpu_ms_;
  std::vector<std::unique_ptr<Pending>> pending_;  // issued queries not yet read
  std::vector<std::unique_ptr<Query>> free_queries_;
};

}  // namespace penumbra::gl
