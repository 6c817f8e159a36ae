// The test helpers that derive truth in a view (page mask, corners, lines)
// agree with each other on every data set with ground truth.
#include "tests/support/ground_truth.h"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "tests/support/test_support.h"

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
      for (const Eigen::Vector2d& c : TrueCorners(*gt, cam)) {
        const int x = int(std::lround(c.x())), y = int(std::lround(c.y()));
        if (x < 0 || y < 0 || x >= cam.width || y >= cam.height) continue;
        EXPECT_LE(dist(y, x), 3.0) << set << " " << cam.image << " corner " << c.transpose();
      }
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

}  // namespace
}  // namespace docunfold::testing
