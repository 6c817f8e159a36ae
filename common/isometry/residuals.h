// Internal to docunfold_isometry (and its tests): the residuals of F with
// their analytic derivatives, in the normalised frame (see isometry.h).
// F = Σ_k λ_k Σ_rows(k) value²: every term is a sum of squared rows; a row
// depends on at most four vertices (5 unknowns each: x, y, z of M and x', y'
// of M') and on at most one line (θ, offset).
#pragma once

#include <Eigen/Core>
#include <array>
#include <vector>

#include "common/grid_mesh.h"
#include "common/isometry/isometry.h"

namespace docunfold::isometry::internal {

using Vec5 = Eigen::Matrix<double, 5, 1>;

// Unknowns in the normalised frame.
struct State {
  QuadGrid grid;
  std::vector<Eigen::Vector3d> v3;  // M
  std::vector<Eigen::Vector2d> v2;  // M'
  std::vector<FeatureLine> lines;
};

// A target point's footpoint on M, held fixed during one step.
struct Footpoint {
  int triangle = -1;
  Eigen::Vector3d bary = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  // unit normal of the triangle
  double distance = 0;
  bool inlier = false;
};

// What one step holds fixed (normalised frame).
struct StepData {
  std::vector<Eigen::Vector3d> points;
  std::vector<Footpoint> footpoints;  // one per point
  std::vector<Marker> markers;        // rays in the normalised frame
  double marker_weights = 0;          // H2: the sum of the markers' weights
  double iso_scale = 1;               // multiplies every c_iso (see IsoNormalization)
  double iso_edge_weight = 0;         // edge rows' share of E_iso (SolveOptions::iso_edges)
  double beta_point = 1;
  double beta_normal = 0.1;
  int num_inliers = 0;
  // Per fair triplet, the square root of Problem::fair3d_weights (empty: 1).
  std::vector<double> fair3d_factor;
};

struct Row {
  double value = 0;
  int count = 0;  // number of vertices involved
  std::array<int, 4> vertex{};
  std::array<Vec5, 4> d;  // ∂value/∂(x, y, z, x', y') of each vertex
  int line = -1;          // the line whose parameters the row depends on
  double d_theta = 0, d_offset = 0;
  void Reset() {
    value = 0;
    count = 0;
    line = -1;
    d_theta = d_offset = 0;
  }
  Vec5& Add(int v) {
    vertex[count] = v;
    d[count].setZero();
    return d[count++];
  }
};

enum Term { kIso = 0, kDist, kFair3d, kFair2d, kLine, kRay, kNumTerms };

inline Triangle TriangleOf(const QuadGrid& grid, int t) {
  const auto c = grid.Quad(t / 2);
  return t % 2 == 0 ? Triangle{c[0], c[1], c[2]} : Triangle{c[0], c[2], c[3]};
}

// Most rows one quad, point, triplet or marker contributes to any term.
constexpr int kMaxRowsPerItem = 8;

// --- E_iso: three rows per quad (the paper's c_iso), and with
// iso_edge_weight > 0 four more, |a|² - |a'|² of each edge scaled by
// iso_edge_weight / √2 (an inner edge is in two quads).
inline int IsoRows(const State& s, const StepData& data, int q, Row* rows) {
  const auto c = s.grid.Quad(q);
  const Eigen::Vector3d d1 = s.v3[c[0]] - s.v3[c[2]], d2 = s.v3[c[1]] - s.v3[c[3]];
  const Eigen::Vector2d e1 = s.v2[c[0]] - s.v2[c[2]], e2 = s.v2[c[1]] - s.v2[c[3]];
  const double k = data.iso_scale;
  // c1 = |d1|² - |e1|²
  Row& r1 = rows[0];
  r1.Reset();
  r1.value = k * (d1.squaredNorm() - e1.squaredNorm());
  {
    Vec5& a = r1.Add(c[0]);
    a.head<3>() = 2 * k * d1;
    a.tail<2>() = -2 * k * e1;
    Vec5& b = r1.Add(c[2]);
    b = -a;
  }
  // c2 = |d2|² - |e2|²
  Row& r2 = rows[1];
  r2.Reset();
  r2.value = k * (d2.squaredNorm() - e2.squaredNorm());
  {
    Vec5& a = r2.Add(c[1]);
    a.head<3>() = 2 * k * d2;
    a.tail<2>() = -2 * k * e2;
    Vec5& b = r2.Add(c[3]);
    b = -a;
  }
  // c3 = <d1, d2> - <e1, e2>
  Row& r3 = rows[2];
  r3.Reset();
  r3.value = k * (d1.dot(d2) - e1.dot(e2));
  {
    Vec5& v0 = r3.Add(c[0]);
    v0.head<3>() = k * d2;
    v0.tail<2>() = -k * e2;
    Vec5& v1 = r3.Add(c[1]);
    v1.head<3>() = k * d1;
    v1.tail<2>() = -k * e1;
    Vec5& v2 = r3.Add(c[2]);
    v2 = -r3.d[0];
    Vec5& v3 = r3.Add(c[3]);
    v3 = -r3.d[1];
  }
  if (!(data.iso_edge_weight > 0)) return 3;
  const double ke = k * data.iso_edge_weight * M_SQRT1_2;
  for (int i = 0; i < 4; ++i) {
    const int a = c[i], b = c[(i + 1) % 4];
    const Eigen::Vector3d d = s.v3[a] - s.v3[b];
    const Eigen::Vector2d e = s.v2[a] - s.v2[b];
    Row& r = rows[3 + i];
    r.Reset();
    r.value = ke * (d.squaredNorm() - e.squaredNorm());
    Vec5& da = r.Add(a);
    da.head<3>() = 2 * ke * d;
    da.tail<2>() = -2 * ke * e;
    Vec5& db = r.Add(b);
    db = -r.d[0];
  }
  return 7;
}

// --- E_dist: four rows per inlier (three point-to-point, one along N).
inline int DistRows(const State& s, const StepData& data, int i, Row* rows) {
  const Footpoint& f = data.footpoints[i];
  if (!f.inlier || data.num_inliers == 0) return 0;
  const Triangle t = TriangleOf(s.grid, f.triangle);
  const Eigen::Vector3d foot =
      f.bary[0] * s.v3[t[0]] + f.bary[1] * s.v3[t[1]] + f.bary[2] * s.v3[t[2]];
  const Eigen::Vector3d e = data.points[i] - foot;
  const double kp = std::sqrt(data.beta_point / data.num_inliers);
  const double kn = std::sqrt(data.beta_normal / data.num_inliers);
  for (int axis = 0; axis < 3; ++axis) {
    Row& r = rows[axis];
    r.Reset();
    r.value = kp * e[axis];
    for (int k = 0; k < 3; ++k) r.Add(t[k])[axis] = -kp * f.bary[k];
  }
  Row& r = rows[3];
  r.Reset();
  r.value = kn * f.normal.dot(e);
  for (int k = 0; k < 3; ++k) r.Add(t[k]).head<3>() = -kn * f.bary[k] * f.normal;
  return 4;
}

// --- E_fair: every interior vertex of every grid row and column.
inline int NumFairTriplets(const QuadGrid& g) {
  return std::max(0, g.ny * (g.nx - 2)) + std::max(0, g.nx * (g.ny - 2));
}
inline std::array<int, 3> FairTriplet(const QuadGrid& g, int t) {
  const int along_rows = std::max(0, g.ny * (g.nx - 2));
  if (t < along_rows) {
    const int r = t / (g.nx - 2), c = t % (g.nx - 2) + 1;
    return {g.Index(r, c - 1), g.Index(r, c), g.Index(r, c + 1)};
  }
  t -= along_rows;
  const int c = t / (g.ny - 2), r = t % (g.ny - 2) + 1;
  return {g.Index(r - 1, c), g.Index(r, c), g.Index(r + 1, c)};
}
// dims 0..2 (M) or 3..4 (M'): one row per coordinate.
inline int FairRows(const State& s, const StepData& data, int t, bool flat, Row* rows) {
  const auto v = FairTriplet(s.grid, t);
  const int first = flat ? 3 : 0, n = flat ? 2 : 3;
  const double f = flat || data.fair3d_factor.empty() ? 1.0 : data.fair3d_factor[size_t(t)];
  for (int k = 0; k < n; ++k) {
    const int dim = first + k;
    Row& r = rows[k];
    r.Reset();
    r.value = f * (flat ? s.v2[v[0]][k] - 2 * s.v2[v[1]][k] + s.v2[v[2]][k]
                        : s.v3[v[0]][k] - 2 * s.v3[v[1]][k] + s.v3[v[2]][k]);
    r.Add(v[0])[dim] = f;
    r.Add(v[1])[dim] = -2 * f;
    r.Add(v[2])[dim] = f;
  }
  return n;
}

// --- E_line: one row per marker on a line.
inline int LineRows(const State& s, const StepData& data, int m, Row* rows) {
  const Marker& mk = data.markers[m];
  if (mk.line < 0 || data.markers.empty()) return 0;
  const FeatureLine& line = s.lines[mk.line];
  const Triangle t = TriangleOf(s.grid, mk.where.triangle);
  const Eigen::Vector3d& w = mk.where.bary;
  const Eigen::Vector2d p = w[0] * s.v2[t[0]] + w[1] * s.v2[t[1]] + w[2] * s.v2[t[2]];
  const Eigen::Vector2d n = line.Normal();
  const double k = 1 / std::sqrt(data.marker_weights);
  Row& r = rows[0];
  r.Reset();
  r.value = k * (n.dot(p) - line.offset);
  for (int i = 0; i < 3; ++i) r.Add(t[i]).tail<2>() = k * w[i] * n;
  r.line = mk.line;
  r.d_theta = k * Eigen::Vector2d(-n.y(), n.x()).dot(p);
  r.d_offset = -k;
  return 1;
}

// Two unit vectors orthogonal to d and to each other.
inline void OrthogonalFrame(const Eigen::Vector3d& d, Eigen::Vector3d* e1, Eigen::Vector3d* e2) {
  const Eigen::Vector3d helper =
      std::abs(d.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  *e1 = d.cross(helper).normalized();
  *e2 = d.cross(*e1).normalized();
}

// --- E_ray: two rows per marker (components of p - o orthogonal to the ray),
// one (along Marker::across) for a marker held to a plane only.
inline int RayRows(const State& s, const StepData& data, int m, Row* rows) {
  const Marker& mk = data.markers[m];
  const Triangle t = TriangleOf(s.grid, mk.where.triangle);
  const Eigen::Vector3d& w = mk.where.bary;
  const Eigen::Vector3d p = w[0] * s.v3[t[0]] + w[1] * s.v3[t[1]] + w[2] * s.v3[t[2]];
  Eigen::Vector3d e[2];
  const bool plane = mk.across.squaredNorm() > 0;
  if (plane) {
    e[0] = mk.across;
  } else {
    OrthogonalFrame(mk.ray_direction, &e[0], &e[1]);
  }
  // sqrt(1) is exact: weight-1 markers get exactly 1/sqrt(H2).
  const double k = std::sqrt(mk.weight) / std::sqrt(data.marker_weights);
  const int n = plane ? 1 : 2;
  for (int j = 0; j < n; ++j) {
    Row& r = rows[j];
    r.Reset();
    r.value = k * e[j].dot(p - mk.ray_origin);
    for (int i = 0; i < 3; ++i) r.Add(t[i]).head<3>() = k * w[i] * e[j];
  }
  return n;
}

// Calls sink(term, row) for every row of every term (λ not applied).
template <class Sink>
void ForEachRow(const State& s, const StepData& data, Sink&& sink) {
  Row rows[kMaxRowsPerItem];
  for (int q = 0; q < s.grid.NumQuads(); ++q) {
    const int n = IsoRows(s, data, q, rows);
    for (int i = 0; i < n; ++i) sink(kIso, rows[i]);
  }
  for (int p = 0; p < int(data.points.size()); ++p) {
    const int n = DistRows(s, data, p, rows);
    for (int i = 0; i < n; ++i) sink(kDist, rows[i]);
  }
  const int triplets = NumFairTriplets(s.grid);
  for (int t = 0; t < triplets; ++t) {
    int n = FairRows(s, data, t, false, rows);
    for (int i = 0; i < n; ++i) sink(kFair3d, rows[i]);
    n = FairRows(s, data, t, true, rows);
    for (int i = 0; i < n; ++i) sink(kFair2d, rows[i]);
  }
  for (int m = 0; m < int(data.markers.size()); ++m) {
    int n = LineRows(s, data, m, rows);
    for (int i = 0; i < n; ++i) sink(kLine, rows[i]);
    n = RayRows(s, data, m, rows);
    for (int i = 0; i < n; ++i) sink(kRay, rows[i]);
  }
}

inline double WeightOf(const Weights& w, int term) {
  switch (term) {
    case kIso:
      return w.iso;
    case kDist:
      return w.dist;
    case kFair3d:
      return w.fair3d;
    case kFair2d:
      return w.fair2d;
    case kLine:
      return w.line;
    default:
      return w.ray;
  }
}

// The unweighted value of every term.
TermValues EvaluateTerms(const State& s, const StepData& data, int threads = 1);

}  // namespace docunfold::isometry::internal
