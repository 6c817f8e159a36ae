// segment-boundary against the ground truth of every data set: the page
// region (IoU), the corners (within 1 % of the page's projected diagonal) and
// the sides (a real side lies on the true page edge; a page cut by the image
// border has its cut sides marked not real), in every view and in crops of
// the most frontal view that cut the page off.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "common/page_files.h"
#include "stages/evaluate/front_end.h"
#include "stages/segment-boundary/segment_boundary.h"
#include "tests/boundary/eval_support.h"
#include "tests/support/test_support.h"

namespace docunfold::testing {
namespace {

using boundary::BoundaryResult;
using evaluate::BoundaryFigures;

// evaluate's figures (stages/evaluate/front_end.h) for one view, and what
// the stage says about the page's orientation.
struct ViewFigures {
  BoundaryFigures f;
  std::string orientation_method;
  int votes = 0;
  double confidence = 0;
};

ViewFigures Measure(const GroundTruth& gt, const PinholeCamera& cam, const BoundaryResult& r) {
  const Boundary boundary =
      ParseBoundary(boundary::BoundaryToJson(r, cam.image, cam.width, cam.height, Json::object()),
                    "segment-boundary's result for " + cam.image);
  ViewFigures v;
  v.f = evaluate::MeasureBoundary(evaluate::SeeTruth(gt, cam), r.mask, boundary);
  v.orientation_method = r.orientation.method;
  v.votes = r.orientation.votes;
  v.confidence = r.orientation.confidence;
  return v;
}

// Every check, for the most frontal view (sfm's likely reference). When a
// true corner is hidden by the page itself (a flap folded over it), the
// outline's four turns are not the page corners and its sides are partly fold
// silhouettes: only the region is checked then.
void ExpectGood(const ViewFigures& v, const std::string& what, bool check_corners = true) {
  const BoundaryFigures& f = v.f;
  EXPECT_GE(f.iou, evaluate::kMinBoundaryIou) << what;
  if (check_corners) {
    EXPECT_TRUE(f.CornersHold()) << what << ": worst corner " << f.worst_corner_px << " px";
  }
  EXPECT_TRUE(f.SidesHold()) << what << ": a real side leaves the true page edge ("
                             << f.real_off_edge_px << " px, max " << f.real_off_edge_max_px
                             << ") or misses it (covers " << f.edge_recall << ")";
  if (f.page_cut)
    EXPECT_GE(f.sides_not_real, 1) << what << ": cut page, no cut side";
  else
    EXPECT_EQ(f.sides_not_real, 0) << what << ": whole page, side marked cut";
  if (v.orientation_method == "text") {
    EXPECT_TRUE(f.corners_in_order) << what << ": orientation read from the text is wrong";
  }
}

// With DOCUNFOLD_DEBUG_DIR set, the overlay with the true outline (blue) and
// true corners (magenta) drawn over it goes there, for a person to look at.
void MaybeWriteDebug(const GroundTruth& gt, const PinholeCamera& cam, const cv::Mat& image,
                     const BoundaryResult& r, const std::string& what) {
  const char* dir = std::getenv("DOCUNFOLD_DEBUG_DIR");
  if (!dir) return;
  cv::Mat out = boundary::DrawBoundaryOverlay(image, r, 100000);
  std::vector<std::vector<cv::Point>> contours;
  cv::findContours(TruePageMask(gt, cam), contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_NONE);
  cv::drawContours(out, contours, -1, cv::Scalar(255, 0, 0), 1);
  for (const auto& c : TrueCorners(gt, cam))
    cv::circle(out, cv::Point(int(c.x()), int(c.y())), 6, cv::Scalar(255, 0, 255), 2);
  std::string name = what;
  for (char& c : name)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  cv::imwrite(std::string(dir) + "/" + name + ".png", out);
}

void Print(const std::string& what, const ViewFigures& v) {
  const BoundaryFigures& f = v.f;
  std::printf(
      "%-36s IoU %.4f  corner%s %5.2f px (%.2f%% diag)  real-off-edge %5.2f (max %5.2f) px  "
      "edge-recall %.3f  not real %d%s  top %s (%d votes, %.2f) %s\n",
      what.c_str(), f.iou, f.corner_hidden ? "(hidden)" : "", f.worst_corner_px,
      100 * f.WorstCornerFraction(), f.real_off_edge_px, f.real_off_edge_max_px, f.edge_recall,
      f.sides_not_real, f.page_cut ? " (cut)" : "", v.orientation_method.c_str(), v.votes,
      v.confidence, f.corners_in_order ? "ok" : "differs");
}

class BoundaryOnDataSet : public ::testing::TestWithParam<fs::path> {};

// All checks on the most frontal view; the other views are measured and
// printed (oblique views have folds that kink the outline as sharply as a
// corner turns, and shaded paper that looks like the table).
TEST_P(BoundaryOnDataSet, EveryViewMatchesTheTruth) {
  auto gt = LoadGroundTruth(GetParam());
  ASSERT_TRUE(gt);
  const int frontal = MostFrontalView(*gt);
  int text_orientations = 0, right_orientations = 0, all_good = 0;
  double mean_iou = 0;
  for (size_t v = 0; v < gt->cameras.views.size(); ++v) {
    const PinholeCamera& cam = gt->cameras.views[v];
    const cv::Mat image = ReadView(*gt, cam);
    ASSERT_FALSE(image.empty()) << cam.image;
    const BoundaryResult r = boundary::SegmentBoundary(image, {});
    const ViewFigures f = Measure(*gt, cam, r);
    const std::string what =
        DataSetName(GetParam()) + "/" + cam.image + (int(v) == frontal ? " (frontal)" : "");
    Print(what, f);
    MaybeWriteDebug(*gt, cam, image, r, what);
    if (int(v) == frontal) ExpectGood(f, what);
    all_good += f.f.AllHold();
    mean_iou += f.f.iou / gt->cameras.views.size();
    text_orientations += f.orientation_method == "text";
    right_orientations += f.orientation_method == "text" && f.f.corners_in_order;
  }
  std::printf(
      "%s: %d of %zu views pass every check; mean IoU %.4f; orientation read from "
      "text in %d views, right in %d\n",
      DataSetName(GetParam()).c_str(), all_good, gt->cameras.views.size(), mean_iou,
      text_orientations, right_orientations);
}

// Crops of the most frontal view that cut the page: off its bottom, off one
// of its corners, and off its top and bottom at once.
TEST_P(BoundaryOnDataSet, CutOffPagesKeepTheirRealSides) {
  auto gt = LoadGroundTruth(GetParam());
  ASSERT_TRUE(gt);
  const PinholeCamera& cam = gt->cameras.views[MostFrontalView(*gt)];
  for (const auto& c : TrueCorners(*gt, cam))
    if (c.x() < 0 || c.y() < 0 || c.x() > cam.width - 1 || c.y() > cam.height - 1)
      GTEST_SKIP() << "the page is cut off already (checked in EveryViewMatchesTheTruth)";
  const cv::Mat image = ReadView(*gt, cam);
  ASSERT_FALSE(image.empty());
  const cv::Rect page = cv::boundingRect(TruePageMask(*gt, cam));
  const std::vector<std::pair<std::string, cv::Rect>> crops = {
      {"bottom", cv::Rect(0, 0, cam.width, page.y + int(0.7 * page.height))},
      {"corner", cv::Rect(page.x + int(0.25 * page.width), page.y + int(0.2 * page.height),
                          cam.width - page.x - int(0.25 * page.width),
                          cam.height - page.y - int(0.2 * page.height))},
      {"two-sides",
       cv::Rect(0, page.y + int(0.15 * page.height), cam.width, int(0.7 * page.height))},
  };
  for (const auto& [name, rect] : crops) {
    const PinholeCamera crop_cam = CropCamera(cam, rect);
    const BoundaryResult r = boundary::SegmentBoundary(image(rect).clone(), {});
    const ViewFigures f = Measure(*gt, crop_cam, r);
    const std::string what = DataSetName(GetParam()) + "/" + cam.image + " crop " + name;
    Print(what, f);
    MaybeWriteDebug(*gt, crop_cam, image(rect), r, what);
    // Corners are printed, not asserted: a crop can leave a fold's kink as
    // the sharpest turn near the border.
    EXPECT_TRUE(f.f.page_cut) << what;
    ExpectGood(f, what, /*check_corners=*/false);
  }
}

std::string SetName(const ::testing::TestParamInfo<fs::path>& info) {
  std::string s = DataSetName(info.param);
  for (char& c : s)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  return s;
}

INSTANTIATE_TEST_SUITE_P(AllSets, BoundaryOnDataSet, ::testing::ValuesIn(DataSetsWithTruth()),
                         SetName);
GTEST_ALLOW_UNINSTANTIATED_PARAMETERIZED_TEST(BoundaryOnDataSet);

}  // namespace
}  // namespace docunfold::testing
