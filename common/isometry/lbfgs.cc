// The L-BFGS step of the solver (LBFGS++) on V, V' and the line parameters,
// footpoints held fixed.
#include <LBFGS.h>

#include <cstdio>
#include <cstdlib>
#include <exception>

#include "common/isometry/solver_internal.h"

namespace docunfold::isometry::internal {
namespace {

class LbfgsObjective {
 public:
  LbfgsObjective(const State& s, const StepData& data, const Weights& w)
      : base_(s), data_(data), w_(w) {}

  static Eigen::VectorXd Pack(const State& s) {
    const int n = int(s.v3.size());
    Eigen::VectorXd x(5 * n + 2 * s.lines.size());
    for (int i = 0; i < n; ++i) {
      x.segment<3>(5 * i) = s.v3[i];
      x.segment<2>(5 * i + 3) = s.v2[i];
    }
    for (size_t l = 0; l < s.lines.size(); ++l) {
      x[5 * n + 2 * l] = s.lines[l].theta;
      x[5 * n + 2 * l + 1] = s.lines[l].offset;
    }
    return x;
  }
  void Unpack(const Eigen::VectorXd& x, State& s) const {
    const int n = int(s.v3.size());
    for (int i = 0; i < n; ++i) {
      s.v3[i] = x.segment<3>(5 * i);
      s.v2[i] = x.segment<2>(5 * i + 3);
    }
    for (size_t l = 0; l < s.lines.size(); ++l) {
      s.lines[l].theta = x[5 * n + 2 * l];
      s.lines[l].offset = x[5 * n + 2 * l + 1];
    }
  }

  double operator()(const Eigen::VectorXd& x, Eigen::VectorXd& grad) {
    State& s = scratch_;
    if (s.v3.empty()) s = base_;
    Unpack(x, s);
    grad.setZero(x.size());
    const int n = int(s.v3.size());
    double f = 0;
    ForEachRow(s, data_, [&](int term, const Row& r) {
      const double weight = WeightOf(w_, term);
      if (weight <= 0) return;
      f += weight * r.value * r.value;
      const double k = 2 * weight * r.value;
      for (int a = 0; a < r.count; ++a) grad.segment<5>(5 * r.vertex[a]) += k * r.d[a];
      if (r.line >= 0) {
        if (!s.lines[r.line].axis_aligned) grad[5 * n + 2 * r.line] += k * r.d_theta;
        grad[5 * n + 2 * r.line + 1] += k * r.d_offset;
      }
    });
    ++evaluations_;
    return f;
  }
  int evaluations() const { return evaluations_; }

 private:
  const State& base_;
  const StepData& data_;
  const Weights& w_;
  State scratch_;
  int evaluations_ = 0;
};

}  // namespace

bool LbfgsStep(State& s, const StepData& data, const Weights& w, const SolveOptions& o,
               int* iterations) {
  LBFGSpp::LBFGSParam<double> param;
  param.m = o.lbfgs_memory;
  param.max_iterations = o.lbfgs_iterations;
  param.epsilon = 1e-14;
  param.epsilon_rel = 0;
  param.max_linesearch = 40;
  param.linesearch = LBFGSpp::LBFGS_LINESEARCH_BACKTRACKING_STRONG_WOLFE;
  LBFGSpp::LBFGSSolver<double, LBFGSpp::LineSearchNocedalWright> solver(param);
  LbfgsObjective objective(s, data, w);
  Eigen::VectorXd x = LbfgsObjective::Pack(s), best = x;
  Eigen::VectorXd grad;
  const double f0 = objective(x, grad);
  double fx = f0;
  try {
    *iterations = solver.minimize(objective, x, fx);
    best = x;
  } catch (const std::exception& e) {
    if (std::getenv("DOCUNFOLD_DEBUG_LBFGS")) fprintf(stderr, "lbfgs: %s\n", e.what());
    // Line search failures near the optimum: keep the best point seen, if any.
    Eigen::VectorXd g2;
    fx = x.allFinite() ? objective(x, g2) : f0;
    if (fx < f0) best = x;
    *iterations = o.lbfgs_iterations;
  }
  if (!(fx < f0)) return false;
  objective.Unpack(best, s);
  return true;
}

}  // namespace docunfold::isometry::internal
