#include "tests/evaluate/truth_init.h"

#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <utility>

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

// The 3D directions of M' x and y at a grid vertex (a least-squares fit to
// its neighbours), normalized.
std::pair<Eigen::Vector3d, Eigen::Vector3d> FlatAxesOnMesh(const MeshPair& m, int row, int col) {
  Eigen::MatrixXd flat(0, 2), space(0, 3);
  const int centre = m.grid.Index(row, col);
  for (auto [dr, dc] : {std::pair{0, 1}, {0, -1}, {1, 0}, {-1, 0}}) {
    const int r = row + dr, c = col + dc;
    if (r < 0 || c < 0 || r >= m.grid.ny || c >= m.grid.nx) continue;
    const int v = m.grid.Index(r, c);
    flat.conservativeResize(flat.rows() + 1, 2);
    space.conservativeResize(space.rows() + 1, 3);
    flat.row(flat.rows() - 1) = (m.mesh2d[v] - m.mesh2d[centre]).transpose();
    space.row(space.rows() - 1) = (m.mesh3d[v] - m.mesh3d[centre]).transpose();
  }
  const Eigen::MatrixXd jacobian = flat.colPivHouseholderQr().solve(space);  // 2 x 3
  return {jacobian.row(0).transpose().normalized(), jacobian.row(1).transpose().normalized()};
}

// The quarter turn taking flat.png's axes (x right, y down) to those of
// `like`'s M' at its middle vertex, as a matrix with entries in {-1, 0, 1}:
// init-mesh turns its M' upright by the text, not as the photo shows it.
Eigen::Matrix2d QuarterTurnOf(const GroundTruth& gt, const MeshPair& like,
                              const evaluate::Similarity& truth_from_sfm) {
  const int row = like.grid.ny / 2, col = like.grid.nx / 2;
  const auto [x_axis, y_axis] = FlatAxesOnMesh(like, row, col);
  // The page's own axes where the true surface is nearest that vertex.
  const Eigen::Vector3d at = truth_from_sfm(like.mesh3d[like.grid.Index(row, col)]);
  size_t nearest = 0;
  for (size_t v = 1; v < gt.mesh.vertices.size(); ++v)
    if ((gt.mesh.vertices[v] - at).squaredNorm() < (gt.mesh.vertices[nearest] - at).squaredNorm())
      nearest = v;
  const double s = std::clamp(double(gt.mesh.FindProperty("s")->values[nearest]), 0.01, 0.99);
  const double t = std::clamp(double(gt.mesh.FindProperty("t")->values[nearest]), 0.01, 0.99);
  const Eigen::Vector3d along_s =
      (PagePoint(gt, s + 0.01, t) - PagePoint(gt, s - 0.01, t)).normalized();
  const Eigen::Vector3d along_t =
      (PagePoint(gt, s, t + 0.01) - PagePoint(gt, s, t - 0.01)).normalized();
  const Eigen::Vector3d x_truth = truth_from_sfm.R * x_axis, y_truth = truth_from_sfm.R * y_axis;
  Eigen::Matrix2d turn;
  turn << x_truth.dot(along_s), x_truth.dot(along_t), y_truth.dot(along_s), y_truth.dot(along_t);
  for (int r = 0; r < 2; ++r)
    for (int c = 0; c < 2; ++c)
      turn(r, c) = std::abs(turn(r, c)) >= M_SQRT1_2 ? std::copysign(1.0, turn(r, c)) : 0.0;
  if (std::abs(turn.determinant() - 1) > 1e-9)
    throw std::runtime_error("the given meshes' flat twin is no quarter turn of the page");
  return turn;
}

}  // namespace

MeshPair TrueSurfaceOnGrid(const GroundTruth& gt, const CameraSet& sfm_cameras,
                           const MeshPair& like, double margin) {
  const QuadGrid& grid = like.grid;
  if (grid.nx < 2 || grid.ny < 2)
    throw std::runtime_error("a grid of " + std::to_string(grid.nx) + " x " +
                             std::to_string(grid.ny) + " vertices has no quad");
  std::string why_not;
  const auto alignment = evaluate::AlignCameras(sfm_cameras, gt.cameras, &why_not);
  if (!alignment) throw std::runtime_error(why_not);
  const evaluate::Similarity& truth_from_sfm = alignment->truth_from_sfm;
  const Eigen::Matrix3d sfm_from_truth_R = truth_from_sfm.R.transpose();
  const double sfm_from_truth_scale = 1.0 / truth_from_sfm.scale;
  const Eigen::Matrix2d turn =
      like.mesh3d.empty() ? Eigen::Matrix2d::Identity() : QuarterTurnOf(gt, like, truth_from_sfm);

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
