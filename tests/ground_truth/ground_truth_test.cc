// The test helpers that derive truth in a view (page mask, corners, lines)
// agree with each other on every data set with ground truth.
#include "tests/support/ground_truth.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "tests/support/test_support.h"
#include "tests/support/truth_frame.h"

namespace docunfold::testing {
namespace {

std::vector<fs::path> DataSetsWithGroundTruth() {
  std::vector<fs::path> sets;
  for (const fs::path& base : {SourceDir() / "samples", RealisticDir()}) {
    std::error_code ec;
    if (base.empty() || !fs::is_directory(base, ec)) continue;
    for (const auto& e : fs::directory_iterator(base))
      if (fs::is_directory(e.path() / "ground_truth")) sets.push_back(e.path());
  }
  std::sort(sets.begin(), sets.end());
  return sets;
}

TEST(GroundTruthHelpers, CornersLieOnTheMaskBoundaryInEveryView) {
  auto sets = DataSetsWithGroundTruth();
  if (sets.empty()) GTEST_SKIP() << "no data sets with ground truth";
  for (const fs::path& set : sets) {
    auto gt = LoadGroundTruth(set);
    ASSERT_TRUE(gt);
    for (const PinholeCamera& cam : gt->cameras.views) {
      cv::Mat1b mask = TruePageMask(*gt, cam);
      const double area = cv::countNonZero(mask);
      EXPECT_GT(area, 0.02 * cam.width * cam.height) << set << " " << cam.image;
      cv::Mat1f dist;
      cv::distanceTransform(255 - mask, dist, cv::DIST_L2, 3);
      // A corner of a folded page may be seen edge-on (a thin sliver covers
      // no pixel centre), so one corner may lie a little off the mask.
      int visible = 0, on_outline = 0;
      for (const Eigen::Vector2d& c : TrueCorners(*gt, cam)) {
        const int x = int(std::lround(c.x())), y = int(std::lround(c.y()));
        if (x < 3 || y < 3 || x >= cam.width - 3 || y >= cam.height - 3) continue;
        ++visible;
        on_outline += dist(y, x) <= 3.0;
        EXPECT_LE(dist(y, x), 15.0) << set << " " << cam.image << " corner " << c.transpose();
      }
      EXPECT_GE(on_outline, std::min(visible, 3)) << set << " " << cam.image;
      if (std::getenv("DOCUNFOLD_KEEP_TEST_DIRS"))
        cv::imwrite("/tmp/gt-mask-" + set.filename().string() + "-" + cam.image + ".png", mask);
    }
  }
}

TEST(GroundTruthHelpers, TrueLinesFallInsideThePage) {
  for (const fs::path& set : DataSetsWithGroundTruth()) {
    auto gt = LoadGroundTruth(set);
    ASSERT_TRUE(gt);
    if (gt->lines.empty()) continue;
    const PinholeCamera& cam = gt->cameras.views[0];
    cv::Mat1b mask = TruePageMask(*gt, cam);
    cv::dilate(mask, mask, cv::Mat(), cv::Point(-1, -1), 2);
    auto lines = TrueLinesInView(*gt, cam);
    EXPECT_FALSE(lines.empty()) << set;
    for (const TrueLine& l : lines)
      for (const Eigen::Vector2d& p : l.points)
        ASSERT_GT(mask(int(std::lround(p.y())), int(std::lround(p.x()))), 0) << set;
  }
}

// A camera behind the page sees its blank back: none of the print's lines.
// The camera of set01's first photo mirrored through the page's mean plane
// (x flipped to keep it a camera) sees the same surface as near as before,
// so only the side it faces tells the lines away.
TEST(GroundTruthHelpers, TrueLinesAreNotSeenFromBehindThePage) {
  auto gt = LoadGroundTruth(SampleDir("set01"));
  ASSERT_TRUE(gt);
  ASSERT_FALSE(gt->lines.empty());
  const PinholeCamera& front = gt->cameras.views[0];
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& v : gt->mesh.vertices) c += v / double(gt->mesh.vertices.size());
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (const Eigen::Vector3d& v : gt->mesh.vertices) scatter += (v - c) * (v - c).transpose();
  const Eigen::Vector3d n =
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(scatter).eigenvectors().col(0);
  const Eigen::Matrix3d mirror = Eigen::Matrix3d::Identity() - 2 * n * n.transpose();
  const Eigen::Matrix3d flip_x = Eigen::Vector3d(-1, 1, 1).asDiagonal();
  PinholeCamera behind = front;
  behind.R = flip_x * front.R * mirror;
  behind.t = flip_x * (front.R * (2 * c.dot(n) * n) + front.t);
  auto length = [](const std::vector<TrueLine>& lines) {
    double sum = 0;
    for (const TrueLine& l : lines)
      for (size_t k = 0; k + 1 < l.points.size(); ++k)
        sum += (l.points[k + 1] - l.points[k]).norm();
    return sum;
  };
  const double seen_from_front = length(TrueLinesInView(*gt, front));
  ASSERT_GT(seen_from_front, 1000);
  // The page itself is there: its mask covers as much of the image.
  EXPECT_GT(cv::countNonZero(TruePageMask(*gt, behind)),
            0.5 * cv::countNonZero(TruePageMask(*gt, front)));
  EXPECT_LT(length(TrueLinesInView(*gt, behind)), 0.02 * seen_from_front);
}

// The page as the true surface and camera predict it in a photo: every pixel
// the surface covers gets the colour of flat.png at its (s, t).
cv::Mat1f PredictedView(const GroundTruth& gt, const PinholeCamera& cam, cv::Mat1b* mask) {
  RasterResult r = RasterizeMesh(cam, gt.mesh.vertices, gt.triangles);
  Eigen::MatrixXf st(gt.mesh.vertices.size(), 2);
  for (size_t i = 0; i < gt.mesh.vertices.size(); ++i) {
    st(i, 0) = float(gt.mesh.FindProperty("s")->values[i] * gt.flat_width - 0.5);
    st(i, 1) = float(gt.mesh.FindProperty("t")->values[i] * gt.flat_height - 0.5);
  }
  cv::Mat map = InterpolateAttributes(r, gt.triangles, st);
  cv::Mat flat = cv::imread((gt.root / "ground_truth/flat.png").string(), cv::IMREAD_GRAYSCALE);
  cv::Mat1f flat_f;
  flat.convertTo(flat_f, CV_32F);
  cv::Mat1f out;
  cv::remap(flat_f, out, map, cv::noArray(), cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  *mask = r.face >= 0;
  out.setTo(0, ~*mask);
  return out;
}

// Grey levels with the slowly varying shading divided out, so a photo and
// the prediction from flat.png can be compared.

TEST(GroundTruth, TrueSurfaceAndCamerasReproduceThePageInEveryPhoto) {
  auto sets = DataSetsWithGroundTruth();
  if (sets.empty()) GTEST_SKIP() << "no data sets with ground truth";
  for (const fs::path& set : sets) {
    auto gt = LoadGroundTruth(set);
    ASSERT_TRUE(gt);
    for (const PinholeCamera& cam : gt->cameras.views) {
      cv::Mat photo = cv::imread((set / "images" / cam.image).string(), cv::IMREAD_GRAYSCALE);
      ASSERT_FALSE(photo.empty()) << set << " " << cam.image;
      ASSERT_EQ(photo.cols, cam.width);
      ASSERT_EQ(photo.rows, cam.height);
      cv::Mat1f photo_f;
      photo.convertTo(photo_f, CV_32F);
      cv::Mat1b mask;
      cv::Mat1f predicted = PredictedView(*gt, cam, &mask);
      cv::erode(mask, mask, cv::Mat(), cv::Point(-1, -1), 4);
      ASSERT_GT(cv::countNonZero(mask), 1000);
      const cv::Mat1f a = Detail(predicted), b = Detail(photo_f);
      const double aligned = Correlation(a, b, mask);
      // The same comparison with the photo moved by 4 pixels: text no longer
      // lines up, so a wrong camera or surface would look like this.
      cv::Mat1f shifted;
      cv::Mat1d shift = (cv::Mat1d(2, 3) << 1, 0, 4, 0, 1, 4);
      cv::warpAffine(b, shifted, shift, b.size());
      const double misaligned = Correlation(a, shifted, mask);
      EXPECT_GT(aligned, 0.5) << set << " " << cam.image;
      EXPECT_GT(aligned, misaligned + 0.25) << set << " " << cam.image;
    }
  }
}

TEST(TruthFrame, ReferenceCameraIsTheOriginAndMeshesAreIsometric) {
  auto sets = DataSetsWithGroundTruth();
  if (sets.empty()) GTEST_SKIP() << "no data sets with ground truth";
  auto gt = LoadGroundTruth(sets.front());
  ASSERT_TRUE(gt);
  const PinholeCamera& true_ref = gt->cameras.views[0];
  CameraSet cams = CamerasInReferenceFrame(*gt, true_ref.image);
  const PinholeCamera* ref = cams.Find(true_ref.image);
  ASSERT_NE(ref, nullptr);
  EXPECT_LT((ref->R - Eigen::Matrix3d::Identity()).norm(), 1e-6);
  EXPECT_LT(ref->t.norm(), 1e-6);
  TrueMeshes m = TrueMeshesInReferenceFrame(*gt, true_ref.image);
  // Same pixels in the reference view; same picture in every other view.
  for (size_t i = 0; i < m.mesh3d.vertices.size(); i += 97) {
    EXPECT_LT((ref->Project(m.mesh3d.vertices[i]) - true_ref.Project(gt->mesh.vertices[i])).norm(),
              1e-3);
    for (size_t v = 1; v < cams.views.size(); ++v)
      EXPECT_LT((cams.views[v].Project(m.mesh3d.vertices[i]) -
                 gt->cameras.views[v].Project(gt->mesh.vertices[i]))
                    .norm(),
                1e-3);
  }
  std::vector<double> depths;
  for (const auto& v : m.mesh3d.vertices) depths.push_back(v.z());
  std::sort(depths.begin(), depths.end());
  EXPECT_NEAR(depths[depths.size() / 2], 1.0, 0.05);
  // The true surface is an isometry of the flat page: edges keep their length.
  double worst = 0, mean_len = 0;
  for (const auto& f : m.mesh3d.faces)
    for (size_t k = 0; k < f.size(); ++k) {
      const int a = f[k], b = f[(k + 1) % f.size()];
      const double l3 = (m.mesh3d.vertices[a] - m.mesh3d.vertices[b]).norm();
      const double l2 = (m.mesh2d.vertices[a] - m.mesh2d.vertices[b]).norm();
      worst = std::max(worst, std::abs(l3 - l2));
      mean_len += l2;
    }
  mean_len /= 4.0 * m.mesh3d.faces.size();
  EXPECT_LT(worst, 0.05 * mean_len);
}

TEST(TruthFrame, SfmFromTruthWritesValidFiles) {
  auto sets = DataSetsWithGroundTruth();
  if (sets.empty()) GTEST_SKIP() << "no data sets with ground truth";
  auto gt = LoadGroundTruth(sets.front());
  ASSERT_TRUE(gt);
  TempDir dir;
  SfmFromTruthOptions options;
  options.num_points = 500;
  WriteSfmFromTruth(*gt, gt->cameras.views[0].image, dir.path(), options);
  CameraSet cams = ReadCameras(dir / "cameras.json");
  EXPECT_EQ(cams.reference, gt->cameras.views[0].image);
  PlyData points = ReadPly(dir / "points.ply");
  EXPECT_EQ(points.vertices.size(), 500u);
  EXPECT_TRUE(fs::is_regular_file(dir / "reference.png"));
  CommandResult r = RunCommand(Quote((SourceDir() / "scripts/validate-json").string()) + " " +
                               Quote((dir / "cameras.json").string()));
  EXPECT_EQ(r.exit_code, 0) << r.output;
}

}  // namespace
}  // namespace docunfold::testing
