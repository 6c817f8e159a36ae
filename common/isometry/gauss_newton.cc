// The Gauss-Newton/Levenberg-Marquardt step of the solver.
#include "common/isometry/gauss_newton.h"

#include <Eigen/Cholesky>
#include <cmath>

#ifdef _OPENMP
#include <omp.h>
#endif

namespace docunfold::isometry::internal {
namespace {

// Applies a step δ (5 unknowns per vertex).
State Moved(const State& s, const Eigen::VectorXd& delta) {
  State t = s;
  for (size_t i = 0; i < t.v3.size(); ++i) {
    t.v3[i] += delta.segment<3>(5 * i);
    t.v2[i] += delta.segment<2>(5 * i + 3);
  }
  return t;
}

}  // namespace

GaussNewton::GaussNewton(const QuadGrid& grid, const SolveOptions& o)
    : o_(o),
      H_(grid),
      threads_(std::max(1, o.num_threads)),
      cg_tolerance_(o.cg_tolerance),
      cg_max_iterations_(o.cg_max_iterations) {
  direct_ = o.linear_solver == LinearSolver::kDirect;
  if (o.linear_solver == LinearSolver::kAuto && grid.NumVertices() <= o.coarse_max_vertices) {
    cg_tolerance_ = o.coarse_cg_tolerance;
    cg_max_iterations_ = o.coarse_cg_max_iterations;
  }
  mu_ = o.initial_damping;
}

bool GaussNewton::Step(State& s, const StepData& data, const Weights& w, int* linear_iterations) {
  const int n = s.grid.NumVertices();
  Eigen::VectorXd g = Eigen::VectorXd::Zero(5 * n);
  const double f0 = Assemble(s, data, w, g);
  Eigen::VectorXd scale = H_.Diagonal();
  const double floor = 1e-12 * std::max(1e-300, scale.maxCoeff());
  for (int i = 0; i < scale.size(); ++i) scale[i] = std::max(scale[i], floor);
  *linear_iterations = 0;
  for (int attempt = 0; attempt < 12; ++attempt) {
    Eigen::VectorXd delta;
    const Eigen::VectorXd shift = mu_ * scale;
    const bool solved = direct_ ? SolveDirect(shift, g, delta, linear_iterations)
                                : SolveCg(shift, g, delta, linear_iterations);
    if (!solved) {
      mu_ = std::max(mu_ * 10, 1e-8);
      continue;
    }
    Eigen::VectorXd Hd;
    H_.Multiply(delta, Hd, threads_);
    const double predicted = -(2 * delta.dot(g) + delta.dot(Hd));
    State trial = Moved(s, delta);
    const double f1 = SurrogateF(trial, data, w, threads_);
    if (f1 < f0 && predicted > 0) {
      const double rho = (f0 - f1) / predicted;
      s = std::move(trial);
      mu_ *= std::max(1.0 / 3, 1 - std::pow(2 * rho - 1, 3));
      mu_ = std::max(mu_, 1e-12);
      nu_ = 2;
      return true;
    }
    mu_ *= nu_;
    nu_ *= 2;
  }
  return false;
}

double GaussNewton::Assemble(const State& s, const StepData& data, const Weights& w,
                             Eigen::VectorXd& g) {
  H_.SetZero();
  const QuadGrid& grid = s.grid;
  const bool parallel = threads_ > 1 && grid.NumVertices() >= kMinParallelVertices;
  auto add = [&](double weight, const Row& r) {
    const double k = std::sqrt(weight);
    const double value = k * r.value;
    Vec5 da[4];
    for (int a = 0; a < r.count; ++a) da[a] = k * r.d[a];
    for (int a = 0; a < r.count; ++a) {
      g.segment<5>(5 * r.vertex[a]) += da[a] * value;
      for (int b = a; b < r.count; ++b) H_.AddOuter(r.vertex[a], da[a], r.vertex[b], da[b]);
    }
    return value * value;
  };
  double f = 0;
  // Per grid row or line, then added in order: F does not depend on the
  // number of threads (see kSumChunk).
  std::vector<double> part(size_t(std::max(grid.nx, grid.ny)), 0.0);
  if (w.iso > 0)
    for (int colour = 0; colour < 4; ++colour) {
      const int r0 = colour / 2, c0 = colour % 2;
#pragma omp parallel for num_threads(threads_) schedule(static) if (parallel)
      for (int r = r0; r < grid.ny - 1; r += 2) {
        Row rows[kMaxRowsPerItem];
        double sum = 0;
        for (int c = c0; c < grid.nx - 1; c += 2) {
          const int q = r * (grid.nx - 1) + c;
          const int m = IsoRows(s, data, q, rows);
          for (int i = 0; i < m; ++i) sum += add(w.iso, rows[i]);
        }
        part[size_t(r)] = sum;
      }
      for (int r = r0; r < grid.ny - 1; r += 2) f += part[size_t(r)];
    }
  // Fairness: triplets along rows come first, then along columns (see
  // FairTriplet); centres three apart along the line share no vertex.
  const int along_rows = std::max(0, grid.ny * (grid.nx - 2));
  const int along_cols = std::max(0, grid.nx * (grid.ny - 2));
  for (int phase = 0; phase < 2; ++phase) {
    const int lines = phase == 0 ? grid.ny : grid.nx;
    const int per_line = phase == 0 ? grid.nx - 2 : grid.ny - 2;
    if (per_line <= 0 || (w.fair3d <= 0 && w.fair2d <= 0)) continue;
    for (int colour = 0; colour < 3; ++colour) {
#pragma omp parallel for num_threads(threads_) schedule(static) if (parallel)
      for (int l = 0; l < lines; ++l) {
        Row rows[3];
        double sum = 0;
        for (int k = colour; k < per_line; k += 3) {
          const int t = (phase == 0 ? 0 : along_rows) + l * per_line + k;
          if (w.fair3d > 0) {
            const int m = FairRows(s, data, t, false, rows);
            for (int i = 0; i < m; ++i) sum += add(w.fair3d, rows[i]);
          }
          if (w.fair2d > 0) {
            const int m = FairRows(s, data, t, true, rows);
            for (int i = 0; i < m; ++i) sum += add(w.fair2d, rows[i]);
          }
        }
        part[size_t(l)] = sum;
      }
      for (int l = 0; l < lines; ++l) f += part[size_t(l)];
    }
  }
  (void)along_cols;
  Row rows[4];
  if (w.dist > 0)
    for (int p = 0; p < int(data.points.size()); ++p) {
      const int m = DistRows(s, data, p, rows);
      for (int i = 0; i < m; ++i) f += add(w.dist, rows[i]);
    }
  for (int mk = 0; mk < int(data.markers.size()); ++mk) {
    if (w.line > 0) {
      const int m = LineRows(s, data, mk, rows);
      for (int i = 0; i < m; ++i) f += add(w.line, rows[i]);
    }
    if (w.ray > 0) {
      const int m = RayRows(s, data, mk, rows);
      for (int i = 0; i < m; ++i) f += add(w.ray, rows[i]);
    }
  }
  return f;
}

bool GaussNewton::SolveDirect(const Eigen::VectorXd& shift, const Eigen::VectorXd& g,
                              Eigen::VectorXd& delta, int* iterations) {
  H_.ToSparseUpper(sparse_, shift);
  if (!cholmod_) {
    cholmod_ =
        std::make_unique<Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Upper>>();
    cholmod_->analyzePattern(sparse_);
  }
  cholmod_->factorize(sparse_);
  ++*iterations;
  if (cholmod_->info() != Eigen::Success) return false;
  delta = cholmod_->solve(-g);
  return cholmod_->info() == Eigen::Success && delta.allFinite();
}

bool GaussNewton::SolveCg(const Eigen::VectorXd& shift, const Eigen::VectorXd& g,
                          Eigen::VectorXd& delta, int* iterations) {
  const int n = H_.NumVertices();
  const bool parallel = threads_ > 1 && n >= kMinParallelVertices;
  precond_.resize(n);
  bool ok = true;
#pragma omp parallel for num_threads(threads_) schedule(static) reduction(&& : ok) if (parallel)
  for (int i = 0; i < n; ++i) {
    Mat5 d = H_.Block(i, 0);
    d.diagonal() += shift.segment<5>(5 * i);
    Eigen::LLT<Mat5> llt(d);
    if (llt.info() != Eigen::Success) {
      ok = false;
      continue;
    }
    precond_[i] = llt.solve(Mat5::Identity());
  }
  if (!ok) return false;
  auto apply_precond = [&](const Eigen::VectorXd& r, Eigen::VectorXd& z) {
    z.resize(r.size());
#pragma omp parallel for num_threads(threads_) schedule(static) if (parallel)
    for (int i = 0; i < n; ++i) z.segment<5>(5 * i).noalias() = precond_[i] * r.segment<5>(5 * i);
  };
  auto apply_a = [&](const Eigen::VectorXd& x, Eigen::VectorXd& y) {
    H_.Multiply(x, y, threads_);
    y += shift.cwiseProduct(x);
  };
  delta = Eigen::VectorXd::Zero(g.size());
  Eigen::VectorXd r = -g, z, p, ap;
  const double b_norm = r.norm();
  if (!(b_norm > 0)) return true;
  apply_precond(r, z);
  p = z;
  double rz = r.dot(z);
  for (int it = 0; it < cg_max_iterations_; ++it) {
    apply_a(p, ap);
    const double pap = p.dot(ap);
    if (!(pap > 0)) break;
    const double alpha = rz / pap;
    delta += alpha * p;
    r -= alpha * ap;
    ++*iterations;
    if (r.norm() <= cg_tolerance_ * b_norm) break;
    apply_precond(r, z);
    const double rz_new = r.dot(z);
    p = z + (rz_new / rz) * p;
    rz = rz_new;
  }
  return delta.allFinite();
}

}  // namespace docunfold::isometry::internal
