#include "stages/init-mesh/page_from_points.h"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <opencv2/imgproc.hpp>
#include <queue>
#include <utility>

#include "common/point_index.h"
#include "common/statistics.h"

namespace docunfold::init_mesh {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// The cell size of the thinning grid: the points' extent between their 1st
// and 99th percentiles per axis, over o.cells_across (0 when they all lie in
// one place).
double CellSize(const std::vector<Eigen::Vector3d>& points, const PageFromPointsOptions& o) {
  Eigen::Vector3d extent;
  for (int axis = 0; axis < 3; ++axis) {
    std::vector<double> v;
    for (const auto& p : points) v.push_back(p[axis]);
    std::sort(v.begin(), v.end());
    extent[axis] = v[v.size() * 99 / 100] - v[v.size() / 100];
  }
  return extent.norm() / o.cells_across;
}

// One point per occupied cell (the first), as indices into `points`.
std::vector<int> Thin(const std::vector<Eigen::Vector3d>& points, double cell) {
  std::map<std::array<int64_t, 3>, int> first;
  std::vector<int> kept;
  for (size_t i = 0; i < points.size(); ++i) {
    const std::array<int64_t, 3> key = {int64_t(std::floor(points[i].x() / cell)),
                                        int64_t(std::floor(points[i].y() / cell)),
                                        int64_t(std::floor(points[i].z() / cell))};
    if (first.emplace(key, int(i)).second) kept.push_back(int(i));
  }
  return kept;
}

// Adjacency lists of the graph joining each point to its nearest point in
// each of `sectors` directions around it in its tangent plane (normal
// `normals[i]`), up to `reach` away: a point on a lone chain of outline
// points reaches across the blank margin to the print, as well as along the
// chain. Symmetric.
using Graph = std::vector<std::vector<std::pair<int, double>>>;

Graph SectorGraph(const std::vector<Eigen::Vector3d>& points,
                  const std::vector<Eigen::Vector3d>& normals, int sectors, double reach) {
  const PointIndex3d tree(points);
  Graph graph(points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3d& n = normals[i];
    const Eigen::Vector3d t1 = n.unitOrthogonal(), t2 = n.cross(t1);
    std::vector<int> nearest(size_t(sectors), -1);
    std::vector<double> length(size_t(sectors), reach);
    for (const auto& [j, d2] : tree.WithinSquaredRadius(points[i], reach * reach)) {
      const double d = std::sqrt(d2);
      if (size_t(j) == i) continue;
      const Eigen::Vector3d v = points[size_t(j)] - points[i];
      const double angle = std::atan2(v.dot(t2), v.dot(t1)) + M_PI;
      const int sector = std::min(sectors - 1, int(angle / (2 * M_PI) * sectors));
      if (d < length[size_t(sector)]) {
        length[size_t(sector)] = d;
        nearest[size_t(sector)] = j;
      }
    }
    for (int s = 0; s < sectors; ++s)
      if (nearest[size_t(s)] >= 0) {
        graph[i].push_back({nearest[size_t(s)], length[size_t(s)]});
        graph[size_t(nearest[size_t(s)])].push_back({int(i), length[size_t(s)]});
      }
  }
  return graph;
}

// Vertices of the largest connected part of `graph`.
std::vector<int> LargestPart(const Graph& graph) {
  std::vector<int> part(graph.size(), -1);
  std::vector<int> best;
  for (size_t seed = 0; seed < graph.size(); ++seed) {
    if (part[seed] >= 0) continue;
    std::vector<int> members{int(seed)};
    part[seed] = int(seed);
    for (size_t q = 0; q < members.size(); ++q)
      for (const auto& [j, d] : graph[size_t(members[q])])
        if (part[size_t(j)] < 0) {
          part[size_t(j)] = int(seed);
          members.push_back(j);
        }
    if (members.size() > best.size()) best = std::move(members);
  }
  std::sort(best.begin(), best.end());
  return best;
}

// Graph distances from `source` to every vertex (infinity where unreached).
std::vector<double> Dijkstra(const Graph& graph, int source) {
  std::vector<double> dist(graph.size(), kInf);
  using Item = std::pair<double, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> queue;
  dist[size_t(source)] = 0;
  queue.push({0, source});
  while (!queue.empty()) {
    const auto [d, v] = queue.top();
    queue.pop();
    if (d > dist[size_t(v)]) continue;
    for (const auto& [w, length] : graph[size_t(v)])
      if (d + length < dist[size_t(w)]) {
        dist[size_t(w)] = d + length;
        queue.push({dist[size_t(w)], w});
      }
  }
  return dist;
}

// The weighted affine fit X(u) = a + B (u - u0) of 3D positions to their
// flat positions, evaluated at u0. A small ridge on B keeps it from
// shooting off where the neighbours lie nearly on a line (or far from u0).
Eigen::Vector3d AffineFitAt(const Eigen::Vector2d& u0, const std::vector<int>& neighbours,
                            const std::vector<Eigen::Vector2d>& flat,
                            const std::vector<Eigen::Vector3d>& points, double scale) {
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(Eigen::Index(neighbours.size()) + 2, 3);
  Eigen::MatrixXd b = Eigen::MatrixXd::Zero(Eigen::Index(neighbours.size()) + 2, 3);
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  double weight_sum = 0;
  for (size_t i = 0; i < neighbours.size(); ++i) {
    const Eigen::Vector2d d = flat[size_t(neighbours[i])] - u0;
    const double w = 1.0 / (1.0 + d.squaredNorm() / (scale * scale));
    const double sw = std::sqrt(w);
    a.row(Eigen::Index(i)) << sw, sw * d.x() / scale, sw * d.y() / scale;
    b.row(Eigen::Index(i)) = sw * points[size_t(neighbours[i])].transpose();
    mean += w * points[size_t(neighbours[i])];
    weight_sum += w;
  }
  const double ridge = 0.1 * std::sqrt(weight_sum);
  a(a.rows() - 2, 1) = ridge;
  a(a.rows() - 1, 2) = ridge;
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(a);
  if (qr.rank() < 3) return mean / weight_sum;
  return qr.solve(b).row(0).transpose();
}

}  // namespace

std::vector<bool> PagePoints(const std::vector<Eigen::Vector3d>& points,
                             const std::vector<ViewPage>& photos, const PageFromPointsOptions& o) {
  std::vector<cv::Mat1b> grown;
  for (const ViewPage& p : photos) grown.push_back(GrowRegion(p.mask, o.mask_margin_px));
  std::vector<bool> page(points.size(), false);
  for (size_t i = 0; i < points.size(); ++i) {
    int framed = 0;
    bool inside = true;
    for (size_t v = 0; v < photos.size() && inside; ++v) {
      const auto px = ProjectDistorted(photos[v].camera, photos[v].distortion, points[i]);
      if (!px) continue;
      const int x = int(std::lround(px->x())), y = int(std::lround(px->y()));
      if (x < 0 || y < 0 || x >= grown[v].cols || y >= grown[v].rows) continue;
      ++framed;
      inside = grown[v](y, x) > 0;
    }
    page[i] = inside && framed >= o.min_photos;
  }
  return page;
}

bool LayOutFlat(const std::vector<Eigen::Vector3d>& points, const PageFromPointsOptions& o,
                FlatLayout* out, std::string* why) {
  if (points.size() < 20) {
    *why = "only " + std::to_string(points.size()) + " points on the page";
    return false;
  }
  const double cell = CellSize(points, o);
  const double largest =
      std::max_element(
          points.begin(), points.end(),
          [](auto& a, auto& b) { return a.cwiseAbs().maxCoeff() < b.cwiseAbs().maxCoeff(); })
          ->cwiseAbs()
          .maxCoeff();
  if (!(cell > 1e-9 * largest) || !std::isfinite(largest)) {
    *why = "the points lie in one place";
    return false;
  }
  const std::vector<int> thinned = Thin(points, cell);
  std::vector<Eigen::Vector3d> thin_points, normals;
  {
    const PointIndex3d all(points);
    const int k = std::min<int>(o.plane_neighbours, int(points.size()));
    for (int i : thinned) {
      const Eigen::Vector3d& p = points[size_t(i)];
      Eigen::Vector3d mean = Eigen::Vector3d::Zero();
      const auto nearest = all.Nearest(p, k);
      for (const auto& [j, d2] : nearest) mean += points[size_t(j)] / double(nearest.size());
      Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
      for (const auto& [j, d2] : nearest) {
        const Eigen::Vector3d d = points[size_t(j)] - mean;
        scatter += d * d.transpose();
      }
      const Eigen::Vector3d normal =
          Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(scatter).eigenvectors().col(0);
      thin_points.push_back(p - normal * normal.dot(p - mean));
      normals.push_back(normal);
    }
  }
  const Graph full = SectorGraph(thin_points, normals, o.graph_sectors, o.graph_reach_cells * cell);
  const std::vector<int> part = LargestPart(full);
  const size_t n = part.size();
  if (n < 20) {
    *why = "the points fall apart into small groups";
    return false;
  }
  // The graph restricted to its largest part, renumbered.
  std::vector<int> index(thin_points.size(), -1);
  out->used.clear();
  out->position.clear();
  for (size_t i = 0; i < n; ++i) {
    index[size_t(part[i])] = int(i);
    out->used.push_back(thinned[size_t(part[i])]);
    out->position.push_back(thin_points[size_t(part[i])]);
  }
  Graph graph(n);
  for (size_t i = 0; i < n; ++i)
    for (const auto& [j, d] : full[size_t(part[i])]) graph[i].push_back({index[size_t(j)], d});

  // Landmarks by farthest-point sampling in graph distance; their distances
  // to every point are the layout's data.
  const int m = std::min<int>(std::max(o.landmarks, 3), int(n));
  std::vector<std::vector<double>> dist;
  std::vector<int> landmark;
  std::vector<double> nearest_landmark(n, kInf);
  int next = 0;
  for (int l = 0; l < m; ++l) {
    landmark.push_back(next);
    dist.push_back(Dijkstra(graph, next));
    double farthest = -1;
    for (size_t i = 0; i < n; ++i) {
      nearest_landmark[i] = std::min(nearest_landmark[i], dist.back()[i]);
      if (nearest_landmark[i] > farthest) {
        farthest = nearest_landmark[i];
        next = int(i);
      }
    }
  }
  // Classical MDS of the landmarks: double-centred squared distances.
  Eigen::MatrixXd d2(m, m);
  for (int a = 0; a < m; ++a)
    for (int b = 0; b < m; ++b) {
      const double d = dist[size_t(a)][size_t(landmark[size_t(b)])];
      d2(a, b) = d * d;
    }
  d2 = 0.5 * (d2 + d2.transpose()).eval();
  const Eigen::VectorXd column_mean = d2.colwise().mean().transpose();
  const Eigen::MatrixXd centring =
      Eigen::MatrixXd::Identity(m, m) - Eigen::MatrixXd::Constant(m, m, 1.0 / m);
  const Eigen::MatrixXd gram = -0.5 * centring * d2 * centring;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(gram);
  const Eigen::VectorXd values = eigen.eigenvalues();  // ascending
  const double l1 = values(m - 1), l2 = values(m - 2);
  if (!(l2 > 1e-9 * l1) || !(l1 > 0)) {
    *why = "the points lie on a line";
    return false;
  }
  // Every point from its squared distances to the landmarks (the landmarks
  // themselves land where the MDS put them).
  Eigen::Matrix<double, 2, Eigen::Dynamic> pinv(2, m);
  pinv.row(0) = eigen.eigenvectors().col(m - 1).transpose() / std::sqrt(l1);
  pinv.row(1) = eigen.eigenvectors().col(m - 2).transpose() / std::sqrt(l2);
  out->flat.resize(n);
  Eigen::VectorXd delta(m);
  for (size_t i = 0; i < n; ++i) {
    for (int l = 0; l < m; ++l) delta(l) = dist[size_t(l)][i] * dist[size_t(l)][i];
    out->flat[i] = 0.5 * pinv * (column_mean - delta);
  }
  return true;
}

bool MeshFromPoints(const std::vector<Eigen::Vector3d>& points, int quads_short, int quads_long,
                    const PageFromPointsOptions& o, MeshPair* out, std::string* why) {
  FlatLayout layout;
  if (!LayOutFlat(points, o, &layout, why)) return false;
  const std::vector<Eigen::Vector3d>& used = layout.position;

  // The rectangle: the smallest-area rectangle's axes, its extent trimmed.
  std::vector<cv::Point2f> cloud;
  for (const auto& u : layout.flat) cloud.emplace_back(float(u.x()), float(u.y()));
  const cv::RotatedRect box = cv::minAreaRect(cloud);
  const double angle = box.angle * M_PI / 180;
  Eigen::Vector2d axis0(std::cos(angle), std::sin(angle));
  Eigen::Vector2d axis1(-axis0.y(), axis0.x());
  if (box.size.height > box.size.width) std::swap(axis0, axis1);  // axis0 along the long side
  std::vector<double> along, across;
  for (const auto& u : layout.flat) {
    along.push_back(axis0.dot(u));
    across.push_back(axis1.dot(u));
  }
  auto trimmed = [&](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    const size_t cut = size_t(o.rectangle_trim * double(v.size()));
    return std::pair<double, double>(v[cut], v[v.size() - 1 - cut]);
  };
  const auto [a0, a1] = trimmed(along);
  const auto [c0, c1] = trimmed(across);

  // A grid over it, rows across the long side; each vertex placed by an
  // affine fit to its nearest points in the layout.
  std::vector<Eigen::Vector2d> flat = layout.flat;
  const PointIndex2d tree(flat);
  std::vector<double> spacing;
  for (const auto& u : flat) {
    const auto nn = tree.Nearest(u, 2);
    if (nn.size() == 2) spacing.push_back(std::sqrt(nn[1].second));
  }
  const double scale = std::max(Median(spacing), 1e-12) * 2;
  MeshPair& m = *out;
  m.grid.nx = quads_long + 1;
  m.grid.ny = quads_short + 1;
  m.mesh3d.clear();
  m.mesh2d.clear();
  const int k = std::min<int>(o.fit_neighbours, int(flat.size()));
  for (int r = 0; r < m.grid.ny; ++r)
    for (int c = 0; c < m.grid.nx; ++c) {
      const double s = a0 + (a1 - a0) * c / quads_long;
      const double t = c0 + (c1 - c0) * r / quads_short;
      const Eigen::Vector2d u = s * axis0 + t * axis1;
      std::vector<int> neighbours;
      for (const auto& [j, d2] : tree.Nearest(u, k)) neighbours.push_back(j);
      m.mesh3d.push_back(AffineFitAt(u, neighbours, flat, used, scale));
      m.mesh2d.push_back({s - a0, t - c0});
    }
  return true;
}

}  // namespace docunfold::init_mesh
