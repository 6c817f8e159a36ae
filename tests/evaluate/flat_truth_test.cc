// LinesFromFlatScan on a drawn till roll (twice as long as wide): a
// receipt's row (item, a wide blank gap, price) is one true line, but not
// across a vertical rule; two rows stay two lines. On a page of ordinary
// proportions a row's pieces stay apart, as synth's tables record cells.
#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "stages/evaluate/ground_truth.h"
#include "tests/support/test_support.h"

namespace docunfold::testing {
namespace {

std::vector<evaluate::TrueLine> TextLinesNear(const std::vector<evaluate::TrueLine>& lines,
                                              double y) {
  std::vector<evaluate::TrueLine> out;
  for (const auto& l : lines)
    if (l.kind == "text" && std::abs(l.points.front().y() - y) < 6) out.push_back(l);
  return out;
}

TEST(LinesFromFlatScan, ARowIsOneLineAcrossItsGapButNotAcrossARule) {
  TempDir dir;
  fs::create_directories(dir / "ground_truth");
  cv::Mat3b page(1700, 800, cv::Vec3b(255, 255, 255));
  const cv::Scalar ink(0, 0, 0);
  // A receipt row: item at the left, price at the right, 500 px apart.
  cv::putText(page, "Butter", {40, 100}, cv::FONT_HERSHEY_SIMPLEX, 1.0, ink, 2);
  cv::putText(page, "5.54", {640, 100}, cv::FONT_HERSHEY_SIMPLEX, 1.0, ink, 2);
  // The next row, 40 px lower.
  cv::putText(page, "Bread", {40, 140}, cv::FONT_HERSHEY_SIMPLEX, 1.0, ink, 2);
  cv::putText(page, "2.10", {640, 140}, cv::FONT_HERSHEY_SIMPLEX, 1.0, ink, 2);
  // A table row whose cells a column rule divides.
  cv::putText(page, "Cell", {40, 400}, cv::FONT_HERSHEY_SIMPLEX, 1.0, ink, 2);
  cv::putText(page, "Value", {600, 400}, cv::FONT_HERSHEY_SIMPLEX, 1.0, ink, 2);
  cv::line(page, {400, 300}, {400, 500}, ink, 2);
  ASSERT_TRUE(cv::imwrite((dir / "ground_truth" / "flat.png").string(), page));
  evaluate::GroundTruth gt;
  gt.root = dir.path();
  const std::vector<evaluate::TrueLine> lines = evaluate::LinesFromFlatScan(gt);

  const auto receipt_row = TextLinesNear(lines, 100);
  ASSERT_EQ(receipt_row.size(), 1u);
  EXPECT_LT(receipt_row[0].points.front().x(), 45);
  EXPECT_GT(receipt_row[0].points.back().x(), 690);
  EXPECT_EQ(TextLinesNear(lines, 140).size(), 1u) << "the next row is a line of its own";
  EXPECT_EQ(TextLinesNear(lines, 400).size(), 2u) << "a column rule divides the cells";

  // The same rows on a page of ordinary proportions: cells, not rows.
  ASSERT_TRUE(cv::imwrite((dir / "ground_truth" / "flat.png").string(),
                          page(cv::Rect(0, 0, 800, 600)).clone()));
  const auto cells = evaluate::LinesFromFlatScan(gt);
  EXPECT_EQ(TextLinesNear(cells, 100).size(), 2u);
}

}  // namespace
}  // namespace docunfold::testing
