// CreaseEvidence and CreaseFairWeights on drawn pages: a step in the paper's
// shading is a crease, a ramp (a curl) and printed strokes are not; only the
// fairness triplets that cross the step are spared.
#include "stages/optimize/crease_evidence.h"

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/imgproc.hpp>

#include "common/isometry/isometry.h"
#include "tests/optimize/flat_sheet.h"

namespace docunfold::optimize {
namespace {

constexpr int kSize = 800;

double StepAt(const cv::Mat2f& evidence, int x, int y) {
  const cv::Vec2f e = evidence(y, x);
  return std::hypot(e[0], e[1]);
}

double MaxStep(const cv::Mat2f& evidence, const cv::Rect& area) {
  double best = 0;
  for (int y = area.y; y < area.y + area.height; ++y)
    for (int x = area.x; x < area.x + area.width; ++x)
      best = std::max(best, StepAt(evidence, x, y));
  return best;
}

// Upper half: two panels, 200 left of x = 400 and 140 right of it. Lower
// half: the same change as a ramp over 600 pixels. Both printed with rows of
// dark strokes 3 pixels wide.
cv::Mat3b DrawnPage() {
  cv::Mat1b gray(kSize, kSize);
  for (int y = 0; y < kSize; ++y)
    for (int x = 0; x < kSize; ++x) {
      const double ramp = std::clamp((x - 100) / 600.0, 0.0, 1.0);
      gray(y, x) = y < 400 ? (x < 400 ? 200 : 140) : uchar(std::lround(200 - 60 * ramp));
    }
  for (int y = 130; y < 700; y += 40)
    for (int x = 120; x < 680; x += 12) cv::line(gray, {x, y}, {x + 2, y - 9}, 30, 3);
  cv::Mat3b page;
  cv::cvtColor(gray, page, cv::COLOR_GRAY2BGR);
  return page;
}

TEST(CreaseEvidence, AStepIsACreaseARampAndPrintAreNot) {
  cv::Mat1b page = cv::Mat1b::zeros(kSize, kSize);
  page(cv::Rect(50, 50, 700, 700)).setTo(255);
  const cv::Mat2f evidence = CreaseEvidence(DrawnPage(), page, CreaseOptions{}).step;
  ASSERT_EQ(evidence.size(), cv::Size(kSize, kSize));
  // log(201 / 141) = 0.35 over a σ = 2 edge: about 0.05 per pixel, across x.
  const double step = MaxStep(evidence, {395, 200, 10, 1});
  EXPECT_GT(step, 0.03);
  const cv::Vec2f across = evidence(150, 400);
  EXPECT_GT(std::abs(across[0]), 0.03);
  EXPECT_LT(std::abs(across[1]), 0.1 * std::abs(across[0]));
  // The ramp, the print away from the step and the page's outline: nothing.
  EXPECT_LT(MaxStep(evidence, {150, 450, 500, 250}), 0.05 * step);
  EXPECT_LT(MaxStep(evidence, {100, 100, 250, 250}), 0.05 * step);
  EXPECT_EQ(StepAt(evidence, 55, 200), 0);
  EXPECT_EQ(StepAt(evidence, 20, 20), 0);
}

TEST(CreaseEvidence, OnlyTripletsAcrossTheStepAreSpared) {
  // The 1 x 1.5 sheet at z = 4 seen square-on: x in [-0.5, 0.5] spans the
  // middle quarter of the photo's width. The panels meet at x = 0.125,
  // between vertex columns 2 and 3. The same in a photo four times as large,
  // read at 1600 pixels.
  const MeshPair sheet = FlatSheetAtDepthFour();
  for (const int factor : {1, 4}) {
    const int size = factor * kSize;
    PinholeCamera camera;
    camera.width = camera.height = size;
    camera.K << size, 0, size / 2, 0, size, size / 2, 0, 0, 1;
    const int edge = size / 2 + size / 32;  // x = 0.125
    cv::Mat3b photo(size, size, cv::Vec3b(200, 200, 200));
    photo(cv::Rect(edge, 0, size - edge, size)).setTo(cv::Vec3b(140, 140, 140));
    const cv::Mat1b page(size, size, uchar(255));
    CreaseOptions options;
    options.step = 0.0025;
    const CreaseMap evidence = CreaseEvidence(photo, page, options);
    EXPECT_DOUBLE_EQ(evidence.scale, factor == 1 ? 1.0 : 0.5);
    int spared = 0;
    const std::vector<double> weights =
        CreaseFairWeights(sheet, camera, evidence, options, &spared);
    const auto triplets = isometry::FairTriplets(sheet.grid);
    ASSERT_EQ(weights.size(), triplets.size());
    for (size_t t = 0; t < triplets.size(); ++t) {
      const int first = triplets[t][0] % sheet.grid.nx, last = triplets[t][2] % sheet.grid.nx;
      const bool along_row = first != last;
      // Row triplets spanning columns 1..3 or 2..4 cross the step.
      if (along_row && last >= 3 && first <= 2) {
        EXPECT_LE(weights[t], 1.5 * options.min_weight) << factor << " " << t;
      } else {
        EXPECT_GT(weights[t], 0.99) << factor << " " << t;
      }
    }
    EXPECT_EQ(spared, 2 * sheet.grid.ny);
    // Off: every weight 1.
    options.step = 0;
    for (const double w : CreaseFairWeights(sheet, camera, evidence, options)) EXPECT_EQ(w, 1);
  }
}

}  // namespace
}  // namespace docunfold::optimize
