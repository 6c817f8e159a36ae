#include "common/raster.h"

#include <gtest/gtest.h>

namespace docunfold {
namespace {

TEST(Raster, PerspectiveCorrectAttributesOnATiltedPlane) {
  PinholeCamera cam;
  cam.width = 200;
  cam.height = 200;
  cam.K << 150, 0, 99.5, 0, 150, 99.5, 0, 0, 1;
  // A unit square tilted away from the camera; attribute = world x, y.
  std::vector<Eigen::Vector3d> v = {
      {-0.5, -0.5, 1.0}, {0.5, -0.5, 1.0}, {0.5, 0.5, 2.0}, {-0.5, 0.5, 2.0}};
  std::vector<Triangle> tris = Triangulate({{0, 1, 2, 3}});
  RasterResult r = RasterizeMesh(cam, v, tris);
  Eigen::MatrixXf attr(4, 3);
  for (int i = 0; i < 4; ++i) attr.row(i) = v[i].cast<float>().transpose();
  cv::Mat xyz = InterpolateAttributes(r, tris, attr);
  int covered = 0;
  for (int y = 0; y < 200; ++y)
    for (int x = 0; x < 200; ++x) {
      if (r.face(y, x) < 0) continue;
      ++covered;
      cv::Vec3f p = xyz.at<cv::Vec3f>(y, x);
      // The interpolated 3D point must project back onto the pixel centre.
      Eigen::Vector2d q = cam.Project(Eigen::Vector3d(p[0], p[1], p[2]));
      ASSERT_NEAR(q.x(), x, 2e-3);
      ASSERT_NEAR(q.y(), y, 2e-3);
      ASSERT_NEAR(r.depth(y, x), p[2], 1e-4);
    }
  EXPECT_GT(covered, 5000);
  EXPECT_TRUE(std::isnan(xyz.at<cv::Vec3f>(0, 0)[0]));
}

TEST(Raster, DepthTestKeepsTheNearestTriangle) {
  std::vector<Eigen::Vector3d> v = {{0, 0, 2}, {20, 0, 2}, {0, 20, 2},
                                    {0, 0, 1}, {20, 0, 1}, {0, 20, 1}};
  RasterResult r = Rasterize(v, {{0, 1, 2}, {3, 4, 5}}, 32, 32);
  EXPECT_EQ(r.face(5, 5), 1);
  EXPECT_FLOAT_EQ(r.depth(5, 5), 1.0f);
  EXPECT_EQ(r.face(30, 30), -1);
  // Reversed order gives the same answer.
  r = Rasterize(v, {{3, 4, 5}, {0, 1, 2}}, 32, 32);
  EXPECT_EQ(r.face(5, 5), 0);
}

TEST(Raster, SkipsTrianglesBehindTheCamera) {
  std::vector<Eigen::Vector3d> v = {{0, 0, -1}, {20, 0, 1}, {0, 20, 1}};
  RasterResult r = Rasterize(v, {{0, 1, 2}}, 32, 32);
  EXPECT_EQ(cv::countNonZero(r.face >= 0), 0);
}

}  // namespace
}  // namespace docunfold
