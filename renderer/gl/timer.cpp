#include "gl/timer.h"

#include <algorithm>
#include <stdexcept>

#include "stats/summary.h"

namespace penumbra::gl {

const char* to_string(TimingMethod m) { return m == TimingMethod::wall_finish ? "wall_finish" : "gpu_timer"; }

struct PassTimer::Pending {
  std::string pass;
  std::unique_ptr<Query> query;
};

PassTimer::PassTimer(bool use_gpu_queries) : use_gpu_(use_gpu_queries) {}
PassTimer::~PassTimer() = default;

void PassTimer::begin(const std::string& pass) {
  if (!current_.empty()) throw std::logic_error("PassTimer: '" + pass + "' begun inside '" + current_ + "'");
  current_ = pass;
  if (std::find(order_.begin(), order_.end(), pass) == order_.end()) order_.push_back(pass);
  poll(false);
  if (use_gpu_) {
    auto p = std::make_unique<Pending>();
    p->pass = pass;
    if (!free_queries_.empty()) {
      p->query = std::move(free_queries_.back());
      free_queries_.pop_back();
    } else {
      p->query = std::make_unique<Query>(GL_TIME_ELAPSED);
    }
    glBeginQuery(GL_TIME_ELAPSED, p->query->id());
    pending_.push_back(std::move(p));
    return;  // no glFinish: it would serialise the frame the queries measure
  }
  glFinish();
  t0_ = std::chrono::steady_clock::now();
}

void PassTimer::end() {
  if (current_.empty()) throw std::logic_error("PassTimer::end without begin");
  if (use_gpu_) {
    glEndQuery(GL_TIME_ELAPSED);
    current_.clear();
    return;
  }
  glFinish();
  const auto t1 = std::chrono::steady_clock::now();
  wall_ms_[current_].push_back(std::chrono::duration<double, std::milli>(t1 - t0_).count());
  current_.clear();
}

void PassTimer::poll(bool wait) {
  while (!pending_.empty()) {
    auto& p = pending_.front();
    GLint available = 0;
    glGetQueryObjectiv(p->query->id(), GL_QUERY_RESULT_AVAILABLE, &available);
    if (!available && !wait) return;
    GLuint64 ns = 0;
    glGetQueryObjectui64v(p->query->id(), GL_QUERY_RESULT, &ns);
    gpu_ms_[p->pass].push_back(static_cast<double>(ns) * 1e-6);
    free_queries_.push_back(std::move(p->query));
    pending_.erase(pending_.begin());
  }
}

void PassTimer::clear() {
  poll(true);
  wall_ms_.clear();
  gpu_ms_.clear();
  order_.clear();
}

std::vector<PassStats> PassTimer::stats() const {
  std::vector<PassStats> out;
  auto add = [&](const std::string& pass, TimingMethod method, const std::vector<double>& v) {
    if (v.empty()) return;
    out.push_back({pass, method, stats::median(v), *std::min_element(v.begin(), v.end()),
                   *std::max_element(v.begin(), v.end()), static_cast<int>(v.size())});
  };
  for (const auto& pass : order_) {
    if (auto it = wall_ms_.find(pass); it != wall_ms_.end()) add(pass, TimingMethod::wall_finish, it->second);
    if (auto it = gpu_ms_.find(pass); it != gpu_ms_.end()) add(pass, TimingMethod::gpu_timer, it->second);
  }
  return out;
}

}  // namespace penumbra::gl
