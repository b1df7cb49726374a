#pragma once
// CeresSolverSettings: the Ceres options every cge optimiser shares, fixed so that a solve is
// deterministic (one thread, no logging, no time limit, fixed tolerances). Same input: bit-identical
// output on the same machine and Ceres build.
#include "cge/ceres/ceres_headers.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

namespace cge {

struct CeresSolverSettings {
  /// Levenberg-Marquardt iterations per solve (a "round" for the pose refiner), >= 1.
  int max_iterations = 50;
  /// Stop when the relative cost decrease of a step is below this, dimensionless, >= 0.
  double function_tolerance = 1e-8;
  /// Stop when the max-norm of the projected gradient is below this, cost units, >= 0.
  double gradient_tolerance = 1e-10;
  /// Stop when the relative step size is below this, dimensionless, >= 0.
  double parameter_tolerance = 1e-10;

  /// Throws std::invalid_argument naming the bad field; `owner` prefixes the message.
  void validate(const std::string& owner) const {
    const auto fail = [&](const std::string& what) { throw std::invalid_argument(owner + ": " + what); };
    if (max_iterations < 1) fail("max_iterations must be at least 1");
    if (!(std::isfinite(function_tolerance) && function_tolerance >= 0))
      fail("function_tolerance must be finite and not negative");
    if (!(std::isfinite(gradient_tolerance) && gradient_tolerance >= 0))
      fail("gradient_tolerance must be finite and not negative");
    if (!(std::isfinite(parameter_tolerance) && parameter_tolerance >= 0))
      fail("parameter_tolerance must be finite and not negative");
  }

  /// Solver options with these settings, one thread, no output. `sparse` asks for a sparse linear
  /// solver (sparse normal Cholesky, or sparse Schur when `schur`), which falls back to the dense
  /// equivalent when Ceres was built without a sparse library.
  ceres::Solver::Options options(bool sparse, bool schur) const {
    ceres::Solver::Options o;
    o.minimizer_type = ceres::TRUST_REGION;
    o.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
    o.max_num_iterations = max_iterations;
    o.function_tolerance = function_tolerance;
    o.gradient_tolerance = gradient_tolerance;
    o.parameter_tolerance = parameter_tolerance;
    o.num_threads = 1;
    o.minimizer_progress_to_stdout = false;
    o.logging_type = ceres::SILENT;
    const bool have_sparse = ceres::IsSparseLinearAlgebraLibraryTypeAvailable(o.sparse_linear_algebra_library_type);
    if (schur) {
      o.linear_solver_type = (sparse && have_sparse) ? ceres::SPARSE_SCHUR : ceres::DENSE_SCHUR;
    } else {
      o.linear_solver_type = (sparse && have_sparse) ? ceres::SPARSE_NORMAL_CHOLESKY : ceres::DENSE_QR;
    }
    return o;
  }
};

}  // namespace cge
