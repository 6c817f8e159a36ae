#include "tests/evaluate/truth_init.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>

#include "stages/evaluate/geometry_metrics.h"

namespace docunfold::testing {

namespace {

// The true surface at page coordinates (s, t) in [0, 1]^2.
Eigen::Vector3d PagePoint(const GroundTruth& gt, double s, double t) {
  // SurfacePoint's pixel convention: s = 0 is the left edge of pixel 0.
  const std::optional<Eigen::Vector3d> x =
      gt.SurfacePoint({s * gt.flat_width - 0.5, t * gt.flat_height - 0.5});
  if (!x)
    throw std::runtime_error("the true surface has no point at s " + std::to_string(s) + ", t " +
                             std::to_string(t));
  return *x;
}

// The true surface at (s, t), continued past the page's border in the
// tangent plane there (unit length per metre of page, so still isometric).
Eigen::Vector3d ContinuedPagePoint(const GroundTruth& gt, double s, double t) {
  const double sc = std::clamp(s, 0.0, 1.0), tc = std::clamp(t, 0.0, 1.0);
  const Eigen::Vector3d at = PagePoint(gt, sc, tc);
  if (sc == s && tc == t) return at;
  constexpr double kStep = 0.01;  // of the page, for the tangents
  const double s0 = std::min(sc, 1 - kStep), t0 = std::min(tc, 1 - kStep);
  const Eigen::Vector3d along_s =
      (PagePoint(gt, s0 + kStep, tc) - PagePoint(gt, s0, tc)).normalized();
  Eigen::Vector3d along_t = PagePoint(gt, sc, t0 + kStep) - PagePoint(gt, sc, t0);
  along_t = (along_t - along_t.dot(along_s) * along_s).normalized();
  return at + (s - sc) * gt.width_m * along_s + (t - tc) * gt.height_m * along_t;
}

// The quarter turn taking flat.png's axes (page x right, y down) to the way
// `reference` shows the page, as a matrix with entries in {-1, 0, 1}:
// init-mesh's M' is upright in the reference view, its sides named there.
Eigen::Matrix2d QuarterTurnInView(const GroundTruth& gt, const PinholeCamera& reference,
                                  const evaluate::Similarity& truth_from_sfm) {
  const Eigen::Matrix3d R = truth_from_sfm.R.transpose();
  auto pixel = [&](double s, double t) {
    return reference.Project(R * (PagePoint(gt, s, t) - truth_from_sfm.t) / truth_from_sfm.scale);
  };
  const Eigen::Vector2d along_s = (pixel(0.6, 0.5) - pixel(0.4, 0.5)).normalized();
  const Eigen::Vector2d along_t = (pixel(0.5, 0.6) - pixel(0.5, 0.4)).normalized();
  Eigen::Matrix2d turn;
  turn << along_s.x(), along_t.x(), along_s.y(), along_t.y();
  for (int i = 0; i < 4; ++i)
    turn(i) = std::abs(turn(i)) >= M_SQRT1_2 ? std::copysign(1.0, turn(i)) : 0.0;
  if (std::abs(turn.determinant() - 1) > 1e-9)
    throw std::runtime_error("the reference view " + reference.image +
                             " sees the page from behind or edge-on");
  return turn;
}

}  // namespace

MeshPair TrueSurfaceOnGrid(const GroundTruth& gt, const CameraSet& sfm_cameras,
                           const QuadGrid& grid, double margin) {
  if (grid.nx < 2 || grid.ny < 2)
    throw std::runtime_error("a grid of " + std::to_string(grid.nx) + " x " +
                             std::to_string(grid.ny) + " vertices has no quad");
  std::string why_not;
  const auto alignment = evaluate::AlignCameras(sfm_cameras, gt.cameras, &why_not);
  if (!alignment) throw std::runtime_error(why_not);
  const evaluate::Similarity& truth_from_sfm = alignment->truth_from_sfm;
  const Eigen::Matrix3d sfm_from_truth_R = truth_from_sfm.R.transpose();
  const double sfm_from_truth_scale = 1.0 / truth_from_sfm.scale;
  const PinholeCamera* reference = sfm_cameras.Find(sfm_cameras.reference);
  const Eigen::Matrix2d turn =
      reference ? QuarterTurnInView(gt, *reference, truth_from_sfm) : Eigen::Matrix2d::Identity();

  // The grown page in M' (metres, turned): its box, spanned by the grid.
  const Eigen::Vector2d size(gt.width_m, gt.height_m);
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(1e300), hi = -lo;
  for (double s : {-margin, 1 + margin}) {
    for (double t : {-margin, 1 + margin}) {
      const Eigen::Vector2d corner = turn * Eigen::Vector2d(s * size.x(), t * size.y());
      lo = lo.cwiseMin(corner);
      hi = hi.cwiseMax(corner);
    }
  }
  MeshPair m;
  m.grid = grid;
  for (int row = 0; row < grid.ny; ++row) {
    for (int col = 0; col < grid.nx; ++col) {
      const Eigen::Vector2d flat(lo.x() + (hi.x() - lo.x()) * col / (grid.nx - 1),
                                 lo.y() + (hi.y() - lo.y()) * row / (grid.ny - 1));
      const Eigen::Vector2d page = turn.transpose() * flat;  // metres along flat.png's axes
      const Eigen::Vector3d x = ContinuedPagePoint(gt, page.x() / size.x(), page.y() / size.y());
      m.mesh3d.push_back(sfm_from_truth_scale * (sfm_from_truth_R * (x - truth_from_sfm.t)));
      m.mesh2d.push_back(sfm_from_truth_scale * flat);
    }
  }
  return m;
}

}  // namespace docunfold::testing
