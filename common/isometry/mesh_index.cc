#include "common/isometry/mesh_index.h"

#include <algorithm>
#include <cmath>

namespace docunfold::isometry {

// Ericson, Real-Time Collision Detection, 5.1.5, with barycentrics kept.
ClosestPoint ClosestPointOnTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                    const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  ClosestPoint r;
  auto finish = [&](double u, double v, double w) {
    r.bary = Eigen::Vector3d(u, v, w);
    r.point = u * a + v * b + w * c;
    r.distance = (p - r.point).norm();
    return r;
  };
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return finish(1, 0, 0);
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return finish(0, 1, 0);
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double v = d1 / (d1 - d3);
    return finish(1 - v, v, 0);
  }
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return finish(0, 0, 1);
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double w = d2 / (d2 - d6);
    return finish(1 - w, 0, w);
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return finish(0, 1 - w, w);
  }
  const double denom = va + vb + vc;
  if (!(std::abs(denom) > 0)) return finish(1, 0, 0);  // degenerate triangle
  const double v = vb / denom, w = vc / denom;
  return finish(1 - v - w, v, w);
}

TriangleMeshIndex::TriangleMeshIndex(const std::vector<Eigen::Vector3d>& vertices,
                                     const std::vector<Triangle>& triangles)
    : vertices_(vertices), triangles_(triangles) {
  std::vector<Eigen::Vector3d> centroids;
  centroids.reserve(triangles_.size());
  for (const Triangle& t : triangles_) {
    const Eigen::Vector3d g = (vertices_[t[0]] + vertices_[t[1]] + vertices_[t[2]]) / 3;
    centroids.push_back(g);
    for (int k = 0; k < 3; ++k) max_radius_ = std::max(max_radius_, (vertices_[t[k]] - g).norm());
  }
  tree_ = std::make_unique<PointIndex3d>(std::move(centroids));
}

TriangleMeshIndex::~TriangleMeshIndex() = default;

std::optional<ClosestPoint> TriangleMeshIndex::Closest(const Eigen::Vector3d& p,
                                                       double max_distance) const {
  if (triangles_.empty()) return std::nullopt;
  auto exact = [&](int t) {
    const Triangle& tri = triangles_[t];
    ClosestPoint c =
        ClosestPointOnTriangle(p, vertices_[tri[0]], vertices_[tri[1]], vertices_[tri[2]]);
    c.triangle = t;
    return c;
  };
  // A few nearest centroids give an upper bound on the distance.
  const std::vector<PointIndex3d::Neighbour> nearest = tree_->Nearest(p, 6);
  // Any triangle is at least (centroid distance - max_radius) away.
  if (std::sqrt(nearest[0].second) - max_radius_ > max_distance) return std::nullopt;
  ClosestPoint best;
  for (const auto& [t, dist2] : nearest) {
    ClosestPoint c = exact(t);
    if (c.distance < best.distance) best = c;
  }
  const double bound = std::min(best.distance, max_distance);
  const double radius = bound + max_radius_;
  auto among_nearest = [&](int t) {
    return std::any_of(nearest.begin(), nearest.end(), [t](const auto& n) { return n.first == t; });
  };
  for (const auto& [t, dist2] : tree_->WithinSquaredRadius(p, radius * radius)) {
    if (std::sqrt(dist2) - max_radius_ > std::min(best.distance, max_distance)) break;
    // Those are in `best` already (a tie keeps the first found).
    if (among_nearest(t)) continue;
    ClosestPoint c = exact(t);
    if (c.distance < best.distance) best = c;
  }
  if (best.distance > max_distance) return std::nullopt;
  return best;
}

FlatMeshLocator::FlatMeshLocator(const MeshPair& meshes)
    : vertices_(meshes.mesh2d), triangles_(meshes.grid.Triangles()) {
  std::vector<Eigen::Vector2d> centroids;
  centroids.reserve(triangles_.size());
  for (const Triangle& t : triangles_) {
    const Eigen::Vector2d g = (vertices_[t[0]] + vertices_[t[1]] + vertices_[t[2]]) / 3;
    centroids.push_back(g);
    for (int k = 0; k < 3; ++k) max_radius_ = std::max(max_radius_, (vertices_[t[k]] - g).norm());
  }
  tree_ = std::make_unique<PointIndex2d>(std::move(centroids));
}

FlatMeshLocator::~FlatMeshLocator() = default;

std::optional<SurfacePoint> FlatMeshLocator::Locate(const Eigen::Vector2d& p) const {
  if (triangles_.empty()) return std::nullopt;
  const double r = max_radius_ * (1 + 1e-9);
  const std::vector<PointIndex2d::Neighbour> matches = tree_->WithinSquaredRadius(p, r * r);
  std::optional<SurfacePoint> best;
  double best_violation = std::numeric_limits<double>::infinity();
  for (const auto& match : matches) {
    const Triangle& t = triangles_[match.first];
    const Eigen::Vector2d a = vertices_[t[0]], b = vertices_[t[1]], c = vertices_[t[2]];
    Eigen::Matrix2d A;
    A << b - a, c - a;
    const double det = A.determinant();
    if (!(std::abs(det) > 0)) continue;
    const Eigen::Vector2d uv = A.inverse() * (p - a);
    const Eigen::Vector3d bary(1 - uv.x() - uv.y(), uv.x(), uv.y());
    // Most negative barycentric: 0 inside; tiny negatives on shared edges.
    const double violation = -std::min(0.0, bary.minCoeff());
    if (violation < best_violation) {
      best_violation = violation;
      best = SurfacePoint{match.first, bary};
      if (violation == 0) break;
    }
  }
  if (!best || best_violation > 1e-9) return std::nullopt;
  return best;
}

}  // namespace docunfold::isometry
