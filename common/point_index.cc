#include "common/point_index.h"

#include <cstdint>
#include <nanoflann.hpp>

namespace docunfold {

template <int Dim>
struct KdTree<Dim>::Tree {
  struct Cloud {
    const std::vector<Point>* points;
    size_t kdtree_get_point_count() const { return points->size(); }
    double kdtree_get_pt(size_t i, size_t d) const { return (*points)[i][int(d)]; }
    template <class Box>
    bool kdtree_get_bbox(Box&) const {
      return false;
    }
  };
  using Index = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, Cloud>,
                                                    Cloud, Dim, uint32_t>;
  Tree(const std::vector<Point>* points, int leaf_size)
      : cloud{points}, index(Dim, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(leaf_size)) {
    index.buildIndex();
  }
  Cloud cloud;
  Index index;
};

template <int Dim>
KdTree<Dim>::KdTree(std::vector<Point> points, int leaf_size)
    : points_(std::move(points)), tree_(std::make_unique<Tree>(&points_, leaf_size)) {}

template <int Dim>
KdTree<Dim>::~KdTree() = default;

template <int Dim>
std::vector<typename KdTree<Dim>::Neighbour> KdTree<Dim>::Nearest(const Point& query, int k) const {
  std::vector<Neighbour> out;
  const size_t n = std::min<size_t>(size_t(std::max(k, 0)), points_.size());
  if (n == 0) return out;
  std::vector<uint32_t> idx(n);
  std::vector<double> d2(n);
  nanoflann::KNNResultSet<double, uint32_t> knn(n);
  knn.init(idx.data(), d2.data());
  tree_->index.findNeighbors(knn, query.data(), nanoflann::SearchParams());
  out.reserve(knn.size());
  for (size_t i = 0; i < knn.size(); ++i) out.emplace_back(int(idx[i]), d2[i]);
  return out;
}

template <int Dim>
std::vector<typename KdTree<Dim>::Neighbour> KdTree<Dim>::WithinSquaredRadius(
    const Point& query, double squared_radius) const {
  std::vector<std::pair<uint32_t, double>> matches;
  if (!points_.empty())
    tree_->index.radiusSearch(query.data(), squared_radius, matches, nanoflann::SearchParams());
  std::vector<Neighbour> out;
  out.reserve(matches.size());
  for (const auto& m : matches) out.emplace_back(int(m.first), m.second);
  return out;
}

template class KdTree<2>;
template class KdTree<3>;

}  // namespace docunfold
