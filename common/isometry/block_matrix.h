// Internal to docunfold_isometry: the Gauss-Newton matrix JᵀJ of F on a
// structured grid, stored as 5x5 blocks (x, y, z, x', y' of a vertex) for
// the vertex pairs that any row of F can couple: the vertex itself, its quad
// neighbours and the vertices two steps along its grid row and column
// (fairness). Only the upper half (j >= i) is stored: 7 blocks per vertex.
#pragma once

#include <Eigen/Core>
#include <Eigen/Sparse>
#include <array>
#include <vector>

#include "common/grid_mesh.h"

namespace docunfold::isometry::internal {

// Grids of at least this many vertices (or quads) are worth a parallel loop:
// the coarsest round's 651 vertices run a conjugate-gradient iteration in
// ~45 us on two threads against ~60 us on one. Threads never change a result.
constexpr int kMinParallelVertices = 300;

using Mat5 = Eigen::Matrix<double, 5, 5>;
using Vec5d = Eigen::Matrix<double, 5, 1>;

class GridBlockMatrix {
 public:
  // (row offset, column offset) of the 7 stored neighbours j >= i.
  static constexpr int kSlots = 7;
  static constexpr std::array<std::array<int, 2>, kSlots> kOffsets = {
      {{0, 0}, {0, 1}, {0, 2}, {1, -1}, {1, 0}, {1, 1}, {2, 0}}};

  explicit GridBlockMatrix(const QuadGrid& grid);
  const QuadGrid& grid() const { return grid_; }
  int NumVertices() const { return n_; }

  void SetZero();
  // Neighbour of vertex i in slot k, or -1 outside the grid.
  int Neighbour(int i, int k) const { return neighbour_[size_t(i) * kSlots + k]; }
  Mat5& Block(int i, int k) { return blocks_[size_t(i) * kSlots + k]; }
  const Mat5& Block(int i, int k) const { return blocks_[size_t(i) * kSlots + k]; }
  // Adds a·bᵀ to the block (vi, vj) of the full symmetric matrix (either
  // order; vi == vj allowed). Throws if the pair is not a stored neighbour.
  void AddOuter(int vi, const Vec5d& a, int vj, const Vec5d& b) {
    if (vi <= vj)
      Block(vi, Slot(vi, vj)).noalias() += a * b.transpose();
    else
      Block(vj, Slot(vj, vi)).noalias() += b * a.transpose();
  }

  // y = A x for the full symmetric matrix (x, y of size 5n), on `threads`.
  void Multiply(const Eigen::VectorXd& x, Eigen::VectorXd& y, int threads = 1) const;
  // Diagonal of the full matrix.
  Eigen::VectorXd Diagonal() const;

  // Upper triangle in compressed column form; the pattern depends only on
  // the grid, so a solver's symbolic analysis can be reused. `shift` is
  // added to the diagonal.
  void ToSparseUpper(Eigen::SparseMatrix<double>& out, const Eigen::VectorXd& shift) const;

 private:
  // The slot of (vi, vj), vi <= vj; in the header, because assembly calls it
  // for every pair of every row.
  int Slot(int vi, int vj) const {
    const int d = vj - vi, nx = grid_.nx;
    if (d == 0) return 0;
    // Only these two need no column test (no other slot's offset can equal
    // them where its column test passes).
    if (d == nx) return 4;
    if (d == 2 * nx) return 6;
    const int c = vi % nx;
    if (d == 1 && c + 1 < nx) return 1;
    if (d == 2 && c + 2 < nx) return 2;
    if (d == nx - 1 && c > 0) return 3;
    if (d == nx + 1 && c + 1 < nx) return 5;
    NotNeighbours(vi, vj);
  }
  [[noreturn]] static void NotNeighbours(int vi, int vj);
  QuadGrid grid_;
  int n_ = 0;
  std::vector<int> neighbour_;
  // For each vertex i, the stored blocks (j, k) with Neighbour(j, k) == i and
  // j < i (the lower half of row i), -1 terminated.
  std::vector<std::array<int, 2 * kSlots>> lower_;
  std::vector<Mat5, Eigen::aligned_allocator<Mat5>> blocks_;
};

}  // namespace docunfold::isometry::internal
