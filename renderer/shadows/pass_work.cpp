#include <penumbra/shadows/pass_work.h>

#include <stdexcept>

namespace penumbra::shadows {

namespace {
constexpr GLenum kTargets[3] = {GL_PRIMITIVES_SUBMITTED_ARB, GL_FRAGMENT_SHADER_INVOCATIONS_ARB, GL_COMPUTE_SHADER_INVOCATIONS_ARB};
}

void WorkCounter::begin(const std::string& pass) {
  if (open_) throw std::logic_error("work counter: pass '" + pass + "' begun inside '" + passes_.back() + "'");
  const std::size_t first = 3 * passes_.size();
  for (std::size_t k = 0; k < 3; ++k) {
    if (queries_.size() <= first + k) queries_.push_back(std::make_unique<gl::Query>(kTargets[k]));
    glBeginQuery(kTargets[k], queries_[first + k]->id());
  }
  passes_.push_back(pass);
  open_ = true;
}

void WorkCounter::end() {
  if (!open_) throw std::logic_error("work counter: end without begin");
  for (GLenum target : kTargets) glEndQuery(target);
  open_ = false;
}

std::vector<PassWork> WorkCounter::collect() {
  if (open_) end();
  std::vector<PassWork> work;
  for (std::size_t i = 0; i < passes_.size(); ++i) {
    GLuint64 v[3] = {0, 0, 0};
    for (std::size_t k = 0; k < 3; ++k) glGetQueryObjectui64v(queries_[3 * i + k]->id(), GL_QUERY_RESULT, &v[k]);
    work.push_back({passes_[i], v[0], v[1], v[2]});
  }
  passes_.clear();
  return work;
}

}  // namespace penumbra::shadows
