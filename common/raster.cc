#include "common/raster.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace docunfold {

RasterResult Rasterize(const std::vector<Eigen::Vector3d>& v,
                       const std::vector<Triangle>& triangles, int width, int height,
                       double near_depth) {
  RasterResult r;
  r.depth = cv::Mat1f(height, width, std::numeric_limits<float>::infinity());
  r.face = cv::Mat1i(height, width, -1);
  r.bary = cv::Mat2f(height, width, cv::Vec2f(0, 0));
  for (size_t f = 0; f < triangles.size(); ++f) {
    const Eigen::Vector3d& a = v[triangles[f][0]];
    const Eigen::Vector3d& b = v[triangles[f][1]];
    const Eigen::Vector3d& c = v[triangles[f][2]];
    if (a.z() <= near_depth || b.z() <= near_depth || c.z() <= near_depth) continue;
    if (!a.allFinite() || !b.allFinite() || !c.allFinite()) continue;
    const double area = (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x());
    if (std::abs(area) < 1e-12) continue;
    const int x0 = std::max(0, int(std::ceil(std::min({a.x(), b.x(), c.x()}))));
    const int x1 = std::min(width - 1, int(std::floor(std::max({a.x(), b.x(), c.x()}))));
    const int y0 = std::max(0, int(std::ceil(std::min({a.y(), b.y(), c.y()}))));
    const int y1 = std::min(height - 1, int(std::floor(std::max({a.y(), b.y(), c.y()}))));
    if (x0 > x1 || y0 > y1) continue;
    const double inv_area = 1.0 / area;
    const double iza = 1.0 / a.z(), izb = 1.0 / b.z(), izc = 1.0 / c.z();
    // Edge functions are affine in x: evaluate at x0 and step.
    const double e_eps = -1e-9;
    for (int y = y0; y <= y1; ++y) {
      float* depth_row = r.depth.ptr<float>(y);
      int* face_row = r.face.ptr<int>(y);
      cv::Vec2f* bary_row = r.bary.ptr<cv::Vec2f>(y);
      for (int x = x0; x <= x1; ++x) {
        // Screen-space barycentrics of the pixel centre.
        const double l1 =
            ((x - a.x()) * (c.y() - a.y()) - (y - a.y()) * (c.x() - a.x())) * inv_area;
        const double l2 =
            ((b.x() - a.x()) * (y - a.y()) - (b.y() - a.y()) * (x - a.x())) * inv_area;
        const double l0 = 1.0 - l1 - l2;
        if (l0 < e_eps || l1 < e_eps || l2 < e_eps) continue;
        const double inv_z = l0 * iza + l1 * izb + l2 * izc;
        const float z = float(1.0 / inv_z);
        if (z >= depth_row[x]) continue;
        depth_row[x] = z;
        face_row[x] = int(f);
        bary_row[x] = cv::Vec2f(float(l1 * izb / inv_z), float(l2 * izc / inv_z));
      }
    }
  }
  return r;
}

RasterResult RasterizeMesh(const PinholeCamera& camera,
                           const std::vector<Eigen::Vector3d>& vertices,
                           const std::vector<Triangle>& triangles, double scale) {
  std::vector<Eigen::Vector3d> screen(vertices.size());
  for (size_t i = 0; i < vertices.size(); ++i) {
    const Eigen::Vector3d x_cam = camera.CamFromWorld(vertices[i]);
    const Eigen::Vector2d p = camera.ProjectCam(x_cam);
    // Pixel centres stay at integer coordinates under scaling.
    screen[i] = {(p.x() + 0.5) * scale - 0.5, (p.y() + 0.5) * scale - 0.5, x_cam.z()};
  }
  return Rasterize(screen, triangles, int(std::lround(camera.width * scale)),
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
