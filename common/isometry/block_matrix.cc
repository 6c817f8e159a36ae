#include "common/isometry/block_matrix.h"

#include <algorithm>
#include <stdexcept>

namespace docunfold::isometry::internal {

GridBlockMatrix::GridBlockMatrix(const QuadGrid& grid) : grid_(grid), n_(grid.NumVertices()) {
  neighbour_.assign(size_t(n_) * kSlots, -1);
  for (int r = 0; r < grid.ny; ++r)
    for (int c = 0; c < grid.nx; ++c)
      for (int k = 0; k < kSlots; ++k) {
        const int rr = r + kOffsets[k][0], cc = c + kOffsets[k][1];
        if (rr < grid.ny && cc >= 0 && cc < grid.nx)
          neighbour_[size_t(grid.Index(r, c)) * kSlots + k] = grid.Index(rr, cc);
      }
  blocks_.resize(size_t(n_) * kSlots);
  lower_.resize(n_);
  for (auto& l : lower_) l.fill(-1);
  std::vector<int> count(n_, 0);
  for (int j = 0; j < n_; ++j)
    for (int k = 1; k < kSlots; ++k) {
      const int i = Neighbour(j, k);
      if (i < 0) continue;
      lower_[i][2 * count[i]] = j;
      lower_[i][2 * count[i] + 1] = k;
      ++count[i];
    }
  SetZero();
}

void GridBlockMatrix::SetZero() {
  for (Mat5& b : blocks_) b.setZero();
}

void GridBlockMatrix::NotNeighbours(int vi, int vj) {
  throw std::logic_error("GridBlockMatrix: vertices " + std::to_string(vi) + " and " +
                         std::to_string(vj) + " are not grid neighbours");
}

void GridBlockMatrix::Multiply(const Eigen::VectorXd& x, Eigen::VectorXd& y, int threads) const {
  y.resize(5 * n_);
  // Row by row (upper blocks of row i, transposed upper blocks of the rows
  // above that reach i): no two threads write the same entry.
#pragma omp parallel for num_threads(threads) \
    schedule(static) if (threads > 1 && n_ >= kMinParallelVertices)
  for (int i = 0; i < n_; ++i) {
    Vec5d acc = Block(i, 0) * x.segment<5>(5 * i);
    for (int k = 1; k < kSlots; ++k) {
      const int j = Neighbour(i, k);
      if (j >= 0) acc.noalias() += Block(i, k) * x.segment<5>(5 * j);
    }
    const auto& lower = lower_[i];
    for (int e = 0; e < 2 * kSlots && lower[e] >= 0; e += 2)
      acc.noalias() += Block(lower[e], lower[e + 1]).transpose() * x.segment<5>(5 * lower[e]);
    y.segment<5>(5 * i) = acc;
  }
}

Eigen::VectorXd GridBlockMatrix::Diagonal() const {
  Eigen::VectorXd d(5 * n_);
  for (int i = 0; i < n_; ++i) d.segment<5>(5 * i) = Block(i, 0).diagonal();
  return d;
}

void GridBlockMatrix::ToSparseUpper(Eigen::SparseMatrix<double>& out,
                                    const Eigen::VectorXd& shift) const {
  const int dofs = 5 * n_;
  // Upper neighbours i < j of each column vertex j, ascending.
  auto column_neighbours = [&](int j, std::array<std::pair<int, int>, kSlots>& list) {
    int count = 0;
    const int r = j / grid_.nx, c = j % grid_.nx;
    for (int k = 1; k < kSlots; ++k) {
      const int rr = r - kOffsets[k][0], cc = c - kOffsets[k][1];
      if (rr < 0 || cc < 0 || cc >= grid_.nx) continue;
      const int i = grid_.Index(rr, cc);
      if (Neighbour(i, k) == j) list[count++] = {i, k};
    }
    std::sort(list.begin(), list.begin() + count);
    return count;
  };
  std::array<std::pair<int, int>, kSlots> list;
  const bool have_pattern =
      out.rows() == dofs && out.cols() == dofs && out.isCompressed() && out.nonZeros() > 0;
  if (!have_pattern) {
    std::vector<int> outer(dofs + 1, 0);
    std::vector<int> inner;
    for (int j = 0; j < n_; ++j) {
      const int count = column_neighbours(j, list);
      for (int b = 0; b < 5; ++b) {
        for (int e = 0; e < count; ++e)
          for (int a = 0; a < 5; ++a) inner.push_back(5 * list[e].first + a);
        for (int a = 0; a <= b; ++a) inner.push_back(5 * j + a);
        outer[5 * j + b + 1] = int(inner.size());
      }
    }
    out.resize(dofs, dofs);
    out.resizeNonZeros(Eigen::Index(inner.size()));
    std::copy(outer.begin(), outer.end(), out.outerIndexPtr());
    std::copy(inner.begin(), inner.end(), out.innerIndexPtr());
  }
  double* value = out.valuePtr();
  for (int j = 0; j < n_; ++j) {
    const int count = column_neighbours(j, list);
    for (int b = 0; b < 5; ++b) {
      for (int e = 0; e < count; ++e) {
        const Mat5& blk = Block(list[e].first, list[e].second);
        for (int a = 0; a < 5; ++a) *value++ = blk(a, b);
      }
      const Mat5& diag = Block(j, 0);
      for (int a = 0; a < b; ++a) *value++ = diag(a, b);
      *value++ = diag(b, b) + shift[5 * j + b];
    }
  }
}

}  // namespace docunfold::isometry::internal
