#include "stages/optimize/mask_hull.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

namespace docunfold::optimize {
namespace {

// The vertex as a point on the meshes (a corner of one of its quads).
SurfacePoint VertexPoint(const QuadGrid& grid, int row, int col) {
  const int qr = std::min(row, grid.ny - 2), qc = std::min(col, grid.nx - 2);
  const int q = qr * (grid.nx - 1) + qc;
  const int dr = row - qr, dc = col - qc;  // corner (dr, dc) of quad q
  SurfacePoint p;
  if (dr == 1 && dc == 0) {  // corner 3: triangle 2q+1 holds corners 0 2 3
    p.triangle = 2 * q + 1;
    p.bary = Eigen::Vector3d(0, 0, 1);
    return p;
  }
  p.triangle = 2 * q;
  const int corner = dr == 0 ? dc : 2;  // 0, 1 or 2
  p.bary = Eigen::Vector3d::Zero();
  p.bary[corner] = 1;
  return p;
}

// Bilinear interpolation with double weights (common/image_sampling.h's
// SampleBilinear weighs in float), clamped to the image.
float Bilinear(const cv::Mat1f& m, double x, double y) {
  const int x0 = std::clamp(int(std::floor(x)), 0, m.cols - 2);
  const int y0 = std::clamp(int(std::floor(y)), 0, m.rows - 2);
  const double fx = std::clamp(x - x0, 0.0, 1.0), fy = std::clamp(y - y0, 0.0, 1.0);
  return float((1 - fy) * ((1 - fx) * m(y0, x0) + fx * m(y0, x0 + 1)) +
               fy * ((1 - fx) * m(y0 + 1, x0) + fx * m(y0 + 1, x0 + 1)));
}

}  // namespace

std::vector<HullView> PrepareHullViews(const std::vector<ViewPage>& pages, int max_side) {
  std::vector<HullView> views;
  for (const ViewPage& page : pages) {
    HullView v;
    v.camera = page.camera;
    v.distortion = page.distortion;
    v.scale = std::min(1.0, double(max_side) / std::max(page.mask.cols, page.mask.rows));
    cv::Mat1b outside_pixels = page.mask == 0;
    if (v.scale < 1)
      cv::resize(outside_pixels, outside_pixels, cv::Size(), v.scale, v.scale, cv::INTER_AREA);
    cv::distanceTransform(outside_pixels, v.outside, cv::DIST_L2, cv::DIST_MASK_PRECISE);
    if (v.scale < 1) v.outside /= v.scale;
    cv::Sobel(v.outside, v.dx, CV_32F, 1, 0, 3, 1.0 / 8);
    cv::Sobel(v.outside, v.dy, CV_32F, 0, 1, 3, 1.0 / 8);
    v.doubt = cv::Mat1b::zeros(v.outside.size());
    views.push_back(std::move(v));
  }
  return views;
}

std::vector<HullViewCheck> MarkMaskDoubts(const std::vector<Eigen::Vector3d>& points,
                                          const HullOptions& o, std::vector<HullView>* views) {
  std::vector<HullViewCheck> checks;
  for (HullView& v : *views) {
    v.doubt = cv::Mat1b::zeros(v.outside.size());
    int out = 0, seen = 0;
    for (const Eigen::Vector3d& x : points) {
      const auto photo = ProjectDistorted(v.camera, v.distortion, x);
      if (!photo) continue;
      const Eigen::Vector2d u = v.scale * *photo;
      if (u.x() < 0 || u.y() < 0 || u.x() > v.outside.cols - 1 || u.y() > v.outside.rows - 1)
        continue;
      ++seen;
      if (Bilinear(v.outside, u.x(), u.y()) <= o.outside_px) continue;
      cv::circle(v.doubt, cv::Point(int(std::lround(u.x())), int(std::lround(u.y()))),
                 int(std::lround(v.scale * o.doubt_radius_px)), 255, cv::FILLED);
      ++out;
    }
    const bool used = out <= o.max_points_outside * seen;
    if (!used) v.doubt.setTo(255);
    checks.push_back({v.camera.image, seen, out, used});
  }
  return checks;
}

cv::Mat1b PageInterior(const cv::Mat1b& reference_page, const HullOptions& o) {
  cv::Mat1b inner;
  const int k = 2 * int(std::ceil(o.page_inset_px)) + 1;
  cv::erode(reference_page, inner, cv::getStructuringElement(cv::MORPH_ELLIPSE, {k, k}));
  return inner;
}

std::vector<isometry::Marker> HullMarkers(const MeshPair& meshes, const PinholeCamera& reference,
                                          const cv::Mat1b& page_interior,
                                          const std::vector<HullView>& views,
                                          const HullOptions& o) {
  std::vector<isometry::Marker> markers;
  const QuadGrid& g = meshes.grid;
  const int step = std::max(1, (std::max(g.nx, g.ny) - 1) / std::max(1, o.lattice_rows - 1));
  for (int row = 0; row < g.ny; row += step)
    for (int col = 0; col < g.nx; col += step) {
      const Eigen::Vector3d& x = meshes.mesh3d[g.Index(row, col)];
      if (reference.CamFromWorld(x).z() <= 0) continue;
      const Eigen::Vector2d r = reference.Project(x);
      const int rx = int(std::lround(r.x())), ry = int(std::lround(r.y()));
      if (rx < 0 || ry < 0 || rx >= page_interior.cols || ry >= page_interior.rows ||
          !page_interior(ry, rx))
        continue;
      for (const HullView& v : views) {
        const auto photo = ProjectDistorted(v.camera, v.distortion, x);
        if (!photo) continue;
        const double b = v.scale * o.image_border_px;
        const Eigen::Vector2d u = v.scale * *photo;
        if (u.x() < b || u.y() < b || u.x() > v.outside.cols - 1 - b ||
            u.y() > v.outside.rows - 1 - b)
          continue;
        if (v.doubt(int(std::lround(u.y())), int(std::lround(u.x())))) continue;
        const double d = Bilinear(v.outside, u.x(), u.y());
        if (d <= o.outside_px) continue;
        Eigen::Vector2d grad(Bilinear(v.dx, u.x(), u.y()), Bilinear(v.dy, u.x(), u.y()));
        if (grad.norm() < 1e-3) continue;
        grad.normalize();
        // The outline's nearest point and its tangent, as undistorted pixels.
        const Eigen::Vector2d edge = *photo - d * grad;
        const Eigen::Vector2d tangent(-grad.y(), grad.x());
        const auto e = UndistortPixels(v.camera.K, v.distortion, {edge, edge + 10 * tangent});
        const Eigen::Vector2d e0 = e[0], e1 = e[1];
        const Eigen::Vector3d d0 = v.camera.RayDirection(e0);
        const Eigen::Vector3d d1 = v.camera.RayDirection(e1);
        Eigen::Vector3d across = d0.cross(d1);
        if (across.norm() < 1e-12) continue;
        across.normalize();
        isometry::Marker m;
        m.where = VertexPoint(g, row, col);
        m.ray_origin = v.camera.Center();
        m.ray_direction = d0;
        m.across = across;
        m.weight = o.weight;
        markers.push_back(m);
      }
    }
  return markers;
}

}  // namespace docunfold::optimize
