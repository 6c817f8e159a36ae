// truth-init's meshes: the true surface on a grid, in whatever frame sfm chose.
#include "tests/evaluate/truth_init.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "tests/support/test_support.h"

namespace docunfold::testing {
namespace {

// The true cameras seen from a frame x_sfm = scale * Q * x_truth + offset, as
// sfm might have chosen it (the camera's depth unit scales with the frame).
CameraSet InOtherFrame(const CameraSet& truth, double scale, const Eigen::Matrix3d& Q,
                       const Eigen::Vector3d& offset) {
  CameraSet out = truth;
  for (PinholeCamera& c : out.views) {
    const Eigen::Matrix3d R = c.R * Q.transpose();
    c.t = scale * c.t - R * offset;
    c.R = R;
  }
  return out;
}

TEST(TruthInit, TrueSurfaceOnGridIsTheTruthInSfmsFrame) {
  const auto gt = LoadGroundTruth(SampleDir("set02"));  // folded along a diagonal
  ASSERT_TRUE(gt);
  const double scale = 3.7;
  const Eigen::Matrix3d Q =
      Eigen::AngleAxisd(0.8, Eigen::Vector3d(1, -2, 0.5).normalized()).toRotationMatrix();
  const Eigen::Vector3d offset(0.3, -1.2, 4.0);
  const CameraSet sfm = InOtherFrame(gt->cameras, scale, Q, offset);
  const QuadGrid grid{9, 13};
  const MeshPair m = TrueSurfaceOnGrid(*gt, sfm, grid, /*margin=*/0);
  ASSERT_EQ(int(m.mesh3d.size()), grid.NumVertices());
  ASSERT_EQ(int(m.mesh2d.size()), grid.NumVertices());
  const double diagonal = gt->Diagonal() * scale;
  for (int row = 0; row < grid.ny; ++row) {
    for (int col = 0; col < grid.nx; ++col) {
      const int v = grid.Index(row, col);
      const double s = double(col) / (grid.nx - 1), t = double(row) / (grid.ny - 1);
      const auto truth = gt->SurfacePoint({s * gt->flat_width - 0.5, t * gt->flat_height - 0.5});
      ASSERT_TRUE(truth);
      const Eigen::Vector3d expected = scale * (Q * *truth) + offset;
      EXPECT_LT((m.mesh3d[v] - expected).norm(), 1e-6 * diagonal)
          << "row " << row << " col " << col;
      EXPECT_NEAR(m.mesh2d[v].x(), s * gt->width_m * scale, 1e-9);
      EXPECT_NEAR(m.mesh2d[v].y(), t * gt->height_m * scale, 1e-9);
    }
  }
  // The corners are the page's: M' spans the page, M's corners are 3D corners.
  EXPECT_NEAR((m.mesh2d.back() - m.mesh2d.front()).norm(), diagonal, 1e-9);
}

TEST(TruthInit, MarginContinuesThePageIsometrically) {
  const auto gt = LoadGroundTruth(SampleDir("set02"));
  ASSERT_TRUE(gt);
  const QuadGrid grid{9, 13};
  const double margin = 0.05;
  const MeshPair m = TrueSurfaceOnGrid(*gt, gt->cameras, grid, margin);
  // M' spans the grown page; its first row and column lie outside the page.
  EXPECT_NEAR(m.mesh2d[0].x(), -margin * gt->width_m, 1e-12);
  EXPECT_NEAR(m.mesh2d[0].y(), -margin * gt->height_m, 1e-12);
  EXPECT_NEAR(m.mesh2d.back().x(), (1 + margin) * gt->width_m, 1e-12);
  // Edges in the margin keep their flat length (the tangent plane is flat).
  for (int row = 0; row < grid.ny; ++row) {
    for (int col : {0, grid.nx - 2}) {
      const int a = grid.Index(row, col), b = grid.Index(row, col + 1);
      const double flat = (m.mesh2d[b] - m.mesh2d[a]).norm();
      EXPECT_NEAR((m.mesh3d[b] - m.mesh3d[a]).norm() / flat, 1.0, 0.01) << "row " << row;
    }
  }
}

// However the reference view shows the page turned, M' is upright in it:
// the grid's rows run right in that view and its columns down, as init-mesh's.
TEST(TruthInit, FlatTwinIsUprightInTheReferenceView) {
  const auto gt = LoadGroundTruth(SampleDir("set02"));
  ASSERT_TRUE(gt);
  const QuadGrid grid{9, 13};
  for (int quarter = 0; quarter < 4; ++quarter) {
    CameraSet cameras = gt->cameras;
    PinholeCamera& reference = cameras.views[1];
    const Eigen::Matrix3d turn =
        Eigen::AngleAxisd(quarter * M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    reference.R = turn * reference.R;
    reference.t = turn * reference.t;
    cameras.reference = reference.image;
    const MeshPair m = TrueSurfaceOnGrid(*gt, cameras, grid);
    const int centre = grid.Index(grid.ny / 2, grid.nx / 2);
    const Eigen::Vector2d at = reference.Project(m.mesh3d[centre]);
    const Eigen::Vector2d right = reference.Project(m.mesh3d[centre + 1]) - at;
    const Eigen::Vector2d down = reference.Project(m.mesh3d[centre + grid.nx]) - at;
    EXPECT_GT(right.x(), std::abs(right.y())) << quarter << " quarter turns";
    EXPECT_GT(down.y(), std::abs(down.x())) << quarter << " quarter turns";
    // M' keeps the page's size, turned with it.
    const Eigen::Vector2d span = m.mesh2d.back() - m.mesh2d.front();
    const double w = gt->width_m * 1.02, h = gt->height_m * 1.02;
    EXPECT_NEAR(std::abs(span.x()), quarter % 2 ? h : w, 1e-9);
    EXPECT_NEAR(std::abs(span.y()), quarter % 2 ? w : h, 1e-9);
  }
}

TEST(TruthInit, RefusesCamerasItCannotAlign) {
  const auto gt = LoadGroundTruth(SampleDir("set02"));
  ASSERT_TRUE(gt);
  CameraSet two = gt->cameras;
  two.views.resize(2);
  EXPECT_THROW(TrueSurfaceOnGrid(*gt, two, QuadGrid{9, 13}), std::runtime_error);
  EXPECT_THROW(TrueSurfaceOnGrid(*gt, gt->cameras, QuadGrid{1, 13}), std::runtime_error);
}

}  // namespace
}  // namespace docunfold::testing
