#include "tests/boundary/eval_support.h"

#include <algorithm>
#include <cmath>

#include <opencv2/imgcodecs.hpp>

#include "tests/support/test_support.h"

namespace docunfold::testing {

std::vector<fs::path> DataSetsWithTruth() {
  std::vector<fs::path> sets;
  for (const fs::path& base : {SourceDir() / "samples", RealisticDir()}) {
    std::error_code ec;
    if (base.empty() || !fs::is_directory(base, ec)) continue;
    for (const auto& e : fs::directory_iterator(base))
      if (fs::is_regular_file(e.path() / "ground_truth" / "cameras.json", ec) &&
          fs::is_directory(e.path() / "images", ec))
        sets.push_back(e.path());
  }
  std::sort(sets.begin(), sets.end());
  return sets;
}

std::string DataSetName(const fs::path& dataset) {
  return dataset.parent_path().filename().string() + "/" + dataset.filename().string();
}

int MostFrontalView(const GroundTruth& gt) {
  // Page centre and mean normal from the true surface.
  Eigen::Vector3d centre = Eigen::Vector3d::Zero(), normal = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& v : gt.mesh.vertices) centre += v;
  centre /= double(gt.mesh.vertices.size());
  for (const Triangle& t : gt.triangles) {
    const auto& a = gt.mesh.vertices[t[0]];
    normal += (gt.mesh.vertices[t[1]] - a).cross(gt.mesh.vertices[t[2]] - a);
  }
  normal.normalize();
  int best = 0;
  double best_score = -1;
  for (size_t i = 0; i < gt.cameras.views.size(); ++i) {
    const PinholeCamera& cam = gt.cameras.views[i];
    bool all_in = true;
    for (const Eigen::Vector2d& c : TrueCorners(gt, cam))
      all_in = all_in && c.x() >= 0 && c.y() >= 0 && c.x() < cam.width && c.y() < cam.height;
    const double score =
        std::abs(normal.dot((centre - cam.Center()).normalized())) + (all_in ? 1.0 : 0.0);
    if (score > best_score) { best_score = score; best = int(i); }
  }
  return best;
}

cv::Mat ReadView(const GroundTruth& gt, const PinholeCamera& camera) {
  return cv::imread((gt.root / "images" / camera.image).string(), cv::IMREAD_COLOR);
}

PinholeCamera CropCamera(const PinholeCamera& camera, const cv::Rect& crop) {
  PinholeCamera c = camera;
  c.K(0, 2) -= crop.x;
  c.K(1, 2) -= crop.y;
  c.width = crop.width;
  c.height = crop.height;
  return c;
}

std::vector<std::vector<Eigen::Vector2d>> TrueOutlineInView(const GroundTruth& gt,
                                                            const PinholeCamera& camera,
                                                            double step_px) {
  RasterResult depth = RasterizeMesh(camera, gt.mesh.vertices, gt.triangles);
  const double w = gt.flat_width - 1.0, h = gt.flat_height - 1.0;
  // Slightly inside the page so that every sample finds a surface point.
  const double e = 0.5;
  const Eigen::Vector2d corners[4] = {{e, e}, {w - e, e}, {w - e, h - e}, {e, h - e}};
  std::vector<std::vector<Eigen::Vector2d>> out;
  std::vector<Eigen::Vector2d> piece;
  auto flush = [&] {
    if (piece.size() >= 2) out.push_back(piece);
    piece.clear();
  };
  for (int k = 0; k < 4; ++k) {
    const Eigen::Vector2d a = corners[k], b = corners[(k + 1) % 4];
    const int n = std::max(1, int(std::ceil((b - a).norm() / step_px)));
    for (int j = 0; j <= n; ++j) {
      auto p3 = gt.SurfacePoint(a + (b - a) * (double(j) / n));
      bool visible = false;
      Eigen::Vector2d px;
      if (p3) {
        const Eigen::Vector3d xc = camera.CamFromWorld(*p3);
        px = camera.ProjectCam(xc);
        const int x = int(std::lround(px.x())), y = int(std::lround(px.y()));
        visible = xc.z() > 0 && x >= 0 && y >= 0 && x < camera.width && y < camera.height &&
                  xc.z() <= depth.depth(y, x) * (1 + 2e-3);
      }
      if (visible) piece.push_back(px); else flush();
    }
    flush();  // sides are kept apart
  }
  return out;
}

std::array<CornerView, 4> TrueCornersInView(const GroundTruth& gt, const PinholeCamera& camera,
                                            double margin_px) {
  RasterResult depth = RasterizeMesh(camera, gt.mesh.vertices, gt.triangles);
  const double w = gt.flat_width - 1.0, h = gt.flat_height - 1.0, e = 0.5;
  const Eigen::Vector2d corners[4] = {{e, e}, {w - e, e}, {w - e, h - e}, {e, h - e}};
  std::array<CornerView, 4> out;
  out.fill(CornerView::kOutside);
  for (int i = 0; i < 4; ++i) {
    auto p3 = gt.SurfacePoint(corners[i]);
    if (!p3) continue;
    const Eigen::Vector3d xc = camera.CamFromWorld(*p3);
    const Eigen::Vector2d px = camera.ProjectCam(xc);
    if (xc.z() <= 0 || px.x() < margin_px || px.y() < margin_px ||
        px.x() > camera.width - 1 - margin_px || px.y() > camera.height - 1 - margin_px)
      continue;
    // Hidden when the surface in front of it is clearly nearer (a few pixels
    // around, since the corner sits on the silhouette).
    bool hidden = false;
    const int x = int(std::lround(px.x())), y = int(std::lround(px.y()));
    int covered = 0, nearer = 0;
    for (int dy = -2; dy <= 2; ++dy)
      for (int dx = -2; dx <= 2; ++dx) {
        const float d = depth.depth(y + dy, x + dx);
        if (!std::isfinite(d)) continue;
        ++covered;
        nearer += d < xc.z() * (1 - 5e-3);
      }
    hidden = covered > 0 && nearer > covered / 2;
    out[i] = hidden ? CornerView::kHidden : CornerView::kVisible;
  }
  return out;
}

double ProjectedDiagonal(const GroundTruth& gt, const PinholeCamera& camera) {
  const auto c = TrueCorners(gt, camera);
  return 0.5 * ((c[2] - c[0]).norm() + (c[3] - c[1]).norm());
}

double DistanceToPolylines(const Eigen::Vector2d& p,
                           const std::vector<std::vector<Eigen::Vector2d>>& lines) {
  double best = 1e300;
  for (const auto& l : lines)
    for (size_t i = 0; i + 1 < l.size(); ++i) {
      const Eigen::Vector2d a = l[i], d = l[i + 1] - l[i];
      const double t = d.squaredNorm() > 0 ? std::clamp((p - a).dot(d) / d.squaredNorm(), 0.0, 1.0) : 0.0;
      best = std::min(best, (a + t * d - p).norm());
    }
  return best;
}

double IntersectionOverUnion(const cv::Mat1b& a, const cv::Mat1b& b) {
  const double inter = cv::countNonZero(a & b), uni = cv::countNonZero(a | b);
  return uni > 0 ? inter / uni : 0.0;
}

}  // namespace docunfold::testing
