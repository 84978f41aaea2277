#pragma once
// The Ceres settings of the project's small fits (the display's gamma model, the psychometric
// maximum likelihood of the fitter): one definition, so that a change of solver lands in both.
#include <ceres/solver.h>

namespace penumbra::solver {

// Dense QR, single-threaded (results do not depend on the thread count), silent, at most 200
// iterations; converged when the relative cost change and the gradient fall below `tolerance` and
// the relative parameter step below 100 · tolerance.
inline ceres::Solver::Options small_problem_options(double tolerance) {
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_QR;
  options.max_num_iterations = 200;
  options.function_tolerance = tolerance;
  options.gradient_tolerance = tolerance;
  options.parameter_tolerance = 100 * tolerance;
  options.num_threads = 1;
  options.logging_type = ceres::SILENT;
  return options;
}

}  // namespace penumbra::solver
