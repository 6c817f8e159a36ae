// Nearest neighbours among points in 2 or 3 dimensions: a k-d tree
// (nanoflann) over a copy of the points. Every stage's neighbour search goes
// through it.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <utility>
#include <vector>

namespace docunfold {

template <int Dim>
class KdTree {
 public:
  using Point = Eigen::Matrix<double, Dim, 1>;
  // (index into points(), squared distance)
  using Neighbour = std::pair<int, double>;

  // `leaf_size`: points per leaf of the tree (speed only; the neighbours
  // found are the same).
  explicit KdTree(std::vector<Point> points, int leaf_size = 10);
  ~KdTree();
  KdTree(const KdTree&) = delete;
  KdTree& operator=(const KdTree&) = delete;

  // The `k` points nearest to `query` (fewer when there are fewer), nearest
  // first.
  std::vector<Neighbour> Nearest(const Point& query, int k) const;
  // Every point whose squared distance to `query` is below
  // `squared_radius`, nearest first.
  std::vector<Neighbour> WithinSquaredRadius(const Point& query, double squared_radius) const;

  const std::vector<Point>& points() const { return points_; }
  size_t size() const { return points_.size(); }

 private:
  struct Tree;
  std::vector<Point> points_;
  std::unique_ptr<Tree> tree_;
};

using PointIndex2d = KdTree<2>;
using PointIndex3d = KdTree<3>;

extern template class KdTree<2>;
extern template class KdTree<3>;

}  // namespace docunfold
