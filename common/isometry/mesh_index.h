// Spatial queries on the triangulated grid: closest point of a 3D point on M
// (footpoints for E_dist, distances for outliers and tests) and the triangle
// of M' containing a 2D point (feature line projection). A k-d tree over
// triangle centroids (common/point_index.h) narrows the search; results are
// exact.
#pragma once

#include <Eigen/Core>
#include <limits>
#include <memory>
#include <optional>
#include <vector>

#include "common/grid_mesh.h"
#include "common/point_index.h"
#include "common/raster.h"

namespace docunfold::isometry {

struct ClosestPoint {
  int triangle = -1;
  Eigen::Vector3d bary = Eigen::Vector3d::Zero();  // of the triangle's corners
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  double distance = std::numeric_limits<double>::infinity();
};

// Closest point of triangle (a, b, c) to p, with barycentrics.
ClosestPoint ClosestPointOnTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                    const Eigen::Vector3d& b, const Eigen::Vector3d& c);

class TriangleMeshIndex {
 public:
  TriangleMeshIndex(const std::vector<Eigen::Vector3d>& vertices,
                    const std::vector<Triangle>& triangles);
  ~TriangleMeshIndex();
  TriangleMeshIndex(const TriangleMeshIndex&) = delete;
  TriangleMeshIndex& operator=(const TriangleMeshIndex&) = delete;

  // The exact closest point on the mesh, or nullopt when the mesh is
  // certainly farther than max_distance (cheap rejection of outliers).
  std::optional<ClosestPoint> Closest(
      const Eigen::Vector3d& p,
      double max_distance = std::numeric_limits<double>::infinity()) const;

 private:
  std::vector<Eigen::Vector3d> vertices_;
  std::vector<Triangle> triangles_;
  double max_radius_ = 0;               // largest centroid-to-corner distance
  std::unique_ptr<PointIndex3d> tree_;  // of the triangles' centroids
};

// Point location in the flat mesh M' (triangles of the grid, see
// QuadGrid::Triangles): the triangle containing p and barycentrics, or
// nullopt when p is outside M'.
class FlatMeshLocator {
 public:
  explicit FlatMeshLocator(const MeshPair& meshes);
  ~FlatMeshLocator();
  FlatMeshLocator(const FlatMeshLocator&) = delete;
  FlatMeshLocator& operator=(const FlatMeshLocator&) = delete;
  std::optional<SurfacePoint> Locate(const Eigen::Vector2d& p) const;

 private:
  std::vector<Eigen::Vector2d> vertices_;
  std::vector<Triangle> triangles_;
  double max_radius_ = 0;
  std::unique_ptr<PointIndex2d> tree_;  // of the triangles' centroids
};

}  // namespace docunfold::isometry
