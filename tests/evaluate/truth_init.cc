#include "tests/evaluate/truth_init.h"

#include <stdexcept>

#include "stages/evaluate/geometry_metrics.h"

namespace docunfold::testing {

MeshPair TrueSurfaceOnGrid(const GroundTruth& gt, const CameraSet& sfm_cameras,
                           const QuadGrid& grid) {
  if (grid.nx < 2 || grid.ny < 2)
    throw std::runtime_error("a grid of " + std::to_string(grid.nx) + " x " +
                             std::to_string(grid.ny) + " vertices has no quad");
  std::string why_not;
  const auto alignment = evaluate::AlignCameras(sfm_cameras, gt.cameras, &why_not);
  if (!alignment) throw std::runtime_error(why_not);
  const evaluate::Similarity& truth_from_sfm = alignment->truth_from_sfm;
  const Eigen::Matrix3d sfm_from_truth_R = truth_from_sfm.R.transpose();
  const double sfm_from_truth_scale = 1.0 / truth_from_sfm.scale;

  MeshPair m;
  m.grid = grid;
  for (int row = 0; row < grid.ny; ++row) {
    for (int col = 0; col < grid.nx; ++col) {
      const double s = double(col) / (grid.nx - 1), t = double(row) / (grid.ny - 1);
      // SurfacePoint's pixel convention: s = 0 is the left edge of pixel 0.
      const Eigen::Vector2d flat_px(s * gt.flat_width - 0.5, t * gt.flat_height - 0.5);
      const std::optional<Eigen::Vector3d> x = gt.SurfacePoint(flat_px);
      if (!x)
        throw std::runtime_error("the true surface has no point at s " + std::to_string(s) +
                                 ", t " + std::to_string(t));
      m.mesh3d.push_back(sfm_from_truth_scale * (sfm_from_truth_R * (*x - truth_from_sfm.t)));
      m.mesh2d.emplace_back(s * gt.width_m * sfm_from_truth_scale,
                            t * gt.height_m * sfm_from_truth_scale);
    }
  }
  return m;
}

}  // namespace docunfold::testing
