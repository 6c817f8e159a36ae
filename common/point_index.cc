#include "common/point_index.h"

#include <cstdint>
#include <nanoflann.hpp>

namespace docunfold {

struct PointIndex2d::Tree {
  struct Cloud {
    const std::vector<Eigen::Vector2d>* points;
    size_t kdtree_get_point_count() const { return points->size(); }
    double kdtree_get_pt(size_t i, size_t d) const { return (*points)[i][int(d)]; }
    template <class Box>
    bool kdtree_get_bbox(Box&) const {
      return false;
    }
  };
  using Index = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, Cloud>,
                                                    Cloud, 2, uint32_t>;
  explicit Tree(const std::vector<Eigen::Vector2d>* points)
      : cloud{points}, index(2, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(10)) {
    index.buildIndex();
  }
  Cloud cloud;
  Index index;
};

PointIndex2d::PointIndex2d(std::vector<Eigen::Vector2d> points)
    : points_(std::move(points)), tree_(std::make_unique<Tree>(&points_)) {}

PointIndex2d::~PointIndex2d() = default;

std::vector<std::pair<int, double>> PointIndex2d::Nearest(const Eigen::Vector2d& query,
                                                          int k) const {
  std::vector<std::pair<int, double>> out;
  const size_t n = std::min<size_t>(size_t(std::max(k, 0)), points_.size());
  if (n == 0) return out;
  std::vector<uint32_t> idx(n);
  std::vector<double> d2(n);
  nanoflann::KNNResultSet<double, uint32_t> knn(n);
  knn.init(idx.data(), d2.data());
  tree_->index.findNeighbors(knn, query.data(), nanoflann::SearchParams());
  for (size_t i = 0; i < knn.size(); ++i) out.emplace_back(int(idx[i]), d2[i]);
  return out;
}

}  // namespace docunfold
