#include "common/isometry/unfold.h"

#include <Eigen/SVD>
#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

namespace docunfold::isometry {

namespace {

// Each triangle of M isometrically in its own 2D frame, and the cotangent
// weights of its edges (edge k is opposite corner k).
struct LocalTriangles {
  std::vector<Triangle> tris;
  std::vector<std::array<Eigen::Vector2d, 3>> local;
  std::vector<Eigen::Vector3d> cot;
  double mean_cot = 0;
};

LocalTriangles MakeLocalTriangles(const QuadGrid& grid, const std::vector<Eigen::Vector3d>& x3,
                                  const std::vector<Eigen::Vector2d>& initial) {
  LocalTriangles lt;
  lt.tris = grid.Triangles();
  const std::vector<Triangle>& tris = lt.tris;
  const int nt = int(tris.size());

  // Orientation of the initial layout decides the handedness of the local
  // frames, so that rotations (det = +1) keep it.
  double signed_area = 0;
  for (const Triangle& t : tris) {
    const Eigen::Vector2d a = initial[t[1]] - initial[t[0]], b = initial[t[2]] - initial[t[0]];
    signed_area += a.x() * b.y() - a.y() * b.x();
  }
  const double handedness = signed_area >= 0 ? 1 : -1;

  std::vector<std::array<Eigen::Vector2d, 3>>& local = lt.local;
  std::vector<Eigen::Vector3d>& cot = lt.cot;
  local.resize(nt);
  cot.resize(nt);
  double mean_cot = 0;
  for (int i = 0; i < nt; ++i) {
    const Triangle& t = tris[i];
    const Eigen::Vector3d e1 = x3[t[1]] - x3[t[0]], e2 = x3[t[2]] - x3[t[0]];
    const double l1 = e1.norm();
    const Eigen::Vector3d u = l1 > 0 ? Eigen::Vector3d(e1 / l1) : Eigen::Vector3d::UnitX();
    const double px = e2.dot(u), py = (e2 - px * u).norm();
    local[i] = {Eigen::Vector2d(0, 0), Eigen::Vector2d(l1, 0),
                Eigen::Vector2d(px, handedness * py)};
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector2d a = local[i][(k + 1) % 3] - local[i][k];
      const Eigen::Vector2d b = local[i][(k + 2) % 3] - local[i][k];
      const double cross = std::abs(a.x() * b.y() - a.y() * b.x());
      cot[i][k] = cross > 0 ? a.dot(b) / cross : 0;
      mean_cot += std::abs(cot[i][k]);
    }
  }
  mean_cot /= 3.0 * nt;
  // Obtuse angles give negative weights; keep the Laplacian positive.
  for (auto& c : cot)
    for (int k = 0; k < 3; ++k) c[k] = std::max(c[k], 1e-3 * mean_cot);
  lt.mean_cot = mean_cot;
  return lt;
}

// The cotangent Laplacian with vertex 0 pinned (removes the translation).
Eigen::SparseMatrix<double> PinnedLaplacian(const LocalTriangles& lt, int n) {
  const std::vector<Triangle>& tris = lt.tris;
  const int nt = int(tris.size());
  std::vector<Eigen::Triplet<double>> trip;
  for (int i = 0; i < nt; ++i)
    for (int k = 0; k < 3; ++k) {
      const int a = tris[i][(k + 1) % 3], b = tris[i][(k + 2) % 3];
      const double w = lt.cot[i][k];
      trip.emplace_back(a, a, w);
      trip.emplace_back(b, b, w);
      trip.emplace_back(a, b, -w);
      trip.emplace_back(b, a, -w);
    }
  trip.emplace_back(0, 0, 1e6 * lt.mean_cot);
  Eigen::SparseMatrix<double> L(n, n);
  L.setFromTriplets(trip.begin(), trip.end());
  return L;
}

// The initial layout scaled to M's total edge length (into *u, from
// vertex 0); returns M's mean edge length.
double ScaledLayout(const QuadGrid& grid, const std::vector<Eigen::Vector3d>& x3,
                    const std::vector<Eigen::Vector2d>& initial, std::vector<Eigen::Vector2d>* u) {
  double len3 = 0, len2 = 0;
  for (int r = 0; r < grid.ny; ++r)
    for (int c = 0; c < grid.nx; ++c) {
      const int i = grid.Index(r, c);
      if (c + 1 < grid.nx) {
        len3 += (x3[i + 1] - x3[i]).norm();
        len2 += (initial[i + 1] - initial[i]).norm();
      }
      if (r + 1 < grid.ny) {
        len3 += (x3[i + grid.nx] - x3[i]).norm();
        len2 += (initial[i + grid.nx] - initial[i]).norm();
      }
    }
  if (!(len2 > 0) || !(len3 > 0)) throw std::invalid_argument("UnfoldArap: degenerate mesh");
  const int edges = grid.ny * (grid.nx - 1) + grid.nx * (grid.ny - 1);
  const double mean_edge = len3 / edges;
  for (const auto& p : initial) u->push_back((p - initial[0]) * (len3 / len2));
  return mean_edge;
}

// One local/global iteration: the closest rotation per triangle, then the
// layout solved for; returns the largest vertex move.
double ArapIteration(const LocalTriangles& lt,
                     const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>>& solver,
                     std::vector<Eigen::Matrix2d>& rot, Eigen::MatrixXd& rhs, Eigen::MatrixXd& sol,
                     std::vector<Eigen::Vector2d>& u) {
  const std::vector<Triangle>& tris = lt.tris;
  const auto& local = lt.local;
  const auto& cot = lt.cot;
  const int nt = int(tris.size()), n = int(u.size());
  // Local step: the closest rotation per triangle.
  for (int i = 0; i < nt; ++i) {
    Eigen::Matrix2d s = Eigen::Matrix2d::Zero();
    for (int k = 0; k < 3; ++k) {
      const int a = (k + 1) % 3, b = (k + 2) % 3;
      s += cot[i][k] * (u[tris[i][a]] - u[tris[i][b]]) * (local[i][a] - local[i][b]).transpose();
    }
    Eigen::JacobiSVD<Eigen::Matrix2d> svd(s, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Eigen::Matrix2d r = svd.matrixU() * svd.matrixV().transpose();
    if (r.determinant() < 0) {
      Eigen::Matrix2d uu = svd.matrixU();
      uu.col(1) *= -1;
      r = uu * svd.matrixV().transpose();
    }
    rot[i] = r;
  }
  // Global step.
  rhs.setZero();
  for (int i = 0; i < nt; ++i)
    for (int k = 0; k < 3; ++k) {
      const int a = (k + 1) % 3, b = (k + 2) % 3;
      const Eigen::Vector2d e = cot[i][k] * (rot[i] * (local[i][a] - local[i][b]));
      rhs.row(tris[i][a]) += e.transpose();
      rhs.row(tris[i][b]) -= e.transpose();
    }
  rhs.row(0) += 1e6 * lt.mean_cot * u[0].transpose();
  sol = solver.solve(rhs);
  double moved = 0;
  for (int v = 0; v < n; ++v) {
    const Eigen::Vector2d p = sol.row(v).transpose();
    moved = std::max(moved, (p - u[v]).norm());
    u[v] = p;
  }
  return moved;
}

}  // namespace

UnfoldResult UnfoldArap(const QuadGrid& grid, const std::vector<Eigen::Vector3d>& x3,
                        const std::vector<Eigen::Vector2d>& initial, const UnfoldOptions& options) {
  const int n = grid.NumVertices();
  if (int(x3.size()) != n || int(initial.size()) != n || n < 4)
    throw std::invalid_argument("UnfoldArap: sizes do not match the grid");
  const LocalTriangles lt = MakeLocalTriangles(grid, x3, initial);
  const int nt = int(lt.tris.size());
  const Eigen::SparseMatrix<double> L = PinnedLaplacian(lt, n);
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(L);
  if (solver.info() != Eigen::Success) throw std::runtime_error("UnfoldArap: factorisation failed");

  UnfoldResult result;
  const double mean_edge = ScaledLayout(grid, x3, initial, &result.mesh2d);
  Eigen::MatrixXd rhs(n, 2), sol(n, 2);
  std::vector<Eigen::Matrix2d> rot(nt);
  for (int it = 0; it < options.max_iterations; ++it) {
    const double moved = ArapIteration(lt, solver, rot, rhs, sol, result.mesh2d);
    result.iterations = it + 1;
    if (moved < options.tolerance * mean_edge) break;
  }
  return result;
}

}  // namespace docunfold::isometry
