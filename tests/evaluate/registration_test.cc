// The affine registration of a result to its ground truth on pages whose
// misplacement is known.
#include "stages/evaluate/registration.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "stages/evaluate/image_metrics.h"

namespace docunfold::evaluate {
namespace {

// A printed page at the evaluation size: rows of dark words of random
// lengths on white paper, a little soft as a scan is.
cv::Mat1b TextPage(cv::Size size, int seed = 3) {
  cv::RNG rng(seed);
  cv::Mat1b page(size, uchar(240));
  for (int y = 40; y + 12 < size.height - 40; y += 22)
    for (int x = 40; x < size.width - 60;) {
      const int w = rng.uniform(10, 60);
      cv::rectangle(page, cv::Rect(x, y, std::min(w, size.width - 40 - x), 11),
                    cv::Scalar(rng.uniform(20, 70)), cv::FILLED);
      x += w + rng.uniform(6, 14);
    }
  cv::GaussianBlur(page, page, cv::Size(3, 3), 0.8);
  return page;
}

// The page as a result whose crop stops `short_fraction` of the height above
// the page's bottom: truth rows [0, (1 - f) H] stretched over the whole image.
cv::Mat1b CroppedShort(const cv::Mat1b& truth, double short_fraction) {
  const cv::Matx23d result_from_truth(1, 0, 0, 0, 1 / (1 - short_fraction), 0);
  cv::Mat1b out;
  cv::warpAffine(truth, out, cv::Mat(result_from_truth), truth.size(), cv::INTER_LINEAR,
                 cv::BORDER_REPLICATE);
  return out;
}

TEST(RegisterAffine, AnIdenticalResultNeedsNoMap) {
  const cv::Mat1b page = TextPage({480, 680});
  const auto reg = RegisterAffine(page, page, HalfSizeFlow(page, page));
  ASSERT_TRUE(reg.has_value());
  const cv::Matx23d& a = reg->result_from_truth;
  EXPECT_NEAR(a(0, 0), 1, 1e-3);
  EXPECT_NEAR(a(1, 1), 1, 1e-3);
  EXPECT_NEAR(a(0, 2), 0, 0.3);
  EXPECT_NEAR(a(1, 2), 0, 0.3);
  EXPECT_GT(reg->ms_ssim, 0.99);
}

TEST(RegisterAffine, ACropShortAtTheBottomIsOneAffineMapAway) {
  // 1 % of the page cut off at the bottom: every row lands lower by a growing
  // amount, 6.8 px at the bottom of 680, which MS-SSIM counts heavily.
  const cv::Mat1b page = TextPage({480, 680});
  const cv::Mat1b result = CroppedShort(page, 0.01);
  const double plain = MsSsim(page, result).value;
  const auto reg = RegisterAffine(page, result, HalfSizeFlow(page, result));
  ASSERT_TRUE(reg.has_value());
  const cv::Matx23d& a = reg->result_from_truth;
  EXPECT_NEAR(a(1, 1), 1 / 0.99, 1.5e-3);  // rows stretched by 1 %
  EXPECT_NEAR(a(0, 0), 1, 1.5e-3);
  EXPECT_NEAR(a(0, 1), 0, 1.5e-3);
  EXPECT_NEAR(a(1, 0), 0, 1.5e-3);
  EXPECT_LT(reg->residual_px, 0.5);
  EXPECT_LT(plain, 0.9);
  EXPECT_GT(reg->ms_ssim, 0.97);
  EXPECT_NE(reg->fit, "identity");
}

TEST(RegisterAffine, LeavesALocalWaveInTheLoss) {
  // Rows displaced by a wave of 4 px amplitude and 1.5 periods over the page:
  // no affine map undoes it, and the registered figure must not pretend to.
  const cv::Mat1b page = TextPage({480, 680});
  cv::Mat1f map_x(page.size()), map_y(page.size());
  for (int r = 0; r < page.rows; ++r)
    for (int c = 0; c < page.cols; ++c) {
      map_x(r, c) = float(c);
      map_y(r, c) = float(r + 4 * std::sin(2 * M_PI * 1.5 * c / page.cols));
    }
  cv::Mat1b result;
  cv::remap(page, result, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  const double plain = MsSsim(page, result).value;
  const auto reg = RegisterAffine(page, result, HalfSizeFlow(page, result));
  ASSERT_TRUE(reg.has_value());
  EXPECT_LT(reg->ms_ssim, plain + 0.05);
  EXPECT_LT(reg->ms_ssim, 0.9);
}

TEST(RegisterAffine, NeverScoresBelowTheResultAsItIs) {
  // A page shown as two halves moved apart, as across a fold M got wrong:
  // the top 55 % in place, the rest 9 px lower and stretched. No single map
  // fits both; whichever is chosen, the registered score is the best of the
  // maps tried and not below the plain one.
  const cv::Mat1b page = TextPage({480, 680}, 7);
  cv::Mat1f map_x(page.size()), map_y(page.size());
  const float split = 0.55f * float(page.rows);
  for (int r = 0; r < page.rows; ++r)
    for (int c = 0; c < page.cols; ++c) {
      map_x(r, c) = float(c);
      map_y(r, c) = r < split ? float(r) : split + (float(r) - split - 9) / 1.04f;
    }
  cv::Mat1b result;
  cv::remap(page, result, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  const double plain = MsSsim(page, result).value;
  const auto reg = RegisterAffine(page, result, HalfSizeFlow(page, result));
  ASSERT_TRUE(reg.has_value());
  ASSERT_GE(reg->candidates.size(), 3u);
  EXPECT_EQ(reg->candidates.front().fit, "ransac");
  EXPECT_EQ(reg->candidates[1].fit, "least-squares");
  EXPECT_EQ(reg->candidates.back().fit, "identity");
  EXPECT_NEAR(reg->candidates.back().ms_ssim, plain, 1e-9);
  for (const AffineCandidate& c : reg->candidates) EXPECT_GE(reg->ms_ssim, c.ms_ssim);
  EXPECT_GE(reg->ms_ssim, plain);
}

TEST(RegisterAffine, FindsTheMapOfEachOfThreeBands) {
  // Three bands of the page each moved its own way (as a page creased twice
  // that M got wrong twice), no two of them one affine map: one fit and one
  // over what it left out cannot find all three maps; fits peeled off in turn
  // do.
  const cv::Mat1b page = TextPage({480, 680}, 11);
  const std::array<float, 3> ends = {0.4f * page.rows, 0.7f * page.rows, float(page.rows)};
  // Where each band shows in the result, relative to the truth (pixels).
  const std::array<cv::Point2f, 3> shifts = {cv::Point2f(0, 0), cv::Point2f(0, 8),
                                             cv::Point2f(14, -5)};
  cv::Mat1f map_x(page.size()), map_y(page.size());
  for (int r = 0; r < page.rows; ++r)
    for (int c = 0; c < page.cols; ++c) {
      const size_t band = r < ends[0] ? 0 : r < ends[1] ? 1 : 2;
      map_x(r, c) = float(c) - shifts[band].x;
      map_y(r, c) = float(r) - shifts[band].y;
    }
  cv::Mat1b result;
  cv::remap(page, result, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  const auto reg = RegisterAffine(page, result, HalfSizeFlow(page, result));
  ASSERT_TRUE(reg.has_value());
  for (size_t band = 0; band < 3; ++band) {
    // The band's middle and where it shows, in pixels.
    const cv::Point2d middle(0.5 * page.cols, 0.5 * ((band ? ends[band - 1] : 0) + ends[band]));
    const cv::Point2d shown = middle + cv::Point2d(shifts[band]);
    bool found = false;
    for (const AffineCandidate& c : reg->candidates) {
      const cv::Matx23d& a = c.result_from_truth;
      const cv::Point2d q(a(0, 0) * middle.x + a(0, 1) * middle.y + a(0, 2),
                          a(1, 0) * middle.x + a(1, 1) * middle.y + a(1, 2));
      found |= cv::norm(q - shown) < 1.0;
    }
    EXPECT_TRUE(found) << "no map of band " << band;
  }
}

TEST(RegisterAffine, ABlankPageHasNothingToRegister) {
  const cv::Mat1b blank(680, 480, uchar(240));
  EXPECT_FALSE(RegisterAffine(blank, blank, HalfSizeFlow(blank, blank)).has_value());
}

}  // namespace
}  // namespace docunfold::evaluate
