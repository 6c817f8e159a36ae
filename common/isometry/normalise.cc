// The normalised frame of the solver (see isometry.h): lengths divided by
// the bounding-box diagonal of M, M and M' centred on their centroids.
#include <cmath>
#include <stdexcept>
#include <string>

#include "common/isometry/solver_internal.h"

namespace docunfold::isometry::internal {

Frame FrameOf(const MeshPair& m) {
  Frame f;
  Eigen::Vector3d lo = m.mesh3d[0], hi = lo, sum3 = Eigen::Vector3d::Zero();
  Eigen::Vector2d sum2 = Eigen::Vector2d::Zero();
  for (size_t i = 0; i < m.mesh3d.size(); ++i) {
    lo = lo.cwiseMin(m.mesh3d[i]);
    hi = hi.cwiseMax(m.mesh3d[i]);
    sum3 += m.mesh3d[i];
    sum2 += m.mesh2d[i];
  }
  const double diagonal = (hi - lo).norm();
  if (!(diagonal > 0) || !std::isfinite(diagonal))
    throw std::invalid_argument("isometry: M is degenerate (zero or infinite size)");
  f.scale = 1 / diagonal;
  f.center3 = sum3 / double(m.mesh3d.size());
  f.center2 = sum2 / double(m.mesh2d.size());
  return f;
}

void Validate(const Problem& p) {
  const QuadGrid& g = p.meshes.grid;
  if (!p.fair3d_weights.empty() && int(p.fair3d_weights.size()) != NumFairTriplets(g))
    throw std::invalid_argument("isometry: fair3d_weights does not match the grid's triplets");
  for (const double w : p.fair3d_weights)
    if (!(w >= 0 && std::isfinite(w)))
      throw std::invalid_argument("isometry: a fair3d weight is negative or not finite");
  if (g.nx < 2 || g.ny < 2) throw std::invalid_argument("isometry: grid smaller than 2x2");
  if (int(p.meshes.mesh3d.size()) != g.NumVertices() ||
      int(p.meshes.mesh2d.size()) != g.NumVertices())
    throw std::invalid_argument("isometry: mesh sizes do not match the grid");
  for (const auto& v : p.meshes.mesh3d)
    if (!v.allFinite()) throw std::invalid_argument("isometry: non-finite vertex in M");
  for (const auto& v : p.meshes.mesh2d)
    if (!v.allFinite()) throw std::invalid_argument("isometry: non-finite vertex in M'");
  for (const auto& x : p.points)
    if (!x.allFinite()) throw std::invalid_argument("isometry: non-finite target point");
  const int triangles = 2 * g.NumQuads();
  for (const Marker& m : p.markers) {
    if (m.where.triangle < 0 || m.where.triangle >= triangles)
      throw std::invalid_argument("isometry: marker on triangle " +
                                  std::to_string(m.where.triangle) + " outside the grid");
    if (m.line >= int(p.lines.size()))
      throw std::invalid_argument("isometry: marker on line " + std::to_string(m.line) + " of " +
                                  std::to_string(p.lines.size()));
    if (!m.ray_origin.allFinite() || !(m.ray_direction.norm() > 0) || !m.where.bary.allFinite() ||
        !m.across.allFinite() || !(m.weight > 0) || !std::isfinite(m.weight))
      throw std::invalid_argument("isometry: marker with a bad ray, barycentrics or weight");
  }
}

Work Normalise(const Problem& p, const SolveOptions& o) {
  Work w;
  w.frame = FrameOf(p.meshes);
  const Frame& f = w.frame;
  w.state.grid = p.meshes.grid;
  for (const auto& v : p.meshes.mesh3d) w.state.v3.push_back((v - f.center3) * f.scale);
  for (const auto& v : p.meshes.mesh2d) w.state.v2.push_back((v - f.center2) * f.scale);
  for (FeatureLine l : p.lines) {
    l.offset = (l.offset - l.Normal().dot(f.center2)) * f.scale;
    w.state.lines.push_back(l);
  }
  for (const auto& x : p.points) w.data.points.push_back((x - f.center3) * f.scale);
  w.data.footpoints.resize(p.points.size());
  for (Marker m : p.markers) {
    m.ray_origin = (m.ray_origin - f.center3) * f.scale;
    m.ray_direction.normalize();
    w.data.markers.push_back(m);
    w.data.marker_weights += m.weight;
  }
  w.data.beta_point = o.beta_point;
  w.data.beta_normal = o.beta_normal;
  for (const double weight : p.fair3d_weights) w.data.fair3d_factor.push_back(std::sqrt(weight));
  if (o.iso_normalization == IsoNormalization::kStrain) {
    // c_iso divided by ℓ², the mean squared diagonal length of the quads of
    // M' at the start (of M when M' is degenerate): rows are strains of an
    // average quad. (Dividing each quad by its own ℓ_q² lets the small
    // quads of perspective-compressed grid corners dominate; see
    // docs/decisions/optimize.md, "One strain scale for every quad".)
    const int quads = w.state.grid.NumQuads();
    auto mean_diag2 = [&](const auto& v) {
      double sum = 0;
      for (int q = 0; q < quads; ++q) {
        const auto c = w.state.grid.Quad(q);
        sum += 0.5 * ((v[c[0]] - v[c[2]]).squaredNorm() + (v[c[1]] - v[c[3]]).squaredNorm());
      }
      return sum / quads;
    };
    double mean = mean_diag2(w.state.v2);
    if (!(mean > 0)) mean = mean_diag2(w.state.v3);
    if (!(mean > 0)) throw std::invalid_argument("isometry: every quad is degenerate");
    w.data.iso_scale = 1 / (mean * std::sqrt(double(quads)));
  } else {
    w.data.iso_scale = 1;
  }
  w.data.iso_edge_weight = o.iso_edges;
  w.weights = o.weights;
  return w;
}

MeshPair Denormalise(const State& s, const Frame& f) {
  MeshPair m;
  m.grid = s.grid;
  for (const auto& v : s.v3) m.mesh3d.push_back(v / f.scale + f.center3);
  for (const auto& v : s.v2) m.mesh2d.push_back(v / f.scale + f.center2);
  return m;
}

std::vector<FeatureLine> DenormaliseLines(const State& s, const Frame& f) {
  std::vector<FeatureLine> out;
  for (FeatureLine l : s.lines) {
    l.offset = l.offset / f.scale + l.Normal().dot(f.center2);
    out.push_back(l);
  }
  return out;
}

Marker DenormaliseMarker(Marker m, const Frame& f) {
  m.ray_origin = m.ray_origin / f.scale + f.center3;
  return m;
}

Marker NormaliseMarker(Marker m, const Frame& f) {
  m.ray_origin = (m.ray_origin - f.center3) * f.scale;
  m.ray_direction.normalize();
  return m;
}

}  // namespace docunfold::isometry::internal

namespace docunfold::isometry {

std::vector<std::array<int, 3>> FairTriplets(const QuadGrid& grid) {
  std::vector<std::array<int, 3>> triplets;
  for (int t = 0; t < internal::NumFairTriplets(grid); ++t)
    triplets.push_back(internal::FairTriplet(grid, t));
  return triplets;
}

}  // namespace docunfold::isometry
