#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <string>
#include <vector>

#include "common/isometry/mesh_index.h"
#include "stages/init-mesh/init_mesh_internal.h"

namespace docunfold::init_mesh {
namespace {

// The points of `p` on its convex hull, counter-clockwise in x-right y-up.
// OpenCV decides which they are on the points rounded to float; the hull's
// points are `p`'s own.
std::vector<Eigen::Vector2d> ConvexHull(const std::vector<Eigen::Vector2d>& p) {
  std::vector<cv::Point2f> rounded;
  for (const Eigen::Vector2d& q : p) rounded.emplace_back(float(q.x()), float(q.y()));
  std::vector<int> on_hull;
  cv::convexHull(rounded, on_hull, /*clockwise=*/false, /*returnPoints=*/false);
  std::vector<Eigen::Vector2d> hull;
  for (const int i : on_hull) hull.push_back(p[size_t(i)]);
  return hull;
}

// Direction (radians) of an axis of the minimum-area bounding rectangle: one
// of its sides is collinear with a hull edge (rotating calipers).
double OrientedBoxAngle(const std::vector<Eigen::Vector2d>& pts) {
  const std::vector<Eigen::Vector2d> hull = ConvexHull(pts);
  double best_area = std::numeric_limits<double>::infinity(), best_angle = 0;
  for (size_t i = 0; i < hull.size(); ++i) {
    const Eigen::Vector2d e = hull[(i + 1) % hull.size()] - hull[i];
    if (!(e.norm() > 0)) continue;
    const Eigen::Vector2d a = e.normalized(), b(-a.y(), a.x());
    double lo_a = 1e300, hi_a = -1e300, lo_b = 1e300, hi_b = -1e300;
    for (const auto& p : hull) {
      lo_a = std::min(lo_a, p.dot(a));
      hi_a = std::max(hi_a, p.dot(a));
      lo_b = std::min(lo_b, p.dot(b));
      hi_b = std::max(hi_b, p.dot(b));
    }
    const double area = (hi_a - lo_a) * (hi_b - lo_b);
    if (area < best_area) {
      best_area = area;
      best_angle = std::atan2(a.y(), a.x());
    }
  }
  return best_angle;
}

// The rotation (radians) that turns M' upright: the oriented bounding box of
// `pts` (points of M') onto the axes, choosing among the four quarter turns
// the one that takes the grid's rows (the page's top side direction) to +x.
double UprightAngle(const MeshPair& m, const std::vector<Eigen::Vector2d>& pts) {
  const double base = -OrientedBoxAngle(pts);
  Eigen::Vector2d u = Eigen::Vector2d::Zero();
  for (int r = 0; r < m.grid.ny; ++r)
    u += m.mesh2d[m.grid.Index(r, m.grid.nx - 1)] - m.mesh2d[m.grid.Index(r, 0)];
  double best = base, best_x = -2;
  for (int k = 0; k < 4; ++k) {
    const double a = base + k * M_PI / 2;
    const double x = (std::cos(a) * u.x() - std::sin(a) * u.y()) / std::max(u.norm(), 1e-300);
    if (x > best_x) {
      best_x = x;
      best = a;
    }
  }
  return std::remainder(best, 2 * M_PI);
}

// Points of M' along the real boundary sides: on the Coons grid its border
// rows and columns, on the bounding-box grid the sides' pixels found on M.
// `used` names the sides that gave points.
std::vector<Eigen::Vector2d> RealSidesOnFlatMesh(const Inputs& in, const Result& res,
                                                 std::string* used) {
  const MeshPair& m = res.meshes;
  const PinholeCamera& cam = in.reference;
  std::vector<Eigen::Vector2d> flat;
  std::unique_ptr<PixelToSurface> lookup;
  for (int s = 0; s < 4; ++s) {
    if (!in.boundary.sides[s].real) continue;
    const size_t before = flat.size();
    if (res.grid_source == "coons") {
      // The grid's border was built from the sides: top = row 0, right =
      // last column, bottom = last row, left = column 0.
      const QuadGrid& gr = m.grid;
      const int n = s % 2 == 0 ? gr.nx : gr.ny;
      for (int i = 0; i < n; ++i) {
        const int v = s == 0   ? gr.Index(0, i)
                      : s == 1 ? gr.Index(i, gr.nx - 1)
                      : s == 2 ? gr.Index(gr.ny - 1, i)
                               : gr.Index(i, 0);
        flat.push_back(m.mesh2d[v]);
      }
    } else {
      // The bounding-box grid reaches beyond the page: the sides' pixels
      // are inside its silhouette.
      if (!lookup) lookup = std::make_unique<PixelToSurface>(m, cam);
      for (const auto& px : Densify(in.boundary.sides[s].points, 3.0))
        if (auto where = lookup->Lookup(px)) flat.push_back(PointOnMesh2d(m, *where));
    }
    if (flat.size() > before) *used += std::string(used->empty() ? "" : ", ") + kSideNames[s];
  }
  return flat;
}

}  // namespace

MeshPair RegridOnPage(const MeshPair& m) {
  const QuadGrid& g = m.grid;
  auto border = [&](int which) {
    std::vector<Eigen::Vector2d> line;
    const int n = which % 2 == 0 ? g.nx : g.ny;
    for (int i = 0; i < n; ++i)
      line.push_back(m.mesh2d[which == 0   ? g.Index(0, i)
                              : which == 1 ? g.Index(i, g.nx - 1)
                              : which == 2 ? g.Index(g.ny - 1, i)
                                           : g.Index(i, 0)]);
    return line;
  };
  auto resample = [](const std::vector<Eigen::Vector2d>& line) {
    std::vector<double> s{0};
    for (size_t i = 1; i < line.size(); ++i) s.push_back(s.back() + (line[i] - line[i - 1]).norm());
    return AtEqualArcLength(line, s, int(line.size()));
  };
  std::array<std::vector<Eigen::Vector2d>, 4> side;
  for (int k = 0; k < 4; ++k) side[k] = resample(border(k));
  const Eigen::Vector2d tl = side[0].front(), tr = side[0].back();
  const Eigen::Vector2d br = side[2].back(), bl = side[2].front();
  Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
  for (const auto& v : m.mesh2d) centroid += v / double(m.mesh2d.size());
  isometry::FlatMeshLocator locator(m);
  MeshPair out;
  out.grid = g;
  for (int r = 0; r < g.ny; ++r)
    for (int c = 0; c < g.nx; ++c) {
      const double u = double(c) / (g.nx - 1), v = double(r) / (g.ny - 1);
      Eigen::Vector2d p =
          (1 - v) * side[0][c] + v * side[2][c] + (1 - u) * side[3][r] + u * side[1][r] -
          ((1 - u) * (1 - v) * tl + u * (1 - v) * tr + (1 - u) * v * bl + u * v * br);
      // Border points sit on M''s border; nudge them in until located.
      std::optional<SurfacePoint> where = locator.Locate(p);
      for (int k = 1; !where && k <= 30; ++k)
        where = locator.Locate(p + (centroid - p) * (1e-6 * std::pow(2.0, k)));
      if (!where) return m;  // not a simple region: keep the image grid
      out.mesh2d.push_back(p);
      out.mesh3d.push_back(PointOnMesh3d(m, *where));
    }
  return out;
}

void TurnUpright(const Inputs& in, Result* result) {
  Result& res = *result;
  MeshPair& m = res.meshes;
  std::string used;
  std::vector<Eigen::Vector2d> flat = RealSidesOnFlatMesh(in, res, &used);
  if (flat.size() < 10) {
    flat = m.mesh2d;
    res.upright_from = "whole mesh";
  } else {
    res.upright_from = "real sides: " + used;
  }
  const double angle = UprightAngle(m, flat);
  const Eigen::Rotation2Dd rot(angle);
  Eigen::Vector2d lo(1e300, 1e300);
  for (auto& v : m.mesh2d) {
    v = rot * v;
    lo = lo.cwiseMin(v);
  }
  for (auto& v : m.mesh2d) v -= lo;
  res.upright_rotation_deg = angle * 180 / M_PI;
}

}  // namespace docunfold::init_mesh
