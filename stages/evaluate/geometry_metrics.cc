#include "stages/evaluate/geometry_metrics.h"

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <limits>
#include <set>
#include <utility>

#include "common/errors.h"

namespace docunfold::evaluate {

std::optional<CameraAlignment> AlignCameras(const CameraSet& sfm, const CameraSet& truth,
                                            std::string* why_not) {
  std::vector<Eigen::Vector3d> from, to;
  for (const PinholeCamera& camera : sfm.views) {
    if (const PinholeCamera* match = truth.Find(camera.image)) {
      from.push_back(camera.Center());
      to.push_back(match->Center());
    }
  }
  const int n = int(from.size());
  if (n < 3) {
    if (why_not)
      *why_not = std::to_string(n) + " view(s) in both camera sets; 3 are needed to align";
    return std::nullopt;
  }
  Eigen::Matrix3Xd a(3, n), b(3, n);
  for (int i = 0; i < n; ++i) {
    a.col(i) = from[i];
    b.col(i) = to[i];
  }
  // Collinear (or coincident) centres leave the rotation about their line free.
  const Eigen::Matrix3Xd centred = a.colwise() - a.rowwise().mean();
  const Eigen::Vector3d sv = Eigen::JacobiSVD<Eigen::Matrix3Xd>(centred).singularValues();
  if (sv(0) <= 0 || sv(1) < 1e-3 * sv(0)) {
    if (why_not) *why_not = "camera centres are collinear; cannot align";
    return std::nullopt;
  }
  const Eigen::Matrix4d m = Eigen::umeyama(a, b, true);
  CameraAlignment out;
  out.cameras = n;
  const Eigen::Matrix3d sr = m.topLeftCorner<3, 3>();
  out.truth_from_sfm.scale = std::cbrt(sr.determinant());
  out.truth_from_sfm.R = sr / out.truth_from_sfm.scale;
  out.truth_from_sfm.t = m.topRightCorner<3, 1>();
  double sq = 0;
  for (int i = 0; i < n; ++i) sq += (out.truth_from_sfm(from[i]) - to[i]).squaredNorm();
  out.rms_residual = std::sqrt(sq / n);
  return out;
}

double PointTriangleDistance(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                             const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  // Voronoi regions of the triangle's vertices, edges and face in turn.
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return ap.norm();
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return bp.norm();
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return (p - (a + ab * (d1 / (d1 - d3)))).norm();
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return cp.norm();
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return (p - (a + ac * (d2 / (d2 - d6)))).norm();
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return (p - (b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6))))).norm();
  const double denom = va + vb + vc;
  if (std::abs(denom) < 1e-300) return ap.norm();  // degenerate triangle
  const double v = vb / denom, w = vc / denom;
  return (p - (a + ab * v + ac * w)).norm();
}

SurfaceDistance::SurfaceDistance(std::vector<Eigen::Vector3d> vertices,
                                 std::vector<std::array<int, 3>> triangles)
    : vertices_(std::move(vertices), 16),
      triangles_(std::move(triangles)),
      triangles_of_vertex_(vertices_.size()) {
  for (size_t f = 0; f < triangles_.size(); ++f)
    for (int v : triangles_[f]) triangles_of_vertex_.at(v).push_back(int(f));
}

double SurfaceDistance::operator()(const Eigen::Vector3d& point) const {
  constexpr int kNeighbours = 12;
  const std::vector<Eigen::Vector3d>& v = vertices_.points();
  const std::vector<PointIndex3d::Neighbour> near = vertices_.Nearest(point, kNeighbours);
  double best = !near.empty() ? std::sqrt(near[0].second) : std::numeric_limits<double>::infinity();
  for (const PointIndex3d::Neighbour& n : near) {
    for (int f : triangles_of_vertex_[n.first]) {
      const auto& t = triangles_[f];
      best = std::min(best, PointTriangleDistance(point, v[t[0]], v[t[1]], v[t[2]]));
    }
  }
  return best;
}

DistanceStats MeshToSurface(const std::vector<Eigen::Vector3d>& vertices,
                            const Similarity& transform, const SurfaceDistance& surface) {
  DistanceStats s;
  double sum = 0;
  for (const Eigen::Vector3d& v : vertices) {
    const double d = surface(transform(v));
    sum += d;
    s.max = std::max(s.max, d);
    ++s.samples;
  }
  s.mean = s.samples ? sum / double(s.samples) : 0;
  return s;
}

IsometryStats IsometryError(const PlyData& mesh3d, const PlyData& mesh2d,
                            const std::string& names_for_errors) {
  if (mesh3d.vertices.size() != mesh2d.vertices.size() || mesh3d.faces != mesh2d.faces)
    throw InputError(names_for_errors + ": meshes do not share vertices and faces");
  std::set<std::pair<int, int>> edges;
  for (const auto& face : mesh3d.faces)
    for (size_t k = 0; k < face.size(); ++k) {
      const int a = face[k], b = face[(k + 1) % face.size()];
      edges.insert({std::min(a, b), std::max(a, b)});
    }
  IsometryStats s;
  double sum = 0;
  for (const auto& [a, b] : edges) {
    const double flat = (mesh2d.vertices[a] - mesh2d.vertices[b]).norm();
    if (flat <= 0) continue;  // a collapsed flat edge has no relative error
    const double error = std::abs((mesh3d.vertices[a] - mesh3d.vertices[b]).norm() - flat) / flat;
    sum += error;
    s.max = std::max(s.max, error);
    ++s.edges;
  }
  s.mean = s.edges ? sum / double(s.edges) : 0;
  return s;
}

}  // namespace docunfold::evaluate
