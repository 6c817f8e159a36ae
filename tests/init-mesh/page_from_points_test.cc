// The page from its points alone: which points are the page's (inside the
// page in every photo that frames them), and their flat layout (Isomap) on a
// sheet folded twice through 90 degrees, where straight 3D distances across
// a fold are far shorter than on the page.
#include "stages/init-mesh/page_from_points.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include "common/isometry/mesh_index.h"
#include "common/raster.h"
#include "common/statistics.h"
#include "tests/isometry/test_meshes.h"

namespace docunfold::init_mesh {
namespace {

using testing::ProfileSheet;
using testing::SampleSurface;

PinholeCamera Camera(const Eigen::Vector3d& centre) {
  PinholeCamera cam;
  cam.width = 640;
  cam.height = 480;
  cam.K << 500, 0, 319.5, 0, 500, 239.5, 0, 0, 1;
  cam.t = -centre;  // looking down +z
  return cam;
}

TEST(PageFromPoints, PagePointsAreInsideThePageInEveryPhotoThatFramesThem) {
  // A flat page at z = 1 (0.2 x 0.3 around the axis), a table at z = 1.01.
  MeshPair page = ProfileSheet(11, 16, 0.2, 0.3, [](int) { return 0.0; });
  std::vector<ViewPage> photos;
  for (const Eigen::Vector3d& c : {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(0.2, 0, 0.1)}) {
    const PinholeCamera cam = Camera(c);
    ViewPage photo;
    photo.camera = cam;
    photo.mask = cv::Mat1b(RasterizeMesh(cam, page.mesh3d, page.grid.Triangles()).face >= 0);
    photos.push_back(photo);
  }
  const std::vector<Eigen::Vector3d> points = {
      {0, 0, 1},          // the page's middle
      {0.09, 0.14, 1},    // near its corner
      {0.3, 0, 1.01},     // the table beside it
      {0.0, 0.0, 1.011},  // the table under the page: hidden, inside the page in both photos
      {0.12, 0, 1.01},    // the table just right of the page, outside it in both photos
      {-1.5, 0, 1},       // outside both frames
  };
  PageFromPointsOptions o;
  const std::vector<bool> page_points = PagePoints(points, photos, o);
  EXPECT_EQ(page_points, std::vector<bool>({true, true, false, true, false, false}));
  // Framed by one photo only: not enough.
  o.min_photos = 3;
  EXPECT_EQ(PagePoints(points, photos, o), std::vector<bool>(points.size(), false));
}

TEST(PageFromPoints, TheFlatLayoutUnfoldsASheetFoldedTwiceThrough90Degrees) {
  const double w = 0.3, h = 0.2;
  const int nx = 31;
  const MeshPair sheet = ProfileSheet(nx, 21, w, h, [&](int c) {
    return c == 9 || c == 20 ? M_PI / 2 : 0.0;  // a U: two folds of 90 degrees
  });
  const testing::SampledPoints sample = SampleSurface(sheet, 2500, 0.0, 0.0, 11);
  // Each point's true flat position, through its closest point on the sheet.
  const isometry::TriangleMeshIndex index(sheet.mesh3d, sheet.grid.Triangles());
  std::vector<Eigen::Vector2d> truth;
  for (const auto& p : sample.points) {
    const auto c = index.Closest(p);
    truth.push_back(PointOnMesh2d(sheet, {c->triangle, c->bary}));
  }
  FlatLayout layout;
  std::string why;
  ASSERT_TRUE(LayOutFlat(sample.points, {}, &layout, &why)) << why;
  ASSERT_GT(layout.used.size(), 0.7 * sample.points.size());  // thinned, in one part
  // Distances between points at least a fifth of the page apart: on the
  // page, not straight through space.
  std::mt19937 rng(3);
  std::uniform_int_distribution<size_t> pick(0, layout.used.size() - 1);
  std::vector<double> errors, shortcut;
  for (int k = 0; k < 4000; ++k) {
    const size_t a = pick(rng), b = pick(rng);
    const int ia = layout.used[a], ib = layout.used[b];
    const double on_page = (truth[size_t(ia)] - truth[size_t(ib)]).norm();
    if (on_page < 0.2 * w) continue;
    errors.push_back(std::abs((layout.flat[a] - layout.flat[b]).norm() - on_page) / on_page);
    shortcut.push_back(1 -
                       (sample.points[size_t(ia)] - sample.points[size_t(ib)]).norm() / on_page);
  }
  std::sort(errors.begin(), errors.end());
  const double median = errors[errors.size() / 2];
  const double p95 = errors[errors.size() * 95 / 100];
  std::printf(
      "[page from points] U-folded sheet: flat distances off by %.2f %% (median), %.2f %% "
      "(95th percentile); straight 3D distances %.1f %% short (median)\n",
      100 * median, 100 * p95, 100 * Median(shortcut));
  EXPECT_LT(median, 0.045);
  EXPECT_LT(p95, 0.09);
}

TEST(PageFromPoints, TooFewOrCollinearPointsAreRefused) {
  FlatLayout layout;
  std::string why;
  EXPECT_FALSE(
      LayOutFlat(std::vector<Eigen::Vector3d>(5, Eigen::Vector3d::Zero()), {}, &layout, &why));
  EXPECT_NE(why.find("only 5 points"), std::string::npos) << why;
  EXPECT_FALSE(LayOutFlat(std::vector<Eigen::Vector3d>(100, Eigen::Vector3d(0.1, 0.2, 1)), {},
                          &layout, &why));
  EXPECT_NE(why.find("in one place"), std::string::npos) << why;
  std::vector<Eigen::Vector3d> line;
  for (int i = 0; i < 100; ++i) line.push_back({0.01 * i, 0, 1});
  EXPECT_FALSE(LayOutFlat(line, {}, &layout, &why));
  EXPECT_NE(why.find("on a line"), std::string::npos) << why;
}

}  // namespace
}  // namespace docunfold::init_mesh
