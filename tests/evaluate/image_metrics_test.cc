// MS-SSIM, grey conversion, evaluation size and the flow metrics on images
// whose answer is known.
#include "stages/evaluate/image_metrics.h"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

namespace docunfold::evaluate {
namespace {

// Smooth random texture with structure at several scales (what DeepFlow and
// SSIM need to see anything), deterministic.
cv::Mat1b Texture(cv::Size size, int seed = 1) {
  cv::RNG rng(seed);
  cv::Mat1f acc(size, 0.f);
  for (int sigma : {2, 5, 12}) {
    cv::Mat1f noise(size);
    rng.fill(noise, cv::RNG::NORMAL, 0, 1);
    cv::GaussianBlur(noise, noise, cv::Size(), sigma);
    cv::normalize(noise, noise, -1, 1, cv::NORM_MINMAX);
    acc += noise;
  }
  cv::Mat1b out;
  cv::normalize(acc, out, 20, 235, cv::NORM_MINMAX, CV_8U);
  return out;
}

// `image` moved right by dx and down by dy, borders replicated.
cv::Mat1b Shift(const cv::Mat1b& image, double dx, double dy) {
  cv::Mat m = (cv::Mat_<double>(2, 3) << 1, 0, dx, 0, 1, dy);
  cv::Mat1b out;
  cv::warpAffine(image, out, m, image.size(), cv::INTER_CUBIC, cv::BORDER_REPLICATE);
  return out;
}

TEST(EvaluationSize, MatchesMatlabImresizeCeil) {
  EXPECT_EQ(EvaluationSize({1240, 1753}), cv::Size(651, 920));
  EXPECT_EQ(EvaluationSize({472, 1181}), cv::Size(490, 1224));  // upscaled
  EXPECT_EQ(EvaluationSize({880, 680}), cv::Size(880, 680));    // exactly the area
  EXPECT_EQ(EvaluationSize({1760, 1360}), cv::Size(880, 680));  // exactly half
}

TEST(MatlabGrey, UsesRgb2grayWeightsAndRounds) {
  cv::Mat3b bgr(1, 4);
  bgr(0, 0) = {0, 0, 255};   // red
  bgr(0, 1) = {0, 255, 0};   // green
  bgr(0, 2) = {255, 0, 0};   // blue
  bgr(0, 3) = {77, 77, 77};  // grey stays grey
  const cv::Mat1b g = MatlabGrey(bgr);
  EXPECT_EQ(g(0, 0), 76);   // 0.298936 * 255 = 76.23
  EXPECT_EQ(g(0, 1), 150);  // 0.587043 * 255 = 149.70
  EXPECT_EQ(g(0, 2), 29);   // 0.114021 * 255 = 29.08
  EXPECT_EQ(g(0, 3), 77);
  cv::Mat4b bgra(1, 1, cv::Vec4b(0, 0, 255, 0));  // alpha is ignored
  EXPECT_EQ(MatlabGrey(bgra)(0, 0), 76);
}

TEST(MsSsim, IdenticalImagesGiveExactlyOne) {
  const cv::Mat1b a = Texture({320, 240});
  const MsSsimResult r = MsSsim(a, a);
  EXPECT_NEAR(r.value, 1.0, 1e-12);
  for (double s : r.scales) EXPECT_NEAR(s, 1.0, 1e-12);
}

TEST(MsSsim, FallsWithDistortionAndIsSymmetric) {
  const cv::Mat1b a = Texture({320, 240});
  const double slight = MsSsim(a, Shift(a, 1, 0)).value;
  const double strong = MsSsim(a, Shift(a, 8, 5)).value;
  const double unrelated = MsSsim(a, Texture({320, 240}, 7)).value;
  EXPECT_LT(slight, 1.0);
  EXPECT_LT(strong, slight);
  EXPECT_LT(unrelated, strong);
  EXPECT_LT(unrelated, 0.3);
  EXPECT_NEAR(MsSsim(a, Shift(a, 8, 5)).value, MsSsim(Shift(a, 8, 5), a).value, 1e-12);
}

TEST(Ssim, ConstantImagesDifferingInBrightness) {
  // Only the luminance term differs: (2 * 100 * 150 + C1) / (100^2 + 150^2 + C1).
  const cv::Mat1b a(64, 64, uint8_t(100)), b(64, 64, uint8_t(150));
  const double c1 = 6.5025;
  EXPECT_NEAR(Ssim(a, b), (2 * 100.0 * 150 + c1) / (100.0 * 100 + 150.0 * 150 + c1), 1e-9);
}

TEST(FlowStatistics, ConstantFlowHasLengthAndNoLineDistortion) {
  const cv::Mat2f flow(50, 80, cv::Vec2f(3, 4));
  const FlowResult r = FlowStatistics(flow);
  EXPECT_NEAR(r.ld, 5.0, 1e-6);
  EXPECT_NEAR(r.li_d, 0.0, 1e-6);
}

TEST(FlowStatistics, LineDistortionMeasuresBentRows) {
  // v_y alternating +-1 along each row: std along rows = sqrt(n/(n-1)), v_x = 0.
  cv::Mat2f flow(10, 100);
  for (int r = 0; r < flow.rows; ++r)
    for (int c = 0; c < flow.cols; ++c) flow(r, c) = cv::Vec2f(0, c % 2 ? 1.f : -1.f);
  const FlowResult f = FlowStatistics(flow);
  EXPECT_NEAR(f.ld, 1.0, 1e-9);
  EXPECT_NEAR(f.li_d, 0.5 * std::sqrt(100.0 / 99.0), 1e-6);
}

TEST(DeepFlow, IdenticalImagesGiveZeroFlow) {
  const cv::Mat1b a = Texture({200, 160});
  const FlowResult r = FlowStatistics(DeepFlow(a, a));
  EXPECT_LT(r.ld, 0.05);
  EXPECT_LT(r.li_d, 0.05);
}

TEST(DeepFlow, ThreePixelShiftGivesLdThree) {
  // The result is the ground truth moved 3 pixels right: every ground-truth
  // pixel is found 3 pixels to the right, flow (+3, 0).
  const cv::Mat1b a = Texture({200, 160});
  const cv::Mat2f flow = DeepFlow(a, Shift(a, 3, 0));
  const FlowResult r = FlowStatistics(flow);
  EXPECT_NEAR(r.ld, 3.0, 0.25);
  EXPECT_NEAR(cv::mean(flow)[0], 3.0, 0.25);
  EXPECT_NEAR(cv::mean(flow)[1], 0.0, 0.1);
  EXPECT_LT(r.li_d, 0.3);  // a rigid shift bends no line
}

TEST(DenseFlowMetrics, WorksAtHalfTheEvaluationSize) {
  // 6 pixels at the evaluation size are 3 at the flow size.
  const cv::Mat1b a = Texture({320, 240});
  const FlowResult r = DenseFlowMetrics(a, Shift(a, 0, 6));
  EXPECT_EQ(r.size, cv::Size(160, 120));
  EXPECT_NEAR(r.ld, 3.0, 0.3);
}

TEST(PrepareEvaluationPair, ResizesBothToTheGroundTruthEvaluationSize) {
  cv::Mat3b gt(1753, 1240, cv::Vec3b(200, 200, 200)), result(500, 300, cv::Vec3b(10, 20, 30));
  const EvaluationPair p = PrepareEvaluationPair(gt, result);
  EXPECT_EQ(p.ground_truth.size(), cv::Size(651, 920));
  EXPECT_EQ(p.result.size(), cv::Size(651, 920));
}

}  // namespace
}  // namespace docunfold::evaluate
