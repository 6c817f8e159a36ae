#include "common/isometry/subdivision.h"

#include <stdexcept>

namespace docunfold::isometry {
namespace {

template <class V>
std::vector<V> Subdivide(const QuadGrid& g, const std::vector<V>& p) {
  const int nx = g.nx, ny = g.ny, fx = 2 * nx - 1, fy = 2 * ny - 1;
  std::vector<V> out(size_t(fx) * fy);
  auto P = [&](int r, int c) -> const V& { return p[size_t(r) * nx + c]; };
  auto out_at = [&](int r, int c) -> V& { return out[size_t(r) * fx + c]; };
  // Face points.
  std::vector<V> face(size_t(nx - 1) * (ny - 1));
  auto F = [&](int r, int c) -> V& { return face[size_t(r) * (nx - 1) + c]; };
  for (int r = 0; r + 1 < ny; ++r)
    for (int c = 0; c + 1 < nx; ++c) {
      F(r, c) = (P(r, c) + P(r, c + 1) + P(r + 1, c) + P(r + 1, c + 1)) / 4;
      out_at(2 * r + 1, 2 * c + 1) = F(r, c);
    }
  // Edge points: along rows (between (r,c) and (r,c+1)).
  for (int r = 0; r < ny; ++r)
    for (int c = 0; c + 1 < nx; ++c) {
      const V mid = (P(r, c) + P(r, c + 1)) / 2;
      if (r == 0 || r == ny - 1)
        out_at(2 * r, 2 * c + 1) = mid;
      else
        out_at(2 * r, 2 * c + 1) = (P(r, c) + P(r, c + 1) + F(r - 1, c) + F(r, c)) / 4;
    }
  // Edge points: along columns (between (r,c) and (r+1,c)).
  for (int r = 0; r + 1 < ny; ++r)
    for (int c = 0; c < nx; ++c) {
      const V mid = (P(r, c) + P(r + 1, c)) / 2;
      if (c == 0 || c == nx - 1)
        out_at(2 * r + 1, 2 * c) = mid;
      else
        out_at(2 * r + 1, 2 * c) = (P(r, c) + P(r + 1, c) + F(r, c - 1) + F(r, c)) / 4;
    }
  // Vertex points.
  for (int r = 0; r < ny; ++r)
    for (int c = 0; c < nx; ++c) {
      const bool top = r == 0, bottom = r == ny - 1, left = c == 0, right = c == nx - 1;
      V& o = out_at(2 * r, 2 * c);
      if ((top || bottom) && (left || right)) {
        o = P(r, c);  // corner
      } else if (top || bottom) {
        o = (P(r, c - 1) + 6 * P(r, c) + P(r, c + 1)) / 8;
      } else if (left || right) {
        o = (P(r - 1, c) + 6 * P(r, c) + P(r + 1, c)) / 8;
      } else {
        const V f = (F(r - 1, c - 1) + F(r - 1, c) + F(r, c - 1) + F(r, c)) / 4;
        const V e = (P(r, c - 1) + P(r, c + 1) + P(r - 1, c) + P(r + 1, c) + 4 * P(r, c)) / 8;
        o = (f + 2 * e + P(r, c)) / 4;
      }
    }
  return out;
}

}  // namespace

MeshPair SubdivideCatmullClark(const MeshPair& m) {
  if (m.grid.nx < 2 || m.grid.ny < 2)
    throw std::invalid_argument("SubdivideCatmullClark: grid smaller than 2x2");
  MeshPair out;
  out.grid = {2 * m.grid.nx - 1, 2 * m.grid.ny - 1};
  out.mesh3d = Subdivide(m.grid, m.mesh3d);
  out.mesh2d = Subdivide(m.grid, m.mesh2d);
  return out;
}

SurfacePoint SubdividedSurfacePoint(const QuadGrid& coarse, const SurfacePoint& p) {
  // (u, v) in the coarse quad from the triangle's barycentrics. Triangle 2q
  // is corners (0,1,2) = (0,0) (1,0) (1,1); 2q+1 is (0,2,3) = (0,0) (1,1) (0,1).
  const int q = p.triangle / 2;
  const Eigen::Vector3d& w = p.bary;
  double u, v;
  if (p.triangle % 2 == 0) {
    u = w[1] + w[2];
    v = w[2];
  } else {
    u = w[1];
    v = w[1] + w[2];
  }
  const int qr = q / (coarse.nx - 1), qc = q % (coarse.nx - 1);
  const int fnx = 2 * coarse.nx - 1;
  const int sr = v < 0.5 ? 0 : 1, sc = u < 0.5 ? 0 : 1;
  const double fu = 2 * u - sc, fv = 2 * v - sr;
  const int fq = (2 * qr + sr) * (fnx - 1) + (2 * qc + sc);
  SurfacePoint out;
  if (fv <= fu) {  // lower triangle (0,0) (1,0) (1,1)
    out.triangle = 2 * fq;
    out.bary = Eigen::Vector3d(1 - fu, fu - fv, fv);
  } else {
    out.triangle = 2 * fq + 1;
    out.bary = Eigen::Vector3d(1 - fv, fu, fv - fu);
  }
  return out;
}

}  // namespace docunfold::isometry
