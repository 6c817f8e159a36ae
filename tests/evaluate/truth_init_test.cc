// truth-init's meshes: the true surface on a grid, in whatever frame sfm chose.
#include "tests/evaluate/truth_init.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

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

MeshPair GridOnly(const QuadGrid& grid) {
  MeshPair m;
  m.grid = grid;
  return m;
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
  const MeshPair m = TrueSurfaceOnGrid(*gt, sfm, GridOnly(grid), /*margin=*/0);
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
  const MeshPair m = TrueSurfaceOnGrid(*gt, gt->cameras, GridOnly(grid), margin);
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

// M' is turned the way the given meshes' is (init-mesh turns its M' upright by
// the text, whichever way the photo shows the page): the same 3D direction
// runs along M' x in both.
TEST(TruthInit, FlatTwinIsTurnedLikeTheGivenMeshes) {
  const auto gt = LoadGroundTruth(SampleDir("set02"));
  ASSERT_TRUE(gt);
  const MeshPair upright = TrueSurfaceOnGrid(*gt, gt->cameras, GridOnly({9, 13}));
  const int centre = upright.grid.Index(6, 4);
  for (int quarter = 0; quarter < 4; ++quarter) {
    MeshPair like = upright;
    const Eigen::Rotation2Dd turn(quarter * M_PI / 2);
    for (Eigen::Vector2d& v : like.mesh2d) v = turn * v;
    const MeshPair m = TrueSurfaceOnGrid(*gt, gt->cameras, like);
    // Where M' x points, in 3D, at the middle of each.
    auto x_direction = [&](const MeshPair& pair) {
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      for (int v : {centre - 1, centre + 1, centre - pair.grid.nx, centre + pair.grid.nx}) {
        const double dx = pair.mesh2d[v].x() - pair.mesh2d[centre].x();
        sum += dx * (pair.mesh3d[v] - pair.mesh3d[centre]);
      }
      return sum.normalized();
    };
    EXPECT_GT(x_direction(m).dot(x_direction(like)), 0.9) << quarter << " quarter turns";
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
  EXPECT_THROW(TrueSurfaceOnGrid(*gt, two, GridOnly({9, 13})), std::runtime_error);
  EXPECT_THROW(TrueSurfaceOnGrid(*gt, gt->cameras, GridOnly({1, 13})), std::runtime_error);
}

}  // namespace
}  // namespace docunfold::testing
