#include "stages/init-mesh/init_mesh.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <nanoflann.hpp>
#include <numeric>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <sstream>

#include "common/atomic_file.h"
#include "common/cli.h"
#include "common/depth_field.h"
#include "common/errors.h"
#include "common/isometry/mesh_index.h"
#include "common/isometry/metrics.h"
#include "common/isometry/unfold.h"
#include "common/page_files.h"
#include "common/ply.h"

namespace docunfold::init_mesh {
namespace {

using Clock = std::chrono::steady_clock;
double Since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

std::string Fixed(double x, int digits) {
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(digits);
  s << x;
  return s.str();
}

// ---------------------------------------------------------------------------
// Reading boundary.json (tolerant: what cannot be used is recorded, Run
// decides whether the grid can still follow the page border).

std::vector<Eigen::Vector2d> ParsePolyline(const Json& j) {
  std::vector<Eigen::Vector2d> out;
  if (!j.is_array()) return {};
  for (const Json& p : j) {
    if (!p.is_array() || p.size() != 2 || !p[0].is_number() || !p[1].is_number()) return {};
    const Eigen::Vector2d v(p[0].get<double>(), p[1].get<double>());
    if (!v.allFinite()) return {};
    out.push_back(v);
  }
  return out;
}

Boundary ParseBoundary(const Json& doc) {
  Boundary b;
  if (doc.contains("contour")) b.contour = ParsePolyline(doc["contour"]);
  if (doc.contains("corners")) b.corners = ParsePolyline(doc["corners"]);
  if (b.corners.size() < 3)
    b.problems.push_back(std::to_string(b.corners.size()) + " usable corners");
  const Json* sides = doc.contains("sides") && doc["sides"].is_object() ? &doc["sides"] : nullptr;
  for (int s = 0; s < 4; ++s) {
    const char* name = kSideNames[s];
    if (!sides || !sides->contains(name) || !(*sides)[name].is_object()) {
      b.problems.push_back(std::string("no ") + name + " side");
      continue;
    }
    const Json& side = (*sides)[name];
    if (side.contains("points")) b.sides[s].points = ParsePolyline(side["points"]);
    if (b.sides[s].points.size() < 2) {
      b.problems.push_back(std::string("the ") + name + " side has fewer than 2 points");
      b.sides[s].points.clear();
    }
    b.sides[s].real =
        side.contains("real") && side["real"].is_boolean() && side["real"].get<bool>();
  }
  return b;
}

// ---------------------------------------------------------------------------
// 2D k-d tree over projected points.

// nanoflann's view of a vector of D-dimensional points.
template <int D>
struct VectorCloud {
  const std::vector<Eigen::Matrix<double, D, 1>>* pts;
  size_t kdtree_get_point_count() const { return pts->size(); }
  double kdtree_get_pt(size_t i, size_t d) const { return (*pts)[i][int(d)]; }
  template <class B>
  bool kdtree_get_bbox(B&) const {
    return false;
  }
};
using PixelCloud = VectorCloud<2>;
using PixelTree =
    nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, PixelCloud>,
                                        PixelCloud, 2, uint32_t>;

// Distance from a 3D position to the nearest of a fixed set of points.
class NearestPoint {
 public:
  explicit NearestPoint(const std::vector<Eigen::Vector3d>& points)
      : cloud_{&points}, tree_(3, cloud_, nanoflann::KDTreeSingleIndexAdaptorParams(10)) {
    tree_.buildIndex();
  }
  double Distance(const Eigen::Vector3d& x) const {
    if (cloud_.pts->empty()) return std::numeric_limits<double>::infinity();
    uint32_t index = 0;
    double d2 = 0;
    nanoflann::KNNResultSet<double, uint32_t> knn(1);
    knn.init(&index, &d2);
    tree_.findNeighbors(knn, x.data(), nanoflann::SearchParams());
    return std::sqrt(d2);
  }

 private:
  using Cloud = VectorCloud<3>;
  Cloud cloud_;
  nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, Cloud>, Cloud, 3,
                                      uint32_t>
      tree_;
};

// ---------------------------------------------------------------------------
// The grid in the image.

double Length(const std::vector<Eigen::Vector2d>& p) {
  double l = 0;
  for (size_t i = 1; i < p.size(); ++i) l += (p[i] - p[i - 1]).norm();
  return l;
}

// Densifies a polyline to steps of at most `step` pixels.
std::vector<Eigen::Vector2d> Densify(const std::vector<Eigen::Vector2d>& p, double step) {
  std::vector<Eigen::Vector2d> out{p.front()};
  for (size_t i = 1; i < p.size(); ++i) {
    const int n = std::max(1, int(std::ceil((p[i] - p[i - 1]).norm() / step)));
    for (int k = 1; k <= n; ++k) out.push_back(p[i - 1] + (p[i] - p[i - 1]) * (double(k) / n));
  }
  return out;
}

// n points along a polyline, equally spaced in arc length on the page (the
// polyline lifted to 3D), so quads are near-uniform on the page rather than
// in the perspective image. Also returns the 3D length.
template <class Lift>
std::vector<Eigen::Vector2d> ResampleOnPage(const std::vector<Eigen::Vector2d>& poly, int n,
                                            const Lift& lift, double* length3d) {
  const std::vector<Eigen::Vector2d> dense = Densify(poly, 3.0);
  std::vector<double> s{0};
  Eigen::Vector3d prev = lift(dense[0]);
  for (size_t i = 1; i < dense.size(); ++i) {
    const Eigen::Vector3d x = lift(dense[i]);
    s.push_back(s.back() + (x - prev).norm());
    prev = x;
  }
  *length3d = s.back();
  std::vector<Eigen::Vector2d> out;
  size_t j = 0;
  for (int k = 0; k < n; ++k) {
    const double target = s.back() * k / (n - 1);
    while (j + 2 < s.size() && s[j + 1] < target) ++j;
    const double span = s[j + 1] - s[j];
    const double f = span > 0 ? std::clamp((target - s[j]) / span, 0.0, 1.0) : 0.0;
    out.push_back(dense[j] + f * (dense[j + 1] - dense[j]));
  }
  return out;
}

struct ImageGrid {
  QuadGrid grid;
  std::vector<Eigen::Vector2d> pixels;
};

// Signed area of quad q in the image (y down: positive for our orientation).
double QuadArea(const ImageGrid& g, int q) {
  const auto c = g.grid.Quad(q);
  double a = 0;
  for (int k = 0; k < 4; ++k) {
    const Eigen::Vector2d& p = g.pixels[c[k]];
    const Eigen::Vector2d& n = g.pixels[c[(k + 1) % 4]];
    a += p.x() * n.y() - p.y() * n.x();
  }
  return a / 2;
}

// Coons patch of the four sides; false (and why) when the boundary cannot
// support it.
template <class Lift>
bool CoonsGrid(const Boundary& b, const Options& o, const Lift& lift, const cv::Mat1b& region,
               ImageGrid* out, std::string* why) {
  if (b.corners.size() < 3) {
    *why = "boundary.json has " + std::to_string(b.corners.size()) + " usable corners";
    return false;
  }
  std::array<std::vector<Eigen::Vector2d>, 4> side;
  for (int s = 0; s < 4; ++s) {
    side[s] = b.sides[s].points;
    if (side[s].size() < 2 || Length(side[s]) < 5) {
      *why = std::string("the ") + kSideNames[s] + " side is missing or too short";
      return false;
    }
  }
  // Expected corners of each side (top TL→TR, right TR→BR, bottom BL→BR,
  // left TL→BL); sides drawn the other way round are turned.
  std::array<Eigen::Vector2d, 4> corner;  // TL, TR, BR, BL
  if (b.corners.size() == 4) {
    for (int k = 0; k < 4; ++k) corner[k] = b.corners[k];
  } else {
    corner = {side[0].front(), side[0].back(), side[2].back(), side[2].front()};
  }
  const std::array<std::array<int, 2>, 4> ends = {{{0, 1}, {1, 2}, {3, 2}, {0, 3}}};
  double mean_length = 0;
  for (int s = 0; s < 4; ++s) {
    const Eigen::Vector2d &a = corner[ends[s][0]], &z = corner[ends[s][1]];
    if ((side[s].front() - a).norm() + (side[s].back() - z).norm() >
        (side[s].back() - a).norm() + (side[s].front() - z).norm())
      std::reverse(side[s].begin(), side[s].end());
    mean_length += Length(side[s]) / 4;
  }
  for (int s = 0; s < 4; ++s) {
    const double gap = std::max((side[s].front() - corner[ends[s][0]]).norm(),
                                (side[s].back() - corner[ends[s][1]]).norm());
    if (gap > 0.1 * mean_length) {
      *why = std::string("the ") + kSideNames[s] + " side does not meet its corners (gap " +
             Fixed(gap, 0) + " px)";
      return false;
    }
  }
  double len[4];
  const int n_dummy = 2;
  for (int s = 0; s < 4; ++s) ResampleOnPage(side[s], n_dummy, lift, &len[s]);
  const bool wide = len[0] + len[2] >= len[1] + len[3];
  const int nx = (wide ? o.grid_long : o.grid_short) + 1;
  const int ny = (wide ? o.grid_short : o.grid_long) + 1;
  std::array<std::vector<Eigen::Vector2d>, 4> s;
  for (int k = 0; k < 4; ++k) s[k] = ResampleOnPage(side[k], k % 2 == 0 ? nx : ny, lift, &len[k]);
  const Eigen::Vector2d tl = (s[0].front() + s[3].front()) / 2,
                        tr = (s[0].back() + s[1].front()) / 2;
  const Eigen::Vector2d br = (s[2].back() + s[1].back()) / 2, bl = (s[2].front() + s[3].back()) / 2;
  ImageGrid g;
  g.grid = {nx, ny};
  for (int r = 0; r < ny; ++r)
    for (int c = 0; c < nx; ++c) {
      const double u = double(c) / (nx - 1), v = double(r) / (ny - 1);
      g.pixels.push_back(
          (1 - v) * s[0][c] + v * s[2][c] + (1 - u) * s[3][r] + u * s[1][r] -
          ((1 - u) * (1 - v) * tl + u * (1 - v) * tr + (1 - u) * v * bl + u * v * br));
    }
  // The patch must be a proper grid: every quad the same orientation, and on
  // the page.
  auto count_flipped = [&] {
    int n = 0;
    for (int q = 0; q < g.grid.NumQuads(); ++q) n += QuadArea(g, q) <= 0;
    return n;
  };
  // A wiggly side (segmentation noise) can fold a few quads of the patch:
  // relax the interior (each vertex toward the mean of its four neighbours,
  // border fixed) until it unfolds.
  int flipped = count_flipped();
  for (int round = 0; flipped > 0 && round < 20; ++round) {
    for (int sweep = 0; sweep < 10; ++sweep) {
      std::vector<Eigen::Vector2d> next = g.pixels;
      for (int r = 1; r + 1 < ny; ++r)
        for (int c = 1; c + 1 < nx; ++c)
          next[g.grid.Index(r, c)] =
              0.25 * (g.pixels[g.grid.Index(r - 1, c)] + g.pixels[g.grid.Index(r + 1, c)] +
                      g.pixels[g.grid.Index(r, c - 1)] + g.pixels[g.grid.Index(r, c + 1)]);
      g.pixels = std::move(next);
    }
    flipped = count_flipped();
  }
  int inside = 0;
  for (const auto& p : g.pixels) {
    const int x = int(std::lround(p.x())), y = int(std::lround(p.y()));
    inside += x >= 0 && y >= 0 && x < region.cols && y < region.rows && region(y, x);
  }
  if (flipped > 0) {
    *why = "the Coons patch of the sides folds over (" + std::to_string(flipped) + " quads)";
    return false;
  }
  if (inside < 0.8 * g.pixels.size()) {
    *why = "the Coons patch of the sides lies mostly outside mask.png";
    return false;
  }
  *out = std::move(g);
  return true;
}

template <class Lift>
ImageGrid BoundingBoxGrid(const cv::Mat1b& mask, const Options& o, const Lift& lift) {
  const cv::Rect box = cv::boundingRect(mask);
  const Eigen::Vector2d p0(box.x, box.y), p1(box.x + box.width - 1, box.y + box.height - 1);
  const double wide3d = (lift(Eigen::Vector2d(p1.x(), p0.y())) - lift(p0)).norm() +
                        (lift(p1) - lift(Eigen::Vector2d(p0.x(), p1.y()))).norm();
  const double tall3d = (lift(Eigen::Vector2d(p0.x(), p1.y())) - lift(p0)).norm() +
                        (lift(p1) - lift(Eigen::Vector2d(p1.x(), p0.y()))).norm();
  const bool wide = wide3d >= tall3d;
  ImageGrid g;
  g.grid = {(wide ? o.grid_long : o.grid_short) + 1, (wide ? o.grid_short : o.grid_long) + 1};
  for (int r = 0; r < g.grid.ny; ++r)
    for (int c = 0; c < g.grid.nx; ++c)
      g.pixels.push_back(p0 + Eigen::Vector2d((p1.x() - p0.x()) * c / (g.grid.nx - 1),
                                              (p1.y() - p0.y()) * r / (g.grid.ny - 1)));
  return g;
}

// Re-grids the pair uniformly on the page: a Coons patch of the border of
// M' (each border polyline resampled by arc length in the plane), mapped
// back onto M through the pair's own correspondence. The image-space grid is
// uniform in the perspective image, not on the page; starting from a grid
// whose M' is already fair saves the refinement many slow iterations of
// sliding the grid over the surface (its point-to-point term resists that).
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
    std::vector<Eigen::Vector2d> out;
    size_t j = 0;
    const int n = int(line.size());
    for (int k = 0; k < n; ++k) {
      const double target = s.back() * k / (n - 1);
      while (j + 2 < s.size() && s[j + 1] < target) ++j;
      const double span = s[j + 1] - s[j];
      const double f = span > 0 ? std::clamp((target - s[j]) / span, 0.0, 1.0) : 0.0;
      out.push_back(line[j] + f * (line[j + 1] - line[j]));
    }
    return out;
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

// Where on the page (ninths of the grid) the points fall. Fails when they
// cover less than `min_covered_ninths` of it; otherwise returns a warning
// naming each third (left, right, top, bottom) without points, empty when
// every third has some: the mesh is carried over such a part by fairness
// and isometry alone (a panel of a fold seen by one other photo has none).
std::string CheckCoverage(const ImageGrid& g, const std::vector<Eigen::Vector2d>& pixels, int width,
                          int height, const Options& o, const std::string& image) {
  cv::Mat1i label(height, width, -1);
  for (int q = 0; q < g.grid.NumQuads(); ++q) {
    const auto c = g.grid.Quad(q);
    std::vector<cv::Point> poly;
    for (int k = 0; k < 4; ++k)
      poly.emplace_back(int(std::lround(g.pixels[c[k]].x())), int(std::lround(g.pixels[c[k]].y())));
    cv::fillPoly(label, std::vector<std::vector<cv::Point>>{poly}, cv::Scalar(q));
  }
  int count[3][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}};  // [row third][column third]
  for (const auto& p : pixels) {
    const int x = int(std::lround(p.x())), y = int(std::lround(p.y()));
    if (x < 0 || y < 0 || x >= width || y >= height || label(y, x) < 0) continue;
    const int q = label(y, x), qr = q / (g.grid.nx - 1), qc = q % (g.grid.nx - 1);
    ++count[std::min(2, 3 * qr / (g.grid.ny - 1))][std::min(2, 3 * qc / (g.grid.nx - 1))];
  }
  int covered = 0;
  for (const auto& row : count)
    for (const int n : row) covered += n >= o.min_points_per_ninth;
  const int left = count[0][0] + count[1][0] + count[2][0];
  const int right = count[0][2] + count[1][2] + count[2][2];
  const int top = count[0][0] + count[0][1] + count[0][2];
  const int bottom = count[2][0] + count[2][1] + count[2][2];
  const std::pair<const char*, int> parts[4] = {
      {"left", left}, {"right", right}, {"top", top}, {"bottom", bottom}};
  std::string empty;
  for (const auto& [name, n] : parts)
    if (n < o.min_points_per_ninth) empty += std::string(empty.empty() ? "" : ", ") + name;
  if (covered < o.min_covered_ninths)
    throw InputError("points cover only " + std::to_string(covered) + " of the page's 9 parts in " +
                     image + " (need " + std::to_string(o.min_covered_ninths) + "; " +
                     std::to_string(pixels.size()) + " points inside the document region" +
                     (empty.empty() ? std::string() : ", none in the " + empty + " third") +
                     "): the page cannot be reconstructed");
  if (empty.empty()) return "";
  return "no points in the " + empty + " third of the page in " + image +
         ": its shape there is carried over from the rest";
}

// ---------------------------------------------------------------------------
// Upright.

// Convex hull (Andrew's monotone chain), counter-clockwise in x-right y-up.
std::vector<Eigen::Vector2d> ConvexHull(std::vector<Eigen::Vector2d> p) {
  std::sort(p.begin(), p.end(), [](const auto& a, const auto& b) {
    return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
  });
  if (p.size() < 3) return p;
  auto cross = [](const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
  };
  std::vector<Eigen::Vector2d> h(2 * p.size());
  size_t k = 0;
  for (size_t i = 0; i < p.size(); ++i) {
    while (k >= 2 && cross(h[k - 2], h[k - 1], p[i]) <= 0) --k;
    h[k++] = p[i];
  }
  for (size_t i = p.size() - 1, t = k + 1; i-- > 0;) {
    while (k >= t && cross(h[k - 2], h[k - 1], p[i]) <= 0) --k;
    h[k++] = p[i];
  }
  h.resize(k - 1);
  return h;
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

// Markers holding M's border vertices to the page's outline in the reference
// image: each to the plane through the camera centre and the outline's
// tangent line at the outline point nearest its projection, so it may slide
// along the outline but not across it (re-decided every outer iteration).
std::vector<isometry::Marker> OutlineMarkers(const MeshPair& m, const PinholeCamera& cam,
                                             const std::vector<Eigen::Vector2d>& contour,
                                             const NearestPoint& points, const Options& o) {
  const double min_cos = std::cos(o.outline_hold_max_angle_deg * M_PI / 180);
  const double max_gap = o.outline_hold_support * isometry::ModelSize(m);
  std::vector<isometry::Marker> markers;
  const QuadGrid& g = m.grid;
  const size_t n = contour.size();
  if (n < 3 || g.nx < 2 || g.ny < 2) return markers;
  const Eigen::Vector3d centre = cam.Center();
  // The image border where the page is cut off is no edge of it.
  auto on_frame = [&](const Eigen::Vector2d& p) {
    return p.x() < 2 || p.y() < 2 || p.x() > cam.width - 3 || p.y() > cam.height - 3;
  };
  for (int r = 0; r < g.ny; ++r)
    for (int c = 0; c < g.nx; ++c) {
      if (r != 0 && r != g.ny - 1 && c != 0 && c != g.nx - 1) continue;
      const int v = g.Index(r, c);
      const Eigen::Vector3d x = cam.CamFromWorld(m.mesh3d[v]);
      if (!(x.z() > 0)) continue;
      // Where M is seen at a grazing angle the outline is likely its
      // silhouette (a curl, a panel seen edge-on), not the page's edge.
      const auto& p3 = m.mesh3d;
      const Eigen::Vector3d along_row =
          p3[g.Index(r, std::min(c + 1, g.nx - 1))] - p3[g.Index(r, std::max(c - 1, 0))];
      const Eigen::Vector3d along_col =
          p3[g.Index(std::min(r + 1, g.ny - 1), c)] - p3[g.Index(std::max(r - 1, 0), c)];
      const Eigen::Vector3d normal = along_row.cross(along_col).normalized();
      if (!(std::abs(normal.dot((m.mesh3d[v] - centre).normalized())) >= min_cos)) continue;
      // Far from every point M's shape there is a guess (a panel past a
      // fold without points stays flat): pulling its border onto the
      // outline would tilt the guess, not correct it.
      if (!(points.Distance(m.mesh3d[v]) <= max_gap)) continue;
      const Eigen::Vector2d px = cam.ProjectCam(x);
      double best = std::numeric_limits<double>::infinity();
      Eigen::Vector2d q, tangent;
      bool cut = false;
      for (size_t i = 0; i < n; ++i) {
        const Eigen::Vector2d a = contour[i], b = contour[(i + 1) % n];
        const Eigen::Vector2d d = b - a;
        const double len2 = d.squaredNorm();
        if (!(len2 > 0)) continue;
        const double u = std::clamp((px - a).dot(d) / len2, 0.0, 1.0);
        const Eigen::Vector2d on = a + u * d;
        const double dist = (px - on).squaredNorm();
        if (dist < best) {
          best = dist;
          q = on;
          tangent = d / std::sqrt(len2);
          cut = on_frame(a) && on_frame(b);
        }
      }
      if (!std::isfinite(best) || cut) continue;
      isometry::Marker mk;
      mk.where = VertexSurfacePoint(g, r, c);
      mk.ray_origin = centre;
      mk.ray_direction = cam.RayDirection(q);
      mk.across = mk.ray_direction.cross(cam.RayDirection(q + tangent)).normalized();
      if (!mk.across.allFinite()) continue;
      markers.push_back(mk);
    }
  return markers;
}

}  // namespace

// ---------------------------------------------------------------------------

Inputs ReadInputs(const fs::path& sfm_dir, const fs::path& boundary_dir,
                  const fs::path& points_file) {
  Inputs in;
  const fs::path cameras_path = sfm_dir / "cameras.json";
  const CameraSet cameras = ReadCameras(cameras_path);
  if (cameras.reference.empty())
    throw InputError(cameras_path.string() +
                     ": no reference view (expected format docunfold.cameras with \"reference\")");
  in.reference = *cameras.Find(cameras.reference);

  const fs::path points_path = points_file.empty() ? sfm_dir / "points.ply" : points_file;
  PlyData ply = ReadPly(points_path);
  if (ply.vertices.empty()) throw InputError(points_path.string() + ": no points");
  if (const PlyProperty* source = ply.FindProperty("source"))
    for (double v : source->values) in.point_sources.push_back(int(v));
  in.points = std::move(ply.vertices);

  in.reference_image = sfm_dir / "reference.png";
  const cv::Mat image = ReadImage(in.reference_image, cv::IMREAD_REDUCED_GRAYSCALE_2);
  const int w2 = (in.reference.width + 1) / 2, h2 = (in.reference.height + 1) / 2;
  if (std::abs(image.cols - w2) > 1 || std::abs(image.rows - h2) > 1)
    throw InputError(in.reference_image.string() + ": size does not match the reference camera (" +
                     std::to_string(in.reference.width) + "x" +
                     std::to_string(in.reference.height) + " in cameras.json)");

  const fs::path boundary_path = boundary_dir / "boundary.json";
  const Json doc = ReadJsonFile(boundary_path);
  CheckFormat(doc, boundary_path, "docunfold.boundary", 1);
  in.boundary = ParseBoundary(doc);

  in.mask = ReadDocumentMask(boundary_dir / "mask.png", in.reference.width, in.reference.height);
  return in;
}

Result Run(const Inputs& in, const Options& o) {
  const auto start = Clock::now();
  if (o.grid_short < 1 || o.grid_long < 1) throw UsageError("the grid needs at least 1x1 quads");
  Result res;
  const PinholeCamera& cam = in.reference;
  const std::string image_name = in.reference_image.filename().string();

  // --- SfM points inside the document region.
  auto t = Clock::now();
  const cv::Mat1b region = GrowRegion(in.mask, o.mask_margin_px);
  std::vector<Eigen::Vector3d> region_points;
  std::vector<Eigen::Vector2d> pixels, outline_pixels;
  std::vector<double> depths, outline_depths;
  constexpr int kOutlineSource = 2;  // densify's points.ply
  for (const int i : PointsInRegion(in.points, cam, region)) {
    const Eigen::Vector3d xc = cam.CamFromWorld(in.points[i]);
    region_points.push_back(in.points[i]);
    pixels.push_back(cam.ProjectCam(xc));
    depths.push_back(xc.z());
    if (size_t(i) < in.point_sources.size() && in.point_sources[i] == kOutlineSource) {
      outline_pixels.push_back(pixels.back());
      outline_depths.push_back(depths.back());
    }
  }
  res.points_total = int(in.points.size());
  res.points_in_region = int(region_points.size());
  if (res.points_in_region < std::max(o.min_points, 4))
    throw InputError(
        "only " + std::to_string(res.points_in_region) + " of " + std::to_string(res.points_total) +
        " SfM points fall inside the document region of " + image_name + " (need at least " +
        std::to_string(std::max(o.min_points, 4)) + " to support the mesh)");

  // Depth outliers: far from the median depth of their image neighbours.
  std::vector<Eigen::Vector2d> kept_px;
  std::vector<double> kept_depth;
  {
    PixelCloud cloud{&pixels};
    PixelTree tree(2, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(10));
    tree.buildIndex();
    const size_t k = std::min<size_t>(9, pixels.size());
    std::vector<uint32_t> idx(k);
    std::vector<double> d2(k), nbr;
    std::vector<double> spacing;
    for (size_t i = 0; i < pixels.size(); ++i) {
      nanoflann::KNNResultSet<double, uint32_t> knn(k);
      knn.init(idx.data(), d2.data());
      tree.findNeighbors(knn, pixels[i].data(), nanoflann::SearchParams());
      nbr.clear();
      for (size_t j = 0; j < knn.size(); ++j)
        if (idx[j] != i) nbr.push_back(depths[idx[j]]);
      if (knn.size() > 1) spacing.push_back(std::sqrt(d2[1]));
      std::nth_element(nbr.begin(), nbr.begin() + nbr.size() / 2, nbr.end());
      const double median = nbr[nbr.size() / 2];
      if (std::abs(depths[i] - median) <= o.depth_outlier * median) {
        kept_px.push_back(pixels[i]);
        kept_depth.push_back(depths[i]);
      }
    }
    std::nth_element(spacing.begin(), spacing.begin() + spacing.size() / 2, spacing.end());
    res.rbf_scale_px =
        o.rbf_scale_px > 0 ? o.rbf_scale_px : std::max(1.0, spacing[spacing.size() / 2]);
  }
  if (kept_px.size() < 4) {  // everything disagrees: use every point
    kept_px = pixels;
    kept_depth = depths;
  }
  res.points_for_depth = int(kept_px.size());
  const DepthField depth(kept_px, kept_depth, std::max(1, o.depth_neighbours), res.rbf_scale_px,
                         o.depth_model, o.planar_neighbours, o.planar_guard);
  const Eigen::Matrix3d K_inv = cam.K.inverse();
  const Eigen::Matrix3d R_t = cam.R.transpose();
  auto lift = [&](const Eigen::Vector2d& px) -> Eigen::Vector3d {
    const Eigen::Vector3d xc = depth.At(px) * (K_inv * Eigen::Vector3d(px.x(), px.y(), 1));
    return R_t * (xc - cam.t);
  };
  res.timings.depth = Since(t);

  // --- The grid M^r in the image.
  t = Clock::now();
  ImageGrid g;
  std::string why;
  if (CoonsGrid(in.boundary, o, lift, region, &g, &why)) {
    res.grid_source = "coons";
  } else {
    res.warnings.push_back("boundary unusable (" + why + "): grid over the mask's bounding box");
    g = BoundingBoxGrid(in.mask, o, lift);
    res.grid_source = "mask_bbox";
  }
  const std::string coverage = CheckCoverage(g, pixels, cam.width, cam.height, o, image_name);
  if (!coverage.empty()) res.warnings.push_back(coverage);
  MeshPair& m = res.meshes;
  m.grid = g.grid;
  for (const auto& px : g.pixels) m.mesh3d.push_back(lift(px));
  if (res.grid_source == "coons") {
    std::vector<double> grid_depths;
    for (const Eigen::Vector3d& x : m.mesh3d) grid_depths.push_back(cam.CamFromWorld(x).z());
    std::array<std::vector<Eigen::Vector2d>, 4> sides;
    std::array<bool, 4> real{};
    for (int s = 0; s < 4; ++s) {
      sides[s] = in.boundary.sides[s].points;
      real[s] = in.boundary.sides[s].real;
    }
    res.outline_prior =
        OutlinePriorDepths(m.grid, g.pixels, grid_depths, sides, real, cam, outline_pixels,
                           outline_depths, kept_px, kept_depth, o.outline_prior);
    if (res.outline_prior.used)
      for (size_t v = 0; v < m.mesh3d.size(); ++v) {
        const Eigen::Vector2d& px = g.pixels[v];
        const Eigen::Vector3d xc =
            res.outline_prior.depth[v] * (K_inv * Eigen::Vector3d(px.x(), px.y(), 1));
        m.mesh3d[v] = R_t * (xc - cam.t);
      }
  } else {
    res.outline_prior.note = "no boundary sides (grid over the mask's bounding box)";
  }
  res.timings.grid = Since(t);

  // --- Unfold to the plane.
  t = Clock::now();
  const auto unfolded = isometry::UnfoldArap(m.grid, m.mesh3d, g.pixels);
  m.mesh2d = unfolded.mesh2d;
  res.unfold_iterations = unfolded.iterations;
  if (o.regrid_on_page) m = RegridOnPage(m);
  res.timings.unfold = Since(t);

  // --- Refine: the joint optimisation without feature lines.
  t = Clock::now();
  isometry::Problem problem;
  problem.meshes = m;
  problem.points = region_points;
  isometry::SolveOptions so = o.refine;
  so.weights.line = 0;
  so.weights.ray = o.outline_hold;
  if (o.outline_hold > 0 && !in.boundary.contour.empty()) {
    auto nearest = std::make_shared<NearestPoint>(region_points);
    problem.markers = OutlineMarkers(m, cam, in.boundary.contour, *nearest, o);
    so.on_outer_iteration = [&, nearest](const isometry::OuterIterationContext& c) {
      *c.markers = OutlineMarkers(*c.meshes, cam, in.boundary.contour, *nearest, o);
    };
  }
  isometry::Result refined = isometry::Solve(problem, so);
  m = refined.meshes;
  res.refine = refined.report;
  double distance_sum = 0;
  for (size_t i = 0; i < refined.point_inlier.size(); ++i)
    if (refined.point_inlier[i]) {
      ++res.inliers;
      distance_sum += refined.point_distance[i];
    }
  res.mean_inlier_distance =
      res.inliers ? distance_sum / res.inliers / std::max(refined.report.model_size, 1e-300) : 0;
  res.timings.refine = Since(t);

  // --- Upright.
  t = Clock::now();
  if (o.upright) {
    std::vector<Eigen::Vector2d> flat;
    std::string used;
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
      if (flat.size() > before) used += std::string(used.empty() ? "" : ", ") + kSideNames[s];
    }
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
  res.timings.upright = Since(t);

  const auto edge = isometry::IsometryEdgeError(m);
  res.isometry_error_mean = edge.mean;
  res.isometry_error_max = edge.max;
  res.timings.total = Since(start);
  return res;
}

Json OptionsToJson(const Options& o) {
  const auto& r = o.refine;
  return Json{
      {"grid", std::to_string(o.grid_short) + "x" + std::to_string(o.grid_long)},
      {"depth_neighbours", o.depth_neighbours},
      {"rbf_scale_px", o.rbf_scale_px},
      {"depth_model", o.depth_model == DepthModel::kPlanar ? "planar" : "average"},
      {"planar_neighbours", o.planar_neighbours},
      {"planar_guard", o.planar_guard},
      {"depth_outlier", o.depth_outlier},
      {"mask_margin_px", o.mask_margin_px},
      {"min_points", o.min_points},
      {"min_points_per_ninth", o.min_points_per_ninth},
      {"min_covered_ninths", o.min_covered_ninths},
      {"upright", o.upright},
      {"outline_prior",
       {{"enabled", o.outline_prior.enabled},
        {"side_distance_px", o.outline_prior.side_distance_px},
        {"min_side_points", o.outline_prior.min_side_points},
        {"min_measured_sides", o.outline_prior.min_measured_sides},
        {"neighbours", o.outline_prior.neighbours},
        {"radius_fraction", o.outline_prior.radius_fraction},
        {"prior_weight", o.outline_prior.prior_weight},
        {"agreement", o.outline_prior.agreement}}},
      {"refine",
       {{"lambda",
         {r.weights.iso, r.weights.dist, r.weights.fair3d, r.weights.fair2d, 0.0, o.outline_hold}},
        {"beta", {r.beta_point, r.beta_normal}},
        {"outlier_distance", r.outlier_distance},
        {"iso_normalization",
         r.iso_normalization == isometry::IsoNormalization::kStrain ? "strain" : "raw"},
        {"iso_edges", r.iso_edges},
        {"outline_hold", o.outline_hold},
        {"outline_hold_max_angle_deg", o.outline_hold_max_angle_deg},
        {"outline_hold_support", o.outline_hold_support},
        {"method", r.method == isometry::Method::kGaussNewton ? "gn" : "lbfgs"},
        {"max_outer_iterations", r.max_outer_iterations},
        {"relative_tolerance", r.relative_tolerance},
        {"converged_max_damping", r.converged_max_damping},
        {"threads", r.num_threads}}}};
}

Json ResultToJson(const Inputs& in, const Result& r, const Options& o, double read_seconds,
                  double write_seconds) {
  Json doc = MakeHeader("docunfold.init", 1, "init-mesh", OptionsToJson(o));
  doc["reference"] = in.reference.image;
  doc["grid"] = {{"nx", r.meshes.grid.nx},
                 {"ny", r.meshes.grid.ny},
                 {"quads", {r.meshes.grid.nx - 1, r.meshes.grid.ny - 1}},
                 {"source", r.grid_source}};
  doc["points"] = {{"total", r.points_total},
                   {"in_region", r.points_in_region},
                   {"used_for_depth", r.points_for_depth},
                   {"inliers", r.inliers},
                   {"outliers", r.points_in_region - r.inliers}};
  doc["depth"] = {{"neighbours", o.depth_neighbours},
                  {"rbf_scale_px", r.rbf_scale_px},
                  {"model", o.depth_model == DepthModel::kPlanar ? "planar" : "average"},
                  {"planar_neighbours", o.planar_neighbours},
                  {"planar_guard", o.planar_guard}};
  {
    const OutlinePriorResult& p = r.outline_prior;
    doc["outline_prior"] = {{"used", p.used},
                            {"sides_measured", p.measured_sides},
                            {"outline_points_per_side",
                             {{"top", p.side_points[0]},
                              {"right", p.side_points[1]},
                              {"bottom", p.side_points[2]},
                              {"left", p.side_points[3]}}},
                            {"mean_weight", p.mean_weight}};
    if (!p.note.empty()) doc["outline_prior"]["note"] = p.note;
  }
  doc["unfold"] = {{"method", "arap"}, {"iterations", r.unfold_iterations}};
  Json refine = isometry::ToJson(r.refine);
  if (!r.refine.iterations.empty()) {
    refine["F_initial"] = r.refine.iterations.front().F;
    refine["F_final"] = r.refine.iterations.back().F;
    refine["terms_final"] = isometry::ToJson(r.refine.iterations.back().terms);
  }
  doc["refine"] = refine;
  doc["quality"] = {{"isometry_edge_error_mean", r.isometry_error_mean},
                    {"isometry_edge_error_max", r.isometry_error_max},
                    {"mean_inlier_distance", r.mean_inlier_distance},
                    {"model_size", r.refine.model_size}};
  doc["upright"] = {{"rotation_deg", r.upright_rotation_deg}, {"from", r.upright_from}};
  doc["warnings"] = r.warnings;
  doc["timings_s"] = {
      {"read", read_seconds},       {"depth", r.timings.depth},
      {"grid", r.timings.grid},     {"unfold", r.timings.unfold},
      {"refine", r.timings.refine}, {"upright", r.timings.upright},
      {"write", write_seconds},     {"total", read_seconds + r.timings.total + write_seconds}};
  return doc;
}

void WriteOutputs(const fs::path& out_dir, const Inputs& in, const Result& r, const Options& o,
                  double read_seconds) {
  const auto start = Clock::now();
  EnsureDirectory(out_dir);
  MeshPairWriteOptions w;
  w.reference_camera = in.reference;
  w.reference_image = in.reference_image;
  w.comments = {
      std::string("init-mesh ") + ProgramVersion() + ": " + std::to_string(r.meshes.grid.nx - 1) +
          "x" + std::to_string(r.meshes.grid.ny - 1) + " quads (" + r.grid_source + ")",
      "refined: " + std::to_string(r.refine.iterations.size()) +
          " outer iterations, isometry edge error " + Fixed(100 * r.isometry_error_mean, 3) + " %"};
  // init.json last: its presence means the meshes beside it are complete.
  WriteMeshPair(out_dir, r.meshes, w);
  WriteJsonAtomic(out_dir / "init.json", ResultToJson(in, r, o, read_seconds, Since(start)));
}

}  // namespace docunfold::init_mesh
