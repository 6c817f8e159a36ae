// What each outer iteration of the solver re-decides before its step:
// footpoints and outliers, the lines' parameters, the markers' projection.
#include <Eigen/Eigenvalues>
#include <cmath>
#include <limits>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "common/isometry/mesh_index.h"
#include "common/isometry/solver_internal.h"

namespace docunfold::isometry::internal {

// θ of an axis-aligned line: the nearest multiple of 90 degrees.
double NearestAxisTheta(double theta) {
  constexpr double kHalfPi = 1.57079632679489661923;
  return kHalfPi * std::round(theta / kHalfPi);
}

// Footpoints of every target point on M, and the outlier decision.
void UpdateFootpoints(const State& s, StepData& data, double phi, int threads) {
  if (data.points.empty()) {
    data.num_inliers = 0;
    return;
  }
  const std::vector<Triangle> triangles = s.grid.Triangles();
  TriangleMeshIndex index(s.v3, triangles);
  const double max_distance = phi > 0 ? phi : std::numeric_limits<double>::infinity();
  const int n = int(data.points.size());
  int inliers = 0;
#pragma omp parallel for num_threads(threads) reduction(+ : inliers) schedule(dynamic, 256) if (threads > 1 && n > 2000)
  for (int i = 0; i < n; ++i) {
    Footpoint& f = data.footpoints[i];
    const auto c = index.Closest(data.points[i], max_distance);
    if (!c) {
      f.inlier = false;
      f.distance = std::numeric_limits<double>::infinity();
      continue;
    }
    f.triangle = c->triangle;
    f.bary = c->bary;
    f.distance = c->distance;
    const Triangle& t = triangles[c->triangle];
    const Eigen::Vector3d normal = (s.v3[t[1]] - s.v3[t[0]]).cross(s.v3[t[2]] - s.v3[t[0]]);
    if (normal.norm() > 0) f.normal = normal.normalized();
    f.inlier = true;
    ++inliers;
  }
  data.num_inliers = inliers;
}

Eigen::Vector2d FlatPoint(const State& s, const SurfacePoint& w) {
  const Triangle t = TriangleOf(s.grid, w.triangle);
  return w.bary[0] * s.v2[t[0]] + w.bary[1] * s.v2[t[1]] + w.bary[2] * s.v2[t[2]];
}

// Total least squares line through each line's markers: the exact minimiser
// of E_line over (θ, offset) for the current M'.
void FitLines(State& s, const StepData& data) {
  const int n = int(s.lines.size());
  std::vector<Eigen::Vector2d> sum(n, Eigen::Vector2d::Zero());
  std::vector<Eigen::Matrix2d> outer(n, Eigen::Matrix2d::Zero());
  std::vector<int> count(n, 0);
  for (const Marker& m : data.markers) {
    if (m.line < 0) continue;
    const Eigen::Vector2d p = FlatPoint(s, m.where);
    sum[m.line] += p;
    outer[m.line] += p * p.transpose();
    ++count[m.line];
  }
  for (int l = 0; l < n; ++l) {
    if (count[l] < 2) continue;
    const Eigen::Vector2d mean = sum[l] / count[l];
    const Eigen::Matrix2d scatter = outer[l] - count[l] * mean * mean.transpose();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(scatter);
    Eigen::Vector2d normal = eig.eigenvectors().col(0);
    if (normal.dot(s.lines[l].Normal()) < 0) normal = -normal;
    double theta = std::atan2(normal.y(), normal.x());
    if (s.lines[l].axis_aligned) {
      theta = NearestAxisTheta(theta);
      normal = Eigen::Vector2d(std::cos(theta), std::sin(theta));
    }
    s.lines[l].theta = theta;
    s.lines[l].offset = normal.dot(mean);
  }
}

// Feature line projection: p' onto its line, then the new face and
// barycentrics of the moved point in M'.
void ProjectMarkers(const State& s, StepData& data) {
  MeshPair flat;
  flat.grid = s.grid;
  flat.mesh2d = s.v2;
  FlatMeshLocator locator(flat);
  for (Marker& m : data.markers) {
    if (m.line < 0) continue;
    const FeatureLine& l = s.lines[m.line];
    const Eigen::Vector2d p = FlatPoint(s, m.where);
    const Eigen::Vector2d moved = p - l.SignedDistance(p) * l.Normal();
    if (auto w = locator.Locate(moved)) m.where = *w;
  }
}

}  // namespace docunfold::isometry::internal
