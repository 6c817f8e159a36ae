#include "stages/report/mesh_views.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "common/raster.h"

namespace docunfold::report {

cv::Mat RenderMeshView(const MeshPair& mesh, const PinholeCamera& reference, const cv::Mat& texture,
                       const std::vector<Eigen::Vector3d>& points, const MeshViewOptions& o) {
  const auto& V = mesh.mesh3d;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (const auto& v : V) centre += v;
  centre /= double(V.size());
  double radius = 0;
  for (const auto& v : V) radius = std::max(radius, (v - centre).norm());

  // The virtual camera: the reference camera's orientation, turned.
  const double kDeg = 3.14159265358979 / 180;
  const Eigen::Matrix3d turn = (Eigen::AngleAxisd(o.pitch_deg * kDeg, Eigen::Vector3d::UnitX()) *
                                Eigen::AngleAxisd(o.yaw_deg * kDeg, Eigen::Vector3d::UnitY()))
                                   .toRotationMatrix();
  PinholeCamera cam;
  cam.width = o.width;
  cam.height = o.height;
  const double f = 0.5 * std::min(o.width, o.height) / std::tan(20 * kDeg);
  cam.K << f, 0, (o.width - 1) / 2.0, 0, f, (o.height - 1) / 2.0, 0, 0, 1;
  cam.R = turn * reference.R;
  const double distance = radius / std::tan(20 * kDeg) * 1.1;
  const Eigen::Vector3d eye = centre - cam.R.transpose() * Eigen::Vector3d(0, 0, distance);
  cam.t = -cam.R * eye;

  const std::vector<Triangle> tris = mesh.grid.Triangles();
  RasterResult raster = RasterizeMesh(cam, V, tris);

  // Per-vertex normals (from the grid) and texture coordinates.
  const QuadGrid& g = mesh.grid;
  auto at = [&](int r, int c) {
    return V[g.Index(std::clamp(r, 0, g.ny - 1), std::clamp(c, 0, g.nx - 1))];
  };
  Eigen::MatrixXf attributes(V.size(), 5);
  for (int r = 0; r < g.ny; ++r)
    for (int c = 0; c < g.nx; ++c) {
      const int i = g.Index(r, c);
      const Eigen::Vector3d n =
          (at(r, c + 1) - at(r, c - 1)).cross(at(r + 1, c) - at(r - 1, c)).normalized();
      const Eigen::Vector2d uv = reference.Project(V[i]);
      attributes.row(i) << float(uv.x()), float(uv.y()), float(n.x()), float(n.y()), float(n.z());
    }
  cv::Mat attr = InterpolateAttributes(raster, tris, attributes);

  cv::Mat3b out(o.height, o.width, cv::Vec3b(250, 250, 250));
  cv::Mat map_x(o.height, o.width, CV_32F), map_y(o.height, o.width, CV_32F);
  for (int y = 0; y < o.height; ++y)
    for (int x = 0; x < o.width; ++x) {
      const float* a = attr.ptr<float>(y) + 5 * x;
      map_x.at<float>(y, x) = a[0];
      map_y.at<float>(y, x) = a[1];
    }
  cv::Mat sampled;
  if (!texture.empty())
    cv::remap(texture, sampled, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  // A headlight from the virtual camera, plus ambient.
  const Eigen::Vector3d light = (cam.R.transpose() * Eigen::Vector3d(0.3, -0.4, -1)).normalized();
  for (int y = 0; y < o.height; ++y)
    for (int x = 0; x < o.width; ++x) {
      if (raster.face(y, x) < 0) continue;
      const float* a = attr.ptr<float>(y) + 5 * x;
      const Eigen::Vector3d n = Eigen::Vector3d(a[2], a[3], a[4]).normalized();
      const double shade = 0.45 + 0.55 * std::abs(n.dot(light));
      cv::Vec3b base(200, 205, 215);
      if (!sampled.empty()) base = sampled.at<cv::Vec3b>(y, x);
      out(y, x) = cv::Vec3b(cv::saturate_cast<uchar>(base[0] * shade),
                            cv::saturate_cast<uchar>(base[1] * shade),
                            cv::saturate_cast<uchar>(base[2] * shade));
    }

  // Wireframe: every k-th grid line, drawn where it is not hidden.
  auto visible = [&](const Eigen::Vector3d& p, cv::Point2d* px) {
    const Eigen::Vector3d xc = cam.CamFromWorld(p);
    if (xc.z() <= 0) return false;
    const Eigen::Vector2d q = cam.ProjectCam(xc);
    *px = cv::Point2d(q.x(), q.y());
    const int ix = int(std::lround(q.x())), iy = int(std::lround(q.y()));
    if (ix < 0 || iy < 0 || ix >= o.width || iy >= o.height) return false;
    return xc.z() <= raster.depth(iy, ix) * 1.01 + 1e-9;
  };
  const int step_r = std::max(1, (g.ny - 1) / o.max_wire_lines);
  const int step_c = std::max(1, (g.nx - 1) / o.max_wire_lines);
  const cv::Scalar wire(90, 60, 30);
  auto segment = [&](int a, int b) {
    cv::Point2d pa, pb, pm;
    if (visible(V[a], &pa) && visible(V[b], &pb) && visible((V[a] + V[b]) / 2, &pm))
      cv::line(out, pa * 16, pb * 16, wire, 1, cv::LINE_AA, 4);
  };
  for (int r = 0; r < g.ny; r += step_r)
    for (int c = 0; c + 1 < g.nx; ++c) segment(g.Index(r, c), g.Index(r, c + 1));
  for (int c = 0; c < g.nx; c += step_c)
    for (int r = 0; r + 1 < g.ny; ++r) segment(g.Index(r, c), g.Index(r + 1, c));
  for (int r = 0; r + 1 < g.ny; ++r) segment(g.Index(r, g.nx - 1), g.Index(r + 1, g.nx - 1));
  for (int c = 0; c + 1 < g.nx; ++c) segment(g.Index(g.ny - 1, c), g.Index(g.ny - 1, c + 1));

  // SfM points near or in front of the surface.
  const size_t stride = std::max<size_t>(1, points.size() / std::max(1, o.max_points));
  for (size_t i = 0; i < points.size(); i += stride) {
    const Eigen::Vector3d xc = cam.CamFromWorld(points[i]);
    if (xc.z() <= 0) continue;
    const Eigen::Vector2d q = cam.ProjectCam(xc);
    const int ix = int(std::lround(q.x())), iy = int(std::lround(q.y()));
    if (ix < 0 || iy < 0 || ix >= o.width || iy >= o.height) continue;
    if (xc.z() > raster.depth(iy, ix) * 1.01) continue;
    cv::circle(out, cv::Point(ix, iy), 2, cv::Scalar(40, 40, 220), cv::FILLED, cv::LINE_AA);
  }
  return out;
}

}  // namespace docunfold::report
