#include "common/raster.h"

#include <gtest/gtest.h>

#include <limits>
#include <random>

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

// The face index answers every pixel as the full raster does: random
// overlapping triangles at random depths, one drawn twice (a tie: the
// first wins), triangles reaching past the image, behind the camera,
// degenerate or not finite.
TEST(PixelFaceIndex, AgreesWithRasterizeOnEveryPixel) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> xy(-20, 120), z(0.5, 3);
  std::vector<Eigen::Vector3d> v;
  std::vector<Triangle> tris;
  for (int f = 0; f < 300; ++f) {
    const Eigen::Vector3d c(xy(rng), xy(rng), z(rng));
    for (int k = 0; k < 3; ++k)
      v.push_back(c + Eigen::Vector3d(xy(rng) / 6, xy(rng) / 6, f % 5 == 0 ? 0.0 : z(rng) / 10));
    tris.push_back({3 * f, 3 * f + 1, 3 * f + 2});
  }
  tris.push_back(tris[20]);
  v[0].z() = -1;                                        // behind the camera
  v[4] = v[3];                                          // degenerate
  v[7].x() = std::numeric_limits<double>::quiet_NaN();  // not finite
  const int width = 101, height = 77;
  const RasterResult r = Rasterize(v, tris, width, height);
  const PixelFaceIndex index(v, tris, width, height);
  int covered = 0;
  for (int y = -2; y < height + 2; ++y)
    for (int x = -2; x < width + 2; ++x) {
      const bool inside = x >= 0 && y >= 0 && x < width && y < height;
      const int expected = inside ? r.face(y, x) : -1;
      ASSERT_EQ(index(x, y), expected) << "pixel " << x << ", " << y;
      covered += expected >= 0;
    }
  EXPECT_GT(covered, width * height / 2);
}

TEST(PixelFaceIndex, MeshIndexMatchesTheScaledRaster) {
  PinholeCamera cam;
  cam.width = 640;
  cam.height = 480;
  cam.K << 500, 0, 319.5, 0, 500, 239.5, 0, 0, 1;
  std::vector<Eigen::Vector3d> v = {
      {-0.5, -0.4, 1.0}, {0.5, -0.4, 1.2}, {0.6, 0.5, 2.0}, {-0.5, 0.4, 1.5}};
  const std::vector<Triangle> tris = Triangulate({{0, 1, 2, 3}});
  for (const double scale : {1.0, 0.37}) {
    const RasterResult r = RasterizeMesh(cam, v, tris, scale);
    const PixelFaceIndex index = MeshFaceIndex(cam, v, tris, scale);
    ASSERT_EQ(index.width(), r.face.cols);
    ASSERT_EQ(index.height(), r.face.rows);
    for (int y = 0; y < r.face.rows; ++y)
      for (int x = 0; x < r.face.cols; ++x) ASSERT_EQ(index(x, y), r.face(y, x));
  }
}

}  // namespace
}  // namespace docunfold
