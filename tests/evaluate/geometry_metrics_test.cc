#include "stages/evaluate/geometry_metrics.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "common/raster.h"

namespace docunfold::evaluate {
namespace {

PinholeCamera CameraAt(const std::string& name, const Eigen::Vector3d& center,
                       const Eigen::Matrix3d& R) {
  PinholeCamera c;
  c.image = name;
  c.width = 100;
  c.height = 100;
  c.R = R;
  c.t = -R * center;
  return c;
}

// A flat nx x ny grid of the given spacing in z = 0, quads row-major.
PlyData Grid(int nx, int ny, double spacing) {
  PlyData m;
  for (int r = 0; r < ny; ++r)
    for (int c = 0; c < nx; ++c) m.vertices.emplace_back(c * spacing, r * spacing, 0);
  for (int r = 0; r + 1 < ny; ++r)
    for (int c = 0; c + 1 < nx; ++c)
      m.faces.push_back({r * nx + c, r * nx + c + 1, (r + 1) * nx + c + 1, (r + 1) * nx + c});
  return m;
}

TEST(PointTriangleDistance, RegionsOfTheTriangle) {
  const Eigen::Vector3d a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  EXPECT_NEAR(PointTriangleDistance({0.2, 0.2, 0.5}, a, b, c), 0.5, 1e-12);         // face
  EXPECT_NEAR(PointTriangleDistance({-1, -1, 0}, a, b, c), std::sqrt(2.0), 1e-12);  // vertex
  EXPECT_NEAR(PointTriangleDistance({0.5, -2, 0}, a, b, c), 2.0, 1e-12);            // edge ab
  EXPECT_NEAR(PointTriangleDistance({1, 1, 0}, a, b, c), std::sqrt(0.5), 1e-12);    // edge bc
}

TEST(AlignCameras, RecoversAKnownSimilarity) {
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  Similarity truth_from_sfm{2.5, R, Eigen::Vector3d(0.3, -1, 2)};
  CameraSet sfm, truth;
  const Eigen::Vector3d centers[4] = {{0, 0, 0}, {1, 0, 0.2}, {0, 1, 0.1}, {0.5, 0.5, -0.4}};
  for (int i = 0; i < 4; ++i) {
    const std::string name = "v" + std::to_string(i);
    sfm.views.push_back(CameraAt(name, centers[i], Eigen::Matrix3d::Identity()));
    truth.views.push_back(CameraAt(name, truth_from_sfm(centers[i]), Eigen::Matrix3d::Identity()));
  }
  truth.views.push_back(CameraAt("only_in_truth", {9, 9, 9}, Eigen::Matrix3d::Identity()));
  std::string why;
  const auto a = AlignCameras(sfm, truth, &why);
  ASSERT_TRUE(a) << why;
  EXPECT_EQ(a->cameras, 4);
  EXPECT_NEAR(a->truth_from_sfm.scale, 2.5, 1e-9);
  EXPECT_LT((a->truth_from_sfm.R - R).norm(), 1e-9);
  EXPECT_LT(a->rms_residual, 1e-9);
  const Eigen::Vector3d p(0.1, 0.2, 0.3);
  EXPECT_LT((a->truth_from_sfm(p) - truth_from_sfm(p)).norm(), 1e-9);
}

TEST(AlignCameras, RefusesTooFewOrCollinearCameras) {
  CameraSet sfm, truth;
  for (int i = 0; i < 3; ++i) {
    const std::string name = "v" + std::to_string(i);
    sfm.views.push_back(CameraAt(name, {double(i), 0, 0}, Eigen::Matrix3d::Identity()));
    truth.views.push_back(CameraAt(name, {2.0 * i, 0, 0}, Eigen::Matrix3d::Identity()));
  }
  std::string why;
  EXPECT_FALSE(AlignCameras(sfm, truth, &why));
  EXPECT_NE(why.find("collinear"), std::string::npos) << why;
  sfm.views.resize(2);
  EXPECT_FALSE(AlignCameras(sfm, truth, &why));
  EXPECT_NE(why.find("2 view"), std::string::npos) << why;
}

TEST(SurfaceDistance, PointsAboveAFlatGrid) {
  const PlyData grid = Grid(21, 21, 0.05);  // 1 x 1 square
  const SurfaceDistance distance(grid.vertices, Triangulate(grid.faces));
  EXPECT_NEAR(distance({0.512, 0.377, 0.03}), 0.03, 1e-12);
  EXPECT_NEAR(distance({0.5, 0.5, -0.2}), 0.2, 1e-12);
  EXPECT_NEAR(distance({1.1, 0.5, 0}), 0.1, 1e-12);  // beyond the edge
  const DistanceStats s =
      MeshToSurface({{0.3, 0.3, 0.01}, {0.6, 0.6, 0.03}}, Similarity{}, distance);
  EXPECT_NEAR(s.mean, 0.02, 1e-12);
  EXPECT_NEAR(s.max, 0.03, 1e-12);
  EXPECT_EQ(s.samples, 2u);
}

TEST(IsometryError, RelativeEdgeLengthError) {
  const PlyData flat = Grid(4, 3, 0.1);
  PlyData stretched = flat;
  EXPECT_NEAR(IsometryError(stretched, flat, "m").max, 0.0, 1e-12);
  for (auto& v : stretched.vertices) v.x() *= 1.1;  // horizontal edges 10% longer
  const IsometryStats s = IsometryError(stretched, flat, "m");
  EXPECT_EQ(s.edges, 3u * 3 + 4u * 2);  // 9 horizontal, 8 vertical
  EXPECT_NEAR(s.max, 0.1, 1e-12);
  EXPECT_NEAR(s.mean, 0.1 * 9 / 17, 1e-12);
  PlyData other = Grid(3, 3, 0.1);
  EXPECT_THROW(IsometryError(other, flat, "m"), std::exception);
}

}  // namespace
}  // namespace docunfold::evaluate
