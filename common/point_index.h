// Nearest neighbours among 2D points (pixels), a k-d tree (nanoflann).
#pragma once

#include <Eigen/Core>
#include <memory>
#include <utility>
#include <vector>

namespace docunfold {

class PointIndex2d {
 public:
  explicit PointIndex2d(std::vector<Eigen::Vector2d> points);
  ~PointIndex2d();
  PointIndex2d(const PointIndex2d&) = delete;
  PointIndex2d& operator=(const PointIndex2d&) = delete;

  // The `k` points nearest to `query` (fewer when there are fewer), nearest
  // first: (index, squared distance).
  std::vector<std::pair<int, double>> Nearest(const Eigen::Vector2d& query, int k) const;
  const std::vector<Eigen::Vector2d>& points() const { return points_; }

 private:
  struct Tree;
  std::vector<Eigen::Vector2d> points_;
  std::unique_ptr<Tree> tree_;
};

}  // namespace docunfold
