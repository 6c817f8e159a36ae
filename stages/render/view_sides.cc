#include "stages/render/view_sides.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "common/statistics.h"
#include "stages/render/render.h"

namespace docunfold::render {

namespace {

// cos between the ray of `pixel` and the normal of the triangle it meets
// (by the triangle's winding): its sign tells which side of M the camera sees.
double RayCos(const MeshPair& mesh, const PinholeCamera& camera, const SurfacePoint& at,
              const Eigen::Vector2d& pixel) {
  const Triangle t = mesh.grid.TriangleOf(at.triangle);
  const Eigen::Vector3d normal = (mesh.mesh3d[t[1]] - mesh.mesh3d[t[0]])
                                     .cross(mesh.mesh3d[t[2]] - mesh.mesh3d[t[0]])
                                     .normalized();
  return normal.dot(camera.RayDirection(pixel));
}

// The sign of RayCos over most of M seen from `camera`: the side of the page
// it faces.
double FacingSign(const MeshPair& mesh, const PinholeCamera& camera) {
  std::vector<double> cos;
  const Eigen::Vector3d center = camera.Center();
  for (const Triangle& t : mesh.grid.Triangles()) {
    const Eigen::Vector3d a = mesh.mesh3d[t[0]], b = mesh.mesh3d[t[1]], c = mesh.mesh3d[t[2]];
    const Eigen::Vector3d normal = (b - a).cross(c - a).normalized();
    cos.push_back(normal.dot(((a + b + c) / 3 - center).normalized()));
  }
  return Median(cos) < 0 ? -1.0 : 1.0;
}

double DistanceToLine(const SideFit& side, const Eigen::Vector2d& p) {
  const Eigen::Vector2d normal(-side.direction.y(), side.direction.x());
  return std::abs(normal.dot(p - side.point));
}

}  // namespace

std::vector<OutlineOnMesh> CastOutlineOntoMesh(const MeshPair& mesh, const ViewMask& view,
                                               double frame_margin) {
  std::vector<std::vector<cv::Point>> contours;
  cv::findContours(view.mask.clone(), contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_NONE);
  if (contours.empty()) return {};
  const auto outer =
      std::max_element(contours.begin(), contours.end(),
                       [](const auto& a, const auto& b) { return a.size() < b.size(); });
  const double margin = frame_margin * std::hypot(view.mask.cols, view.mask.rows);
  std::vector<Eigen::Vector2d> photo_pixels;
  for (const cv::Point& p : *outer)
    if (p.x >= margin && p.y >= margin && p.x <= view.mask.cols - 1 - margin &&
        p.y <= view.mask.rows - 1 - margin)
      photo_pixels.emplace_back(p.x + 0.5, p.y + 0.5);
  const PixelToSurface lookup(mesh, view.camera);
  std::vector<OutlineOnMesh> out;
  for (const Eigen::Vector2d& pixel :
       UndistortPixels(view.camera.K, view.distortion, photo_pixels)) {
    const auto at = lookup.Lookup(pixel);
    if (at) out.push_back({PointOnMesh2d(mesh, *at), RayCos(mesh, view.camera, *at, pixel)});
  }
  return out;
}

std::optional<double> MedianRayCos(const MeshPair& mesh, const PinholeCamera& camera,
                                   const PixelToSurface& lookup,
                                   const std::vector<Eigen::Vector2d>& pixels) {
  std::vector<double> cos;
  for (const Eigen::Vector2d& pixel : pixels)
    if (const auto at = lookup.Lookup(pixel))
      cos.push_back(std::abs(RayCos(mesh, camera, *at, pixel)));
  if (cos.empty()) return std::nullopt;
  return Median(cos);
}

std::array<SidePlacement, 4> PlaceEdgeOnSides(
    const MeshPair& mesh, const PinholeCamera& reference, const PixelToSurface& lookup,
    const Boundary& boundary, const std::array<SideFit, 4>& sides,
    const std::vector<ViewMask>& views, double flat_diagonal, const EdgeOnSideOptions& options) {
  std::array<SidePlacement, 4> placed;
  std::array<bool, 4> edge_on{};
  for (int i = 0; i < 4; ++i) {
    if (!sides[i].used) continue;
    placed[i].reference_cos = MedianRayCos(mesh, reference, lookup, boundary.sides[i].points);
    edge_on[i] = placed[i].reference_cos && *placed[i].reference_cos < options.max_cos;
  }
  if (std::none_of(edge_on.begin(), edge_on.end(), [](bool e) { return e; })) return placed;
  const double near = options.near_side * flat_diagonal;
  const double facing = FacingSign(mesh, reference);
  for (const ViewMask& view : views) {
    std::array<std::vector<OutlineOnMesh>, 4> on_side;
    for (const OutlineOnMesh& s : CastOutlineOntoMesh(mesh, view, options.frame_margin)) {
      // The nearest used side, if near enough and clear of the others.
      int nearest = -1;
      double first = HUGE_VAL, second = HUGE_VAL;
      for (int i = 0; i < 4; ++i) {
        if (!sides[i].used) continue;
        const double d = DistanceToLine(sides[i], s.flat);
        if (d < first) {
          second = first;
          first = d;
          nearest = i;
        } else {
          second = std::min(second, d);
        }
      }
      // A photo that sees the page from behind there sees a fold's edge as
      // readily as the page's (r03's flap, whose dark back one photo's
      // mask leaves out).
      if (s.cos * facing <= 0) continue;
      if (nearest >= 0 && edge_on[nearest] && first <= near && second >= 2 * near)
        on_side[nearest].push_back(s);
    }
    for (int i = 0; i < 4; ++i) {
      if (int(on_side[i].size()) < options.min_samples) continue;
      std::vector<double> cos;
      for (const auto& s : on_side[i]) cos.push_back(std::abs(s.cos));
      const double median = Median(cos);
      const bool better = placed[i].view.empty()
                              ? AlongSurface(*placed[i].reference_cos) - AlongSurface(median) >=
                                    options.min_tan_saving
                              : median > placed[i].view_cos;
      if (!better) continue;
      placed[i].view = view.camera.image;
      placed[i].view_cos = median;
      placed[i].flat.clear();
      for (const auto& s : on_side[i]) placed[i].flat.push_back(s.flat);
    }
  }
  return placed;
}

}  // namespace docunfold::render
