// HullMarkers and MarkMaskDoubts on a flat sheet too long at one end: a
// second photo's mask shows the page ending a quarter of the sheet's width
// before the sheet does.
#include "stages/optimize/mask_hull.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <opencv2/imgproc.hpp>

#include "tests/optimize/flat_sheet.h"

namespace docunfold::optimize {
namespace {

constexpr int kImageSize = 800;

PinholeCamera Camera(const std::string& image, const Eigen::Matrix3d& R) {
  PinholeCamera c;
  c.image = image;
  c.width = c.height = kImageSize;
  c.K << 800, 0, 400, 0, 800, 400, 0, 0, 1;
  // Looking at the sheet's centre (0, 0, 4) from 4 units away.
  const Eigen::Vector3d centre = Eigen::Vector3d(0, 0, 4) - 4 * R.transpose().col(2);
  c.R = R;
  c.t = -R * centre;
  return c;
}

// The filled image of the quadrilateral x in [-0.5, 0.5], y in [-0.75, y_end]
// of the plane z = 4.
cv::Mat1b PageMask(const PinholeCamera& camera, double y_end) {
  std::vector<cv::Point> corners;
  for (const Eigen::Vector3d& x :
       {Eigen::Vector3d(-0.5, -0.75, 4), Eigen::Vector3d(0.5, -0.75, 4),
        Eigen::Vector3d(0.5, y_end, 4), Eigen::Vector3d(-0.5, y_end, 4)}) {
    const Eigen::Vector2d p = camera.Project(x);
    corners.emplace_back(int(std::lround(p.x())), int(std::lround(p.y())));
  }
  cv::Mat1b mask = cv::Mat1b::zeros(kImageSize, kImageSize);
  cv::fillConvexPoly(mask, corners, 255);
  return mask;
}

// A 1 x 1.5 sheet at z = 4 on a 5 x 7 grid (0.25 apart), seen square-on by
// the reference and from 25 degrees off by view_01, whose mask ends at
// y = 0.5: the sheet's last row (y = 0.75) is off the page there.
struct TwoViewScene {
  MeshPair meshes;
  PinholeCamera reference = Camera("view_00.jpg", Eigen::Matrix3d::Identity());
  std::vector<ViewPage> others;
  cv::Mat1b everywhere = cv::Mat1b(kImageSize, kImageSize, uchar(255));

  TwoViewScene() {
    meshes = FlatSheetAtDepthFour();
    ViewPage page;
    page.camera = Camera("view_01.jpg",
                         Eigen::AngleAxisd(25 * M_PI / 180, Eigen::Vector3d::UnitX()).matrix());
    page.mask = PageMask(page.camera, 0.5);
    others.push_back(page);
  }
};

TEST(MaskHull, VerticesOutsideAnotherMaskAreHeldToItsOutline) {
  const TwoViewScene scene;
  std::vector<HullView> views = PrepareHullViews(scene.others);
  HullOptions options;
  const std::vector<isometry::Marker> markers =
      HullMarkers(scene.meshes, scene.reference, scene.everywhere, views, options);
  // The last row's five vertices, about 50 px outside view_01's mask.
  ASSERT_EQ(markers.size(), 5u);
  const PinholeCamera& camera = scene.others[0].camera;
  for (const isometry::Marker& m : markers) {
    const Eigen::Vector3d x = PointOnMesh3d(scene.meshes, m.where);
    EXPECT_NEAR(x.y(), 0.75, 1e-12);
    EXPECT_EQ(m.weight, options.weight);
    EXPECT_LT((m.ray_origin - camera.Center()).norm(), 1e-9);
    EXPECT_NEAR(m.across.norm(), 1, 1e-12);
    EXPECT_NEAR(m.across.dot(m.ray_direction), 0, 1e-12);
    // Moved onto its plane, the vertex projects onto the mask's outline.
    const double before = views[0].outside(cv::Point(camera.Project(x).x(), camera.Project(x).y()));
    const Eigen::Vector3d on_plane = x - m.across.dot(x - m.ray_origin) * m.across;
    const Eigen::Vector2d p = camera.Project(on_plane);
    EXPECT_GT(before, 30);
    EXPECT_LE(views[0].outside(cv::Point(int(std::lround(p.x())), int(std::lround(p.y())))), 2)
        << p.transpose();
  }
  // From the mask at half its size: the same vertices, held to nearly the
  // same planes.
  const std::vector<HullView> half = PrepareHullViews(scene.others, kImageSize / 2);
  EXPECT_DOUBLE_EQ(half[0].scale, 0.5);
  const std::vector<isometry::Marker> coarse =
      HullMarkers(scene.meshes, scene.reference, scene.everywhere, half, options);
  ASSERT_EQ(coarse.size(), markers.size());
  for (size_t i = 0; i < coarse.size(); ++i) {
    EXPECT_EQ(coarse[i].where.triangle, markers[i].where.triangle);
    EXPECT_LT((coarse[i].across - markers[i].across).norm(), 0.01);
  }

  // The page ends on the reference's page: the last row lies on its border,
  // within page_inset_px, and is not judged.
  const cv::Mat1b sheet = PageInterior(PageMask(scene.reference, 0.75), options);
  EXPECT_TRUE(HullMarkers(scene.meshes, scene.reference, sheet, views, options).empty());
}

TEST(MaskHull, PointsOutsideAMaskMakeItDoubtfulThereOrEverywhere) {
  const TwoViewScene scene;
  std::vector<HullView> views = PrepareHullViews(scene.others);
  HullOptions options;
  // 2,000 points on the page and one past it at the last row's corner: the
  // mask is not trusted within doubt_radius_px of that point's image.
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < 2000; ++i)
    points.emplace_back(-0.45 + 0.9 * (i % 40) / 39.0, -0.7 + 1.15 * (i / 40) / 49.0, 4.0);
  points.emplace_back(0.5, 0.75, 4.0);
  std::vector<HullViewCheck> checks = MarkMaskDoubts(points, options, &views);
  ASSERT_EQ(checks.size(), 1u);
  EXPECT_EQ(checks[0].image, "view_01.jpg");
  EXPECT_EQ(checks[0].points_seen, 2001);
  EXPECT_EQ(checks[0].points_outside, 1);
  EXPECT_TRUE(checks[0].used);
  std::vector<isometry::Marker> markers =
      HullMarkers(scene.meshes, scene.reference, scene.everywhere, views, options);
  ASSERT_EQ(markers.size(), 4u);
  for (const isometry::Marker& m : markers)
    EXPECT_LT(PointOnMesh3d(scene.meshes, m.where).x(), 0.5 - 1e-9);

  // With more than 2 % of the points outside, the photo is not used at all.
  for (int i = 0; i < 60; ++i) points.emplace_back(-0.5 + i / 60.0, 0.7, 4.0);
  checks = MarkMaskDoubts(points, options, &views);
  EXPECT_FALSE(checks[0].used);
  EXPECT_EQ(checks[0].points_outside, 61);
  EXPECT_TRUE(HullMarkers(scene.meshes, scene.reference, scene.everywhere, views, options).empty());
}

}  // namespace
}  // namespace docunfold::optimize
