#include "common/isometry/metrics.h"

#include <algorithm>
#include <cmath>

namespace docunfold::isometry {

EdgeLengthError IsometryEdgeError(const MeshPair& m) {
  EdgeLengthError e;
  double sum = 0;
  auto edge = [&](int a, int b) {
    const double l3 = (m.mesh3d[a] - m.mesh3d[b]).norm();
    const double l2 = (m.mesh2d[a] - m.mesh2d[b]).norm();
    if (!(l2 > 0)) return;
    const double rel = std::abs(l3 - l2) / l2;
    sum += rel;
    e.max = std::max(e.max, rel);
    ++e.edges;
  };
  const QuadGrid& g = m.grid;
  for (int r = 0; r < g.ny; ++r)
    for (int c = 0; c < g.nx; ++c) {
      if (c + 1 < g.nx) edge(g.Index(r, c), g.Index(r, c + 1));
      if (r + 1 < g.ny) edge(g.Index(r, c), g.Index(r + 1, c));
    }
  e.mean = e.edges ? sum / e.edges : 0;
  return e;
}

double ModelSize(const MeshPair& m) {
  if (m.mesh3d.empty()) return 0;
  Eigen::Vector3d lo = m.mesh3d[0], hi = lo;
  for (const auto& v : m.mesh3d) {
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
  return (hi - lo).norm();
}

}  // namespace docunfold::isometry
