// Internal to docunfold_isometry: the Gauss-Newton/Levenberg-Marquardt step
// of the solver, its normal equations solved by CHOLMOD or block-Jacobi
// conjugate gradients (SolveOptions::linear_solver).
#pragma once

#include <Eigen/CholmodSupport>
#include <Eigen/Sparse>
#include <algorithm>
#include <memory>
#include <vector>

#include "common/isometry/block_matrix.h"
#include "common/isometry/solver_internal.h"

namespace docunfold::isometry::internal {

class GaussNewton {
 public:
  GaussNewton(const QuadGrid& grid, const SolveOptions& o);
  bool direct() const { return direct_; }
  void set_threads(int threads) { threads_ = std::max(1, threads); }
  double damping() const { return mu_; }

  // One damped Gauss-Newton step with the data held fixed; returns whether
  // F decreased. `linear_iterations` counts CG iterations or factorisations.
  bool Step(State& s, const StepData& data, const Weights& w, int* linear_iterations);

 private:
  // JᵀJ into H_, Jᵀr into g; returns F. Rows of quads (and fairness
  // triplets) of one colour share no vertex, so they are added in parallel.
  double Assemble(const State& s, const StepData& data, const Weights& w, Eigen::VectorXd& g);
  bool SolveDirect(const Eigen::VectorXd& shift, const Eigen::VectorXd& g, Eigen::VectorXd& delta,
                   int* iterations);
  // Block-Jacobi preconditioned conjugate gradients on (H + shift) δ = -g.
  bool SolveCg(const Eigen::VectorXd& shift, const Eigen::VectorXd& g, Eigen::VectorXd& delta,
               int* iterations);

  const SolveOptions& o_;
  GridBlockMatrix H_;
  int threads_ = 1;
  bool direct_ = false;
  double cg_tolerance_;
  int cg_max_iterations_;
  double mu_ = 1e-4;
  double nu_ = 2;
  Eigen::SparseMatrix<double> sparse_;
  std::vector<Mat5, Eigen::aligned_allocator<Mat5>> precond_;
  std::unique_ptr<Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Upper>> cholmod_;
};

}  // namespace docunfold::isometry::internal
