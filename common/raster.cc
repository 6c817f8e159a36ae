#include "common/raster.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace docunfold {

namespace internal {

// What Rasterize decides for one triangle: its integer pixel box, and per
// pixel centre whether it covers it and at which depth. Rasterize and
// PixelFaceIndex share it so that they decide every pixel alike.
struct ScreenTriangle {
  Eigen::Vector3d a, b, c;
  int x0 = 0, x1 = -1, y0 = 0, y1 = -1;
  double inv_area = 0, iza = 0, izb = 0, izc = 0;

  // False for triangles Rasterize skips (behind the near plane, not finite,
  // degenerate, or off the image).
  bool Set(const Eigen::Vector3d& va, const Eigen::Vector3d& vb, const Eigen::Vector3d& vc,
           int width, int height, double near_depth) {
    a = va;
    b = vb;
    c = vc;
    if (a.z() <= near_depth || b.z() <= near_depth || c.z() <= near_depth) return false;
    if (!a.allFinite() || !b.allFinite() || !c.allFinite()) return false;
    const double area = (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x());
    if (std::abs(area) < 1e-12) return false;
    x0 = std::max(0, int(std::ceil(std::min({a.x(), b.x(), c.x()}))));
    x1 = std::min(width - 1, int(std::floor(std::max({a.x(), b.x(), c.x()}))));
    y0 = std::max(0, int(std::ceil(std::min({a.y(), b.y(), c.y()}))));
    y1 = std::min(height - 1, int(std::floor(std::max({a.y(), b.y(), c.y()}))));
    if (x0 > x1 || y0 > y1) return false;
    inv_area = 1.0 / area;
    iza = 1.0 / a.z();
    izb = 1.0 / b.z();
    izc = 1.0 / c.z();
    return true;
  }

  // Whether the triangle covers pixel centre (x, y) (inside its box), with
  // its depth there and the perspective-correct (b1, b2).
  bool Covers(int x, int y, float* z, double* b1, double* b2) const {
    // Screen-space barycentrics of the pixel centre.
    const double l1 = ((x - a.x()) * (c.y() - a.y()) - (y - a.y()) * (c.x() - a.x())) * inv_area;
    const double l2 = ((b.x() - a.x()) * (y - a.y()) - (b.y() - a.y()) * (x - a.x())) * inv_area;
    const double l0 = 1.0 - l1 - l2;
    constexpr double kEdgeEps = -1e-9;
    if (l0 < kEdgeEps || l1 < kEdgeEps || l2 < kEdgeEps) return false;
    const double inv_z = l0 * iza + l1 * izb + l2 * izc;
    *z = float(1.0 / inv_z);
    if (b1) {
      *b1 = l1 * izb / inv_z;
      *b2 = l2 * izc / inv_z;
    }
    return true;
  }
};

}  // namespace internal

using internal::ScreenTriangle;

RasterResult Rasterize(const std::vector<Eigen::Vector3d>& v,
                       const std::vector<Triangle>& triangles, int width, int height,
                       double near_depth) {
  RasterResult r;
  r.depth = cv::Mat1f(height, width, std::numeric_limits<float>::infinity());
  r.face = cv::Mat1i(height, width, -1);
  r.bary = cv::Mat2f(height, width, cv::Vec2f(0, 0));
  ScreenTriangle t;
  for (size_t f = 0; f < triangles.size(); ++f) {
    if (!t.Set(v[triangles[f][0]], v[triangles[f][1]], v[triangles[f][2]], width, height,
               near_depth))
      continue;
    for (int y = t.y0; y <= t.y1; ++y) {
      float* depth_row = r.depth.ptr<float>(y);
      int* face_row = r.face.ptr<int>(y);
      cv::Vec2f* bary_row = r.bary.ptr<cv::Vec2f>(y);
      for (int x = t.x0; x <= t.x1; ++x) {
        float z;
        double b1, b2;
        if (!t.Covers(x, y, &z, &b1, &b2) || z >= depth_row[x]) continue;
        depth_row[x] = z;
        face_row[x] = int(f);
        bary_row[x] = cv::Vec2f(float(b1), float(b2));
      }
    }
  }
  return r;
}

PixelFaceIndex::PixelFaceIndex(const std::vector<Eigen::Vector3d>& v,
                               const std::vector<Triangle>& triangles, int width, int height,
                               double near_depth)
    : width_(width),
      height_(height),
      cells_x_(std::max(1, (width + kCell - 1) / kCell)),
      cells_y_(std::max(1, (height + kCell - 1) / kCell)) {
  ScreenTriangle t;
  for (size_t f = 0; f < triangles.size(); ++f)
    if (t.Set(v[triangles[f][0]], v[triangles[f][1]], v[triangles[f][2]], width, height,
              near_depth)) {
      screen_.push_back(t);
      face_.push_back(int(f));
    }
  // The cells triangle k's pixel box overlaps.
  auto for_each_cell = [&](size_t k, auto&& visit) {
    const ScreenTriangle& s = screen_[k];
    for (int cy = s.y0 / kCell; cy <= s.y1 / kCell; ++cy)
      for (int cx = s.x0 / kCell; cx <= s.x1 / kCell; ++cx) visit(size_t(cy) * cells_x_ + cx);
  };
  // Count, then fill: every cell lists its triangles in ascending order,
  // the order Rasterize draws them in.
  cell_start_.assign(size_t(cells_x_) * cells_y_ + 1, 0);
  for (size_t k = 0; k < screen_.size(); ++k)
    for_each_cell(k, [&](size_t cell) { ++cell_start_[cell + 1]; });
  for (size_t i = 1; i < cell_start_.size(); ++i) cell_start_[i] += cell_start_[i - 1];
  std::vector<int> next(cell_start_.begin(), cell_start_.end() - 1);
  cell_triangles_.resize(size_t(cell_start_.back()));
  for (size_t k = 0; k < screen_.size(); ++k)
    for_each_cell(k, [&](size_t cell) { cell_triangles_[size_t(next[cell]++)] = int(k); });
}

PixelFaceIndex::~PixelFaceIndex() = default;
PixelFaceIndex::PixelFaceIndex(const PixelFaceIndex&) = default;
PixelFaceIndex::PixelFaceIndex(PixelFaceIndex&&) noexcept = default;

int PixelFaceIndex::operator()(int x, int y) const {
  if (x < 0 || y < 0 || x >= width_ || y >= height_) return -1;
  const size_t cell = size_t(y / kCell) * cells_x_ + x / kCell;
  int best = -1;
  float best_z = std::numeric_limits<float>::infinity();
  for (int k = cell_start_[cell]; k < cell_start_[cell + 1]; ++k) {
    const size_t i = size_t(cell_triangles_[size_t(k)]);
    const ScreenTriangle& t = screen_[i];
    if (x < t.x0 || x > t.x1 || y < t.y0 || y > t.y1) continue;
    float z;
    if (!t.Covers(x, y, &z, nullptr, nullptr) || z >= best_z) continue;
    best_z = z;
    best = face_[i];
  }
  return best;
}

std::vector<Eigen::Vector3d> ScreenVertices(const PinholeCamera& camera,
                                            const std::vector<Eigen::Vector3d>& vertices,
                                            double scale) {
  std::vector<Eigen::Vector3d> screen(vertices.size());
  for (size_t i = 0; i < vertices.size(); ++i) {
    const Eigen::Vector3d x_cam = camera.CamFromWorld(vertices[i]);
    const Eigen::Vector2d p = camera.ProjectCam(x_cam);
    // Pixel centres stay at integer coordinates under scaling.
    screen[i] = {(p.x() + 0.5) * scale - 0.5, (p.y() + 0.5) * scale - 0.5, x_cam.z()};
  }
  return screen;
}

RasterResult RasterizeMesh(const PinholeCamera& camera,
                           const std::vector<Eigen::Vector3d>& vertices,
                           const std::vector<Triangle>& triangles, double scale) {
  return Rasterize(ScreenVertices(camera, vertices, scale), triangles,
                   int(std::lround(camera.width * scale)), int(std::lround(camera.height * scale)));
}

PixelFaceIndex MeshFaceIndex(const PinholeCamera& camera,
                             const std::vector<Eigen::Vector3d>& vertices,
                             const std::vector<Triangle>& triangles, double scale) {
  return PixelFaceIndex(ScreenVertices(camera, vertices, scale), triangles,
                        int(std::lround(camera.width * scale)),
                        int(std::lround(camera.height * scale)));
}

cv::Mat InterpolateAttributes(const RasterResult& raster, const std::vector<Triangle>& triangles,
                              const Eigen::MatrixXf& attributes) {
  const int channels = int(attributes.cols());
  cv::Mat out(raster.face.size(), CV_32FC(channels));
  // Scalars hold at most four channels: fill through a one-channel view.
  out.reshape(1).setTo(std::numeric_limits<float>::quiet_NaN());
  for (int y = 0; y < out.rows; ++y) {
    const int* face_row = raster.face.ptr<int>(y);
    const cv::Vec2f* bary_row = raster.bary.ptr<cv::Vec2f>(y);
    float* out_row = out.ptr<float>(y);
    for (int x = 0; x < out.cols; ++x) {
      const int f = face_row[x];
      if (f < 0) continue;
      const float b1 = bary_row[x][0], b2 = bary_row[x][1], b0 = 1 - b1 - b2;
      const Triangle& t = triangles[f];
      for (int c = 0; c < channels; ++c)
        out_row[x * channels + c] =
            b0 * attributes(t[0], c) + b1 * attributes(t[1], c) + b2 * attributes(t[2], c);
    }
  }
  return out;
}

std::vector<Triangle> Triangulate(const std::vector<std::vector<int>>& faces) {
  std::vector<Triangle> tris;
  tris.reserve(faces.size() * 2);
  for (const auto& f : faces)
    for (size_t k = 1; k + 1 < f.size(); ++k) tris.push_back({f[0], f[k], f[k + 1]});
  return tris;
}

}  // namespace docunfold
