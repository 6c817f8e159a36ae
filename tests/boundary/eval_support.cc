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
    if (score > best_score) {
      best_score = score;
      best = int(i);
    }
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

}  // namespace docunfold::testing
